#!/usr/bin/env -S /usr/bin/python3
"""Plots watchpoints.csv (time, name, x, y, dx, dy): the displacement of each named structure point.

usage: /usr/bin/python3 tools/plot_watchpoints.py RUN/watchpoints.csv [OUT.png]
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")  # files only; no display needed
import matplotlib.pyplot as plt


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    src = sys.argv[1]
    dst = sys.argv[2] if len(sys.argv) > 2 else src.rsplit(".", 1)[0] + ".png"
    series = defaultdict(lambda: ([], [], []))
    with open(src) as f:
        for row in csv.DictReader(f):
            t, dx, dy = series[row["name"]]
            t.append(float(row["time"]))
            dx.append(float(row["dx"]))
            dy.append(float(row["dy"]))
    if not series:
        sys.exit(f"{src}: no watchpoints")
    fig, ax = plt.subplots(figsize=(7, 4))
    for name, (t, dx, dy) in series.items():
        ax.plot(t, [1000 * v for v in dx], label=f"{name} dx")
        ax.plot(t, [1000 * v for v in dy], "--", label=f"{name} dy")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("displacement [mm]")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(dst, dpi=120)
    print(f"wrote {dst}")


if __name__ == "__main__":
    main()
