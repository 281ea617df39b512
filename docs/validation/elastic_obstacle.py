"""The elastic obstacle's top-right corner against the two published simulations (docs/validation.md,
"Elastic obstacle"), from a run of sweeps/elastic_obstacle.toml.
usage: /usr/bin/python3 docs/validation/elastic_obstacle.py SWEEP_DIR
Prints, per run, the corner's peak and when it comes, and the RMS difference from each reference over the
impact (t <= 0.5 s) and over the whole second, as a fraction of that reference's peak (the sweep's
`l2_rel` is the latter); the same for the references against each other. Writes elastic_obstacle_curves.csv
(the runs' corner dx every 5 ms) and elastic_obstacle_curves.png next to this file.
"""
import csv
import glob
import os
import sys

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools"))
from metrics import read_reference_curve  # noqa: E402

REFERENCES = {"Meduri et al. (2017)": "obstacle_tip_dx_meduri2017.csv",
              "Ryzhakov et al. (2010)": "obstacle_tip_dx_ryzhakov2010.csv"}
IMPACT_END, RUN_END = 0.5, 1.0


def corner(run_dir):
    """The corner watchpoint's time and dx from a run's watchpoints.csv."""
    with open(os.path.join(run_dir, "watchpoints.csv")) as f:
        rows = [r for r in csv.DictReader(f) if r["name"] == "corner"]
    return np.array([float(r["time"]) for r in rows]), np.array([float(r["dx"]) for r in rows])


def rms_of_peak(t, u, td, ud, t_max):
    keep = td <= t_max
    e = np.interp(td[keep], t, u) - ud[keep]
    return float(np.sqrt(np.mean(e * e)) / np.max(np.abs(ud)))


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    refs = {name: read_reference_curve(os.path.join(ROOT, "scenarios", "reference", f))
            for name, f in REFERENCES.items()}
    # The sweep's completed runs only: a failed or timed-out run, or a folder a different sweep file left,
    # would be read to its last row and held there (np.interp clamps).
    with open(os.path.join(sys.argv[1], "results.csv")) as f:
        completed = {r["run"] for r in csv.DictReader(f) if r["status"] == "completed"}
    runs = sorted((d for d in glob.glob(os.path.join(sys.argv[1], "runs", "dp=*")) if os.path.basename(d) in completed),
                  key=lambda d: -float(os.path.basename(d).split("=")[1].split("-")[0]))
    if not runs:
        sys.exit(f"no completed runs dp=* in {sys.argv[1]}/results.csv")
    grid = np.arange(0.0, RUN_END + 1e-9, 0.005)
    columns = {"t": grid}
    fig, ax = plt.subplots(figsize=(8, 4))
    print("run | peak dx [mm] at t [s] | " + " | ".join(f"{n}: RMS / peak to {IMPACT_END} s, to {RUN_END} s"
                                                     for n in refs))
    for run in runs:
        label = os.path.basename(run).split("-")[0]
        t, u = corner(run)
        if t[-1] < RUN_END * (1 - 1e-9):
            sys.exit(f"{run}: the corner's record ends at t = {t[-1]:g} s, before {RUN_END} s")
        k = int(np.argmax(u))
        cells = [f"{rms_of_peak(t, u, td, ud, IMPACT_END):.3f}, {rms_of_peak(t, u, td, ud, RUN_END):.3f}"
                 for td, ud in refs.values()]
        print(f"{label} | {1e3 * u[k]:.1f} at {t[k]:.3f} | " + " | ".join(cells))
        columns[label] = np.interp(grid, t, u)
        ax.plot(t, 1e3 * u, lw=1.2, label=f"sphfsi, {label} m")
    (ta, ua), (tb, ub) = refs.values()
    names = list(refs)
    for (td, ud), other, name in (((ta, ua), (tb, ub), names[0]), ((tb, ub), (ta, ua), names[1])):
        k = int(np.argmax(ud))
        print(f"{name} | {1e3 * ud[k]:.1f} at {td[k]:.3f} | against the other: "
              f"{rms_of_peak(other[0], other[1], td, ud, IMPACT_END):.3f}, {rms_of_peak(other[0], other[1], td, ud, RUN_END):.3f}")
    for (td, ud), name, marker in zip(refs.values(), names, ("o", "s")):
        ax.plot(td, 1e3 * ud, marker, ms=3, label=name)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("corner dx [mm]")
    ax.set_title("dam break against an elastic obstacle: the obstacle's top-right corner", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "elastic_obstacle_curves.png"), dpi=90)
    with open(os.path.join(HERE, "elastic_obstacle_curves.csv"), "w", newline="") as f:
        f.write(f"# corner dx [m] of each run of sweeps/elastic_obstacle.toml every 5 ms ({sys.argv[1]})\n")
        w = csv.writer(f)
        w.writerow(list(columns))
        for i in range(grid.size):
            w.writerow([f"{columns[c][i]:.6g}" for c in columns])


if __name__ == "__main__":
    main()
