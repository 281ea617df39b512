#!/usr/bin/env -S /usr/bin/python3
"""Plots watchpoints.csv (time, name, x, y, dx, dy): the displacement of each named structure point.

usage: /usr/bin/python3 tools/plot_watchpoints.py RUN/watchpoints.csv [OUT.png] [--ref "NAME dx=FILE.csv" ...]

--ref overlays reference points (a CSV with '#' comment lines and two columns: t and the component,
e.g. scenarios/reference/antoci2007_gate_tip_dx.csv) on the named watchpoint's component.
"""
import os
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")  # files only; no display needed
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from metrics import MetricError, read_reference_curve, watchpoint_rows  # noqa: E402


def read_reference(path):
    """The reference's times and values, read as the sweeps' metrics read them (a header line is optional;
    reading the first data row as one had dropped it)."""
    try:
        t, v = read_reference_curve(path)
    except MetricError as err:
        sys.exit(f"plot_watchpoints: {err}")
    return list(t), list(v)


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--ref")]
    refs = [a.split("=", 1)[1] for a in sys.argv[1:] if a.startswith("--ref=")]
    refs += [sys.argv[i + 1] for i, a in enumerate(sys.argv[:-1]) if a == "--ref"]
    args = [a for a in args if a not in refs]
    if not args:
        sys.exit(__doc__)
    src = args[0]
    dst = args[1] if len(args) > 1 else src.rsplit(".", 1)[0] + ".png"
    series = defaultdict(lambda: ([], [], []))
    for row in watchpoint_rows(src):  # whole rows only: a killed run's last one may be cut short
        t, dx, dy = series[row["name"]]
        t.append(row["time"])
        dx.append(row["dx"])
        dy.append(row["dy"])
    if not series:
        sys.exit(f"{src}: no watchpoints")
    fig, ax = plt.subplots(figsize=(7, 4))
    colour = {}
    for name, (t, dx, dy) in series.items():
        colour[f"{name} dx"] = ax.plot(t, [1000 * v for v in dx], label=f"{name} dx")[0].get_color()
        colour[f"{name} dy"] = ax.plot(t, [1000 * v for v in dy], "--", label=f"{name} dy")[0].get_color()
    for ref in refs:
        label, path = ref.split("=", 1)
        t, d = read_reference(path)
        ax.plot(t, [1000 * v for v in d], "o", mfc="none", color=colour.get(label), label=f"{label} (reference)")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("displacement [mm]")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(dst, dpi=120)
    print(f"wrote {dst}")


if __name__ == "__main__":
    main()
