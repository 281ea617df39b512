#!/usr/bin/env -S /usr/bin/python3
"""Error against cost from a sweep's results.csv: one series per method, the Pareto front, failed runs.

usage: /usr/bin/python3 tools/chart.py RESULTS.csv --x COST --y ERROR [--series KEY[,KEY...]]
                                        [--annotate KEY] [--where KEY=VALUE ...] [--title TEXT] --out PREFIX

  --x        cost column: wall_s, cpu_s, particle_steps, element_steps, coupling_iterations, ...
  --y        error column, e.g. tip.l2_rel (LABEL.QUANTITY of a [[metric]])
  --series   columns whose values together name a method (one line per method); default: the sweep's
             [chart] series (from sweep.json next to the CSV), else its grid axes whose values are not
             numbers
  --annotate a column printed next to each point (e.g. the resolution)
  --where    keep only rows with KEY = VALUE (repeatable)
Writes PREFIX.png and PREFIX.svg; prints the Pareto front.

Log-log axes. Each method: a line through its completed runs sorted by cost, with the least-squares slope
of log(error) against log(cost) in the legend. Pareto front (over all methods): the runs that no other run
beats on both cost and error (lower or equal in both, lower in one), ringed and joined by a staircase.
Runs that did not complete are drawn as crosses along the top edge, at their cost (left edge if they have
none), each labelled with its status; so are completed runs without a value (a metric that failed, or an
infinite or NaN one) and with a negative one (not an error column: a log axis cannot show it); completed
runs with an error of exactly 0 (an exact result) and the reference run as triangles along the bottom edge.
Nothing is dropped silently: the title counts them.
"""
import argparse
import json
import math
import os
import sys
import textwrap

import matplotlib

matplotlib.use("Agg")  # files only
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.transforms as mtransforms  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sweeplib import results  # noqa: E402

MARKERS = "osD^vP*Xh<>p"


class ChartError(ValueError):
    pass


