"""Charts of docs/validation.md that tools/chart.py does not draw (quantities against a setting rather than
error against cost), from the results CSVs next to this file.
usage: /usr/bin/python3 docs/validation/plots.py   (rewrites compressibility.png, added_mass.png, pcisph.png,
       dam_break_curves.png)
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools"))
from metrics import read_reference_curve  # noqa: E402


def rows(name):
    """A CSV next to this file, without its '#' lines (the source notes some of them carry)."""
    with open(os.path.join(HERE, name)) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def save(fig, name):
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, name), dpi=90)
    plt.close(fig)


def compressibility():
    rs = rows("compressibility.csv")
    fig, axes = plt.subplots(1, 2, figsize=(9, 4), sharey=True)
    for ax, col, title, order in ((axes[0], "collapse.value", "collapse (t <= 0.19 s)", 2),
                                  (axes[1], "impact.value", "impact on the far wall (t >= 0.19 s)", 1)):
        for model, marker in (("standard", "o"), ("wcsph", "s")):
            pts = []
            for r in rs:
                if not r["case"].startswith(model) or r["status"] != "completed":
                    continue
                c = math.sqrt(num(r["fluid.pressure.k"])) if model == "standard" else num(r["fluid.pressure.c0"])
                pts.append((c, num(r[col])))
            pts.sort()
            label = "standard SPH (summation), c = sqrt(k)" if model == "standard" else "WCSPH (continuity), c = c0"
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], marker=marker, label=label)
        u = math.sqrt(2 * 9.81 * 0.2)
        cs = [5, 200]
        ax.loglog(cs, [(u / c) ** order for c in cs], "k--", lw=0.8,
                  label=f"(u/c)^{order}, u = sqrt(2 g H) = {u:.2f} m/s")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("sound speed c [m/s]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_ylabel("max over steps and particles of (rho - rho0)/rho0")
    fig.suptitle("dam break, dp = 5 mm: density error against sound speed", fontsize=11)
    save(fig, "compressibility.png")


def mass_ratio(r):
    """rho_s t / (rho_f L) of an added-mass run: plate 0.02 m thick and 0.2 m long under water."""
    return num(r["structure.material.rho"]) * 0.02 / (1000 * 0.2)


def added_mass():
    rs = rows("added_mass.csv")
    methods = []
    for r in rs:
        if r["method"] not in methods:
            methods.append(r["method"])
    fig, axes = plt.subplots(1, 2, figsize=(12, 5))
    markers = "osD^v<>ph*XP"
    assert len(methods) <= len(markers), "one marker per method"
    for m, mk in zip(methods, markers):
        # Line style by window and structure step: the thesis window sub-cycling the structure (solid),
        # multi-rate windows (dashed), one structure step per window (dash-dotted).
        style = "--" if "multi-rate" in m else "-." if " step" in m else "-"
        sel = sorted((r for r in rs if r["method"] == m), key=mass_ratio)
        ratio = [mass_ratio(r) for r in sel]
        ok = [r["status"] == "completed" for r in sel]
        dev = [num(r["mid.max_rel"]) for r in sel]
        it = [num(r["iterations.value"]) for r in sel]
        line, = axes[0].loglog([x for x, o in zip(ratio, ok) if o], [d for d, o in zip(dev, ok) if o],
                               marker=mk, ls=style, label=m)
        for x, o in zip(ratio, ok):
            if not o:
                axes[0].plot([x], [300], marker=mk, ms=8, mfc="none", color=line.get_color())
        axes[1].semilogx([x for x, o in zip(ratio, ok) if o], [i for i, o in zip(it, ok) if o], marker=mk, ls=style,
                         label=m)
    axes[0].annotate("runs that diverged", (8, 300), fontsize=7, textcoords="offset points", xytext=(0, 8))
    # The explicit scheme's failure point, sub-cycled structure and one structure step per window: between
    # its last stable ratio and the first unstable one (max |u - w| > |w| or a failed run), on both panels.
    for explicit, ls, y in (("serial-explicit", ":", 0.9), ("serial-explicit, one BE step", "-.", 0.7)):
        expl = sorted((r for r in rs if r["method"] == explicit), key=lambda r: -mass_ratio(r))
        last_ok = None
        for r in expl:
            x = mass_ratio(r)
            if r["status"] != "completed" or num(r["mid.max_rel"]) > 1.0:
                edge = math.sqrt(x * last_ok) if last_ok else x
                for ax in axes:
                    ax.axvline(edge, color="r", lw=1.0, ls=ls)
                axes[1].annotate(explicit + ":\nunstable beyond", (edge, y), xycoords=("data", "axes fraction"),
                                 fontsize=7, color="r", textcoords="offset points", xytext=(3, 0))
                break
            last_ok = x
    axes[0].axhline(1.0, color="k", lw=0.8, ls="--")
    axes[0].annotate("undamped overshoot of a sudden load", (8, 1.15), fontsize=7)
    axes[0].set_ylabel("max |u - w| / |w|, mid-span (top row: run diverged)")
    axes[1].set_ylabel("coupling iterations per window (mean)")
    for ax in axes:
        ax.set_xlabel("mass ratio rho_s t / (rho_f L)")
        ax.grid(True, which="both", alpha=0.3)
        ax.invert_xaxis()
    axes[1].legend(fontsize=6.5, loc="upper left")
    fig.suptitle("plate under water (E = 0.7 GPa): added-mass stability", fontsize=11)
    save(fig, "added_mass.png")


def pcisph():
    rs = rows("pcisph.csv")
    fig, axes = plt.subplots(1, 2, figsize=(9, 4))
    for cfl, mk in (("0.2", "o"), ("0.4", "s"), ("1", "D"), ("1.0", "D")):
        sel = sorted((r for r in rs if r["fluid.time.cfl"] == cfl), key=lambda r: num(r["fluid_particles"]))
        if not sel:
            continue
        n = [num(r["fluid_particles"]) for r in sel]
        ok = [r["status"] == "completed" for r in sel]
        ips = [num(r["iterations.value"]) / num(r["steps.value"]) for r in sel]
        de = [num(r["density.max"]) for r in sel]
        line, = axes[0].semilogx([a for a, o in zip(n, ok) if o], [b for b, o in zip(ips, ok) if o], marker=mk,
                                 label=f"cfl = {cfl}")
        axes[1].semilogx([a for a, o in zip(n, ok) if o], [b for b, o in zip(de, ok) if o], marker=mk,
                         label=f"cfl = {cfl}", color=line.get_color())
        for a, o, r in zip(n, ok, sel):
            if not o:
                axes[0].plot([a], [0], marker="x", ms=10, color=line.get_color())
                axes[1].plot([a], [0.3], marker="x", ms=10, color=line.get_color())
                axes[0].annotate("lost through the wall", (a, 0), fontsize=7, color=line.get_color(),
                                 textcoords="offset points", xytext=(-60, 6))
    axes[0].set_ylabel("PCISPH corrections per step (mean)")
    axes[1].set_ylabel("max (rho - rho0)/rho0 in the frames")
    axes[1].set_yscale("log")
    axes[1].axhline(0.01, color="k", lw=0.8, ls="--")
    axes[1].annotate("eta = 0.01", (900, 0.0108), fontsize=7)
    for ax in axes:
        ax.set_xlabel("fluid particles")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_ylim(bottom=0)
    fig.suptitle("dam break to t = 0.4 s, PCISPH (x: run failed)", fontsize=11)
    save(fig, "pcisph.png")


def dam_break_curves():
    rs = rows("dam_break_curves.csv")
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    panels = ((axes[0], "T", "Z", "martin_moyce_1952_front_n2_2.csv", "surge front Z = x / a",
               "T = t sqrt(2 g / a)", 2.6),
              (axes[1], "tau", "H", "martin_moyce_1952_height_n2_2.csv",
               "column height at the back wall H / (2 a)", "tau = t sqrt(g / a)", 2.6))
    colours = {"standard": "tab:blue", "WCSPH": "tab:orange", "PCISPH": "tab:green"}
    for ax, xc, yc, ref, title, xlabel, xmax in panels:
        for method, colour in colours.items():
            for slip, style in (("no_slip", "--"), ("free_slip", "-")):
                sel = [r for r in rs if r["method"] == method and r["slip"] == slip and num(r[xc]) <= xmax]
                ax.plot([num(r[xc]) for r in sel], [num(r[yc]) for r in sel], style, color=colour, lw=1.2,
                        label=f"{method}, {slip.replace('_', '-')}")
        x, y = read_reference_curve(os.path.join(ROOT, "tests", "fluid", "data", ref))
        ax.plot(x[x <= xmax], y[x <= xmax], "ko", ms=5, label="Martin & Moyce (1952)")
        ax.set_xlabel(xlabel)
        ax.set_title(title + ", dp = a/80")
        ax.grid(alpha=0.3)
    axes[1].legend(fontsize=7)
    save(fig, "dam_break_curves.png")


if __name__ == "__main__":
    compressibility()
    added_mass()
    pcisph()
    dam_break_curves()