def pareto_front(points):
    """Indices of the non-dominated (cost, error) points, sorted by cost: a point is dominated when
    another is no worse in both and better in one."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], math.inf
    for i in order:
        if points[i][1] < best:
            # equal cost, higher error: dominated by the one before (sorted by error within equal cost)
            if front and points[front[-1]][0] == points[i][0]:
                continue
            front.append(i)
            best = points[i][1]
    return front


def loglog_slope(xs, ys):
    if len(xs) < 2:
        return None
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    sxx = sum((a - mx) ** 2 for a in lx)
    if sxx == 0:
        return None
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sxx


def load_description(csv_path):
    path = os.path.join(os.path.dirname(os.path.abspath(csv_path)), "sweep.json")
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


def axis_label(col, desc):
    if col in results.COST_LABELS:
        return results.COST_LABELS[col]
    info = (desc.get("columns") or {}).get(col)
    if info:
        unit = info.get("unit") or ""
        unit = "-" if unit in ("", "-") else unit
        # "as the quantity" (value, abs_error of a metric that measures whatever it is given) is no unit to print.
        unit = "" if unit.startswith("as the ") else f" [{unit}]"
        return textwrap.fill(f"{col}: {info['meaning']}{unit}", 70)
    return col


def series_label(row, keys):
    if not keys:
        return "all runs"
    short = {}
    for k in keys:
        s = k.split(".")[-1]
        short[k] = k if list(x.split(".")[-1] for x in keys).count(s) > 1 else s
    return ", ".join(f"{short[k]}={row.get(k, '')}" for k in keys)


def short_number(text):
    """An annotation: a number to 4 significant digits (0.0013333333333333333 as 0.001333), other text as is."""
    try:
        return f"{float(text):.4g}"
    except ValueError:
        return text


def make_chart(rows, x, y, series, prefix, title=None, annotate=None, desc=None):
    """Draws the chart of `rows` (dicts of CSV text) to PREFIX.png and PREFIX.svg; returns a summary."""
    desc = desc or {}
    if not rows:
        raise ChartError("no rows")
    have = set(rows[0])
    for col in [x, y] + list(series) + ([annotate] if annotate else []):
        if col not in have:
            raise ChartError(f"no column {col!r}; columns: {', '.join(rows[0])}")
    groups, failed, no_value, no_error, negative, not_applicable = {}, [], [], [], [], 0
    metric_label = y.split(".", 1)[0]
    for r in rows:
        label = series_label(r, series)
        cx, cy = results.number(r[x]), results.number(r[y])
        if r.get("status", "completed") != "completed":
            failed.append((label, cx, r))
        elif not (cx > 0 and math.isfinite(cx)):
            failed.append((label, cx, dict(r, status="no cost")))
        elif not str(r[y]).strip():
            # Completed with an empty cell: the metric failed when the notes say why; the reference run gets no
            # value from a metric against itself; a run the metric's `where` leaves out has nothing to draw.
            if any(n.startswith(metric_label + ": ") for n in str(r.get("notes") or "").split("; ")):
                no_value.append((label, cx, dict(r, status="no value")))
            elif r.get("run") and r.get("run") == desc.get("reference_run"):
                no_error.append((label, cx, r))
            else:
                not_applicable += 1
        elif not math.isfinite(cy):
            # results.cell writes an infinite value as "inf": no value to draw, not an exact result.
            no_value.append((label, cx, dict(r, status=f"no value ({r[y].strip()})")))
        elif cy < 0:
            # Errors are >= 0; a column that is not one (a signed error) has values a log axis cannot show.
            negative.append((label, cx, dict(r, status=f"negative ({cy:.3g})")))
        elif cy == 0:
            no_error.append((label, cx, r))
        else:
            groups.setdefault(label, []).append((cx, cy, r))

    fig, ax = plt.subplots(figsize=(9, 6))
    ax.set_xscale("log")
    ax.set_yscale("log")
    labels = sorted(set(groups) | {l for l, _, _ in failed + no_value + negative + no_error})
    colours = {l: f"C{i % 10}" for i, l in enumerate(labels)}
    markers = {l: MARKERS[i % len(MARKERS)] for i, l in enumerate(labels)}
    all_pts = []
    for label in labels:
        pts = sorted(groups.get(label, []), key=lambda p: p[0])
        if not pts:
            continue
        slope = loglog_slope([p[0] for p in pts], [p[1] for p in pts])
        text = label + (f" (slope {slope:.2f})" if slope is not None else "")
        ax.plot([p[0] for p in pts], [p[1] for p in pts], "-", marker=markers[label], color=colours[label],
                label=text, ms=6, lw=1.4, zorder=3)
        if annotate:
            for px, py, r in pts:
                ax.annotate(short_number(r.get(annotate, "")), (px, py), textcoords="offset points", xytext=(5, 4),
                            fontsize=7, color=colours[label])
        all_pts += [(p[0], p[1], label, p[2]) for p in pts]

    front = []
    if all_pts:
        idx = pareto_front([(p[0], p[1]) for p in all_pts])
        front = [all_pts[i] for i in idx]
        fx, fy = [p[0] for p in front], [p[1] for p in front]
        ax.step(fx, fy, where="post", color="k", lw=5, alpha=0.18, zorder=1, solid_capstyle="round")
        ax.plot(fx, fy, "o", ms=13, mfc="none", mec="k", mew=1.3, zorder=4,
                label=f"Pareto front ({len(front)} of {len(all_pts)} runs)")

    # Axis limits from everything that has a cost, so crosses of failed runs fall inside.
    xs = [p[0] for p in all_pts] + [c for _, c, _ in failed + no_value + negative + no_error
                                    if c > 0 and math.isfinite(c)]
    ys = [p[1] for p in all_pts]
    if xs:
        lo, hi = min(xs), max(xs)
        ax.set_xlim(lo / 1.6, hi * 1.6) if lo < hi else ax.set_xlim(lo / 3, hi * 3)
    if ys:
        lo, hi = min(ys), max(ys)
        ax.set_ylim(lo / 3, hi * 6) if lo < hi else ax.set_ylim(lo / 10, hi * 10)
    ax.autoscale(False)
    edge = mtransforms.blended_transform_factory(ax.transData, ax.transAxes)
    xlo = ax.get_xlim()[0]

    def at_x(c):
        return c if c > 0 and math.isfinite(c) else xlo * 1.08

    crosses = failed + no_value + negative
    if crosses:
        for i, (label, c, r) in enumerate(crosses):
            ax.plot([at_x(c)], [0.965], "x", color=colours.get(label, "r"), ms=10, mew=2.2, transform=edge,
                    clip_on=False, zorder=5, label="did not complete, or no value" if i == 0 else None)
            if len(crosses) <= 24:
                ax.annotate(f"{r.get('status')}: {r.get('case') or label}", (at_x(c), 0.935), xycoords=edge, rotation=90,
                            fontsize=6.5, ha="center", va="top", color=colours.get(label, "r"))
        ax.axhspan(0.9, 1.0, transform=ax.transAxes, color="r", alpha=0.05, zorder=0)
    if no_error:
        for i, (label, c, r) in enumerate(no_error):
            ax.plot([at_x(c)], [0.03], "v", color=colours.get(label, "k"), ms=8, transform=edge, clip_on=False,
                    zorder=5, label="completed, error 0 (exact) or the reference run" if i == 0 else None)
    ax.set_xlabel(axis_label(x, desc))
    ax.set_ylabel(axis_label(y, desc))
    ttl = title or desc.get("title") or "error against cost"
    # Completed runs without a value on the cost axis (a structure alone has no particle_steps) are not failures.
    no_cost = sum(1 for _, _, r in failed if r.get("status") == "no cost")
    counts = f"{len(all_pts)} plotted, {len(failed) - no_cost} did not complete, " \
             + (f"{no_cost} completed without a {x}, " if no_cost else "") + f"{len(no_value)} no value, " \
             f"{len(no_error)} without error" + (f", {len(negative)} negative" if negative else "") \
             + (f", {not_applicable} not applicable" if not_applicable else "")
    ax.set_title(f"{ttl}\n{y} against {x} ({counts})", fontsize=10)
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    fig.tight_layout()
    d = os.path.dirname(os.path.abspath(prefix))
    os.makedirs(d, exist_ok=True)
    fig.savefig(prefix + ".png", dpi=150)
    fig.savefig(prefix + ".svg")
    plt.close(fig)
    return {"plotted": len(all_pts), "series": len([l for l in labels if groups.get(l)]), "failed": len(failed) - no_cost,
            "no_cost": no_cost,
            "no_value": len(no_value), "no_error": len(no_error), "negative": len(negative),
            "not_applicable": not_applicable,
            "pareto": [(p[2], p[0], p[1], p[3].get("run", "")) for p in front]}


def default_series(rows, desc):
    """The sweep's [chart] series; else the grid axes whose values are not numbers (method names, bundle
    labels: numeric axes are the refinement along each line); else one series."""
    chart = desc.get("chart") or {}
    if chart.get("series"):
        return list(chart["series"])
    out = []
    for axis in desc.get("axes") or []:
        if not all(_is_number(v) for v in axis.get("values", [])):
            out.append(axis["name"])
    return [k for k in out if not rows or k in rows[0]]


def _is_number(text):
    try:
        float(text)
        return True
    except (TypeError, ValueError):
        return False


def filter_rows(rows, where):
    out = rows
    for w in where:
        k, _, v = w.partition("=")
        out = [r for r in out if k in r and (r[k] == v or results.number(r[k]) == results.number(v))]
    return out


def chart_file(csv_path, x, y, series, prefix, title=None, annotate=None, where=()):
    rows = filter_rows(results.read_csv(csv_path), where)
    desc = load_description(csv_path)
    if series is None:
        series = default_series(rows, desc)
    s = make_chart(rows, x, y, series, prefix, title, annotate, desc)
    return (f"{s['plotted']} runs in {s['series']} series, {s['failed']} did not complete, "
            + (f"{s['no_cost']} completed without a {x}, " if s['no_cost'] else "") + f"{s['no_value']} no value, "
            f"{s['no_error']} without error, " + (f"{s['negative']} negative, " if s['negative'] else "")
            + f"{s['not_applicable']} not applicable, Pareto front {len(s['pareto'])}")


def threshold_chart(rows, key, prefix, title=None, log=True, probes=None, bracket=None):
    """Bisection results, one line per target: every probe (passing: green dot, failing: red cross), the
    threshold (last passing value, large dot) and the first failing value (large cross) joined by a bar;
    targets without a bracket carry their note."""
    if not rows:
        raise ChartError("no rows")
    fig, ax = plt.subplots(figsize=(9, 0.55 * len(rows) + 2.0))
    names = [r["target"] or "scene" for r in rows]

    def num(v):
        return results.number(v) if isinstance(v, str) else (math.nan if v is None else float(v))

    for i, r in enumerate(rows):
        for p in (probes or {}).get(r["target"], []):
            v = num(p.get("value"))
            ok = p.get("passed") in (True, "true")
            ax.plot([v], [i], "o" if ok else "x", color="C2" if ok else "C3", ms=4, alpha=0.6,
                    label=None)
        t, f = num(r.get("threshold")), num(r.get("first_failing"))
        if math.isfinite(t):
            ax.plot([t, f], [i, i], "-", color="k", lw=3, alpha=0.35)
            ax.plot([t], [i], "o", color="C2", ms=10, label="last passing value" if i == 0 else None)
            ax.plot([f], [i], "X", color="C3", ms=10, label="first failing value" if i == 0 else None)
            ax.annotate(f"{t:.4g}", (t, i), textcoords="offset points", xytext=(0, 9), fontsize=7, ha="center")
        else:
            ax.annotate(str(r.get("note", "")), (0.01, i), xycoords=("axes fraction", "data"), fontsize=7,
                        va="center")
    ax.plot([], [], "o", color="C2", ms=4, alpha=0.6, label="probe: passes")
    ax.plot([], [], "x", color="C3", ms=4, alpha=0.6, label="probe: fails")
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(names, fontsize=8)
    ax.set_ylim(-0.7, len(rows) - 0.3)
    if log:
        ax.set_xscale("log")
    if bracket:
        lo, hi = bracket
        ax.set_xlim(lo / 1.3, hi * 1.3) if log else ax.set_xlim(lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo))
    ax.set_xlabel(key)
    ax.set_title(textwrap.fill(title or f"stability limit of {key}", 90), fontsize=10)
    ax.grid(True, axis="x", which="both", alpha=0.25)
    ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    fig.tight_layout()
    fig.savefig(prefix + ".png", dpi=150)
    fig.savefig(prefix + ".svg")
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="chart.py", usage=argparse.SUPPRESS, description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("--x", required=True)
    ap.add_argument("--y", required=True)
    ap.add_argument("--series", action="append")
    ap.add_argument("--annotate")
    ap.add_argument("--where", action="append", default=[])
    ap.add_argument("--title")
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    series = None
    if args.series is not None:
        series = [k for s in args.series for k in s.split(",") if k]
    rows = filter_rows(results.read_csv(args.csv), args.where)
    desc = load_description(args.csv)
    if series is None:
        series = default_series(rows, desc)
    try:
        s = make_chart(rows, args.x, args.y, series, args.out, args.title, args.annotate, desc)
    except ChartError as err:
        print(f"chart: {err}", file=sys.stderr)
        return 2
    print(f"wrote {args.out}.png and {args.out}.svg: {s['plotted']} runs in {s['series']} series, "
          f"{s['failed']} did not complete, " + (f"{s['no_cost']} completed without a {args.x}, " if s['no_cost'] else "")
          + f"{s['no_error']} without error")
    print(f"Pareto front ({args.x} -> {args.y}):")
    for label, cx, cy, run in s["pareto"]:
        print(f"  {cx:12.5g} {cy:12.5g}  {label}  {run}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
