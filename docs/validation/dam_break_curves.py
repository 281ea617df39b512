"""Dam break: the front and the column's height at every frame of the a/80 runs of a walls sweep, for the
chart of docs/validation.md ("Dam break: the column's height at the back wall").

Reads the runs of a sweeps/dam_break_walls.toml folder at dp = a/80 and writes docs/validation/
dam_break_curves.csv: method, wall condition, t, T = t sqrt(2 g / a), Z = front / a, tau = t sqrt(g / a),
H = height / (2 a), measured as tools/metrics.py's surge_front and column_height metrics measure them
(surge_front_series, column_height_series; time never shifted). plots.py draws dam_break_curves.png from it.
usage: /usr/bin/python3 docs/validation/dam_break_curves.py SWEEP_DIR
"""
import csv
import math
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import metrics  # noqa: E402

A, G, DP = 0.1, 9.81, 0.00125
OUT = os.path.join(ROOT, "docs", "validation", "dam_break_curves.csv")


def main(sweep_dir):
    runs = [r for r in csv.DictReader(open(os.path.join(sweep_dir, "results.csv")))
            if r["status"] == "completed" and math.isclose(float(r["fluid.dp"]), DP)]
    if not runs:
        sys.exit(f"{sweep_dir}: no completed run at dp = {DP} m in results.csv")
    with metrics.open_record(os.path.join(sweep_dir, "runs", runs[0]["run"])) as f:
        revision = f.attrs.get("git_revision", "unknown")
    with open(OUT, "w", newline="") as out:
        out.write(f"# Dam break at dp = a/80 (sweeps/dam_break_walls.toml, build of {revision}): "
                  "front Z = x_front/a at T = t sqrt(2g/a) and\n"
                  "# column height H at the back wall at tau = t sqrt(g/a) (docs/validation/dam_break_curves.py), "
                  "every 5 ms frame\n")
        w = csv.writer(out, lineterminator="\n")
        w.writerow(["method", "slip", "t", "T", "Z", "tau", "H"])
        for r in runs:
            run_dir = os.path.join(sweep_dir, "runs", r["run"])
            T, Z = metrics.surge_front_series(run_dir, A)
            tau, H = metrics.column_height_series(run_dir, A)
            for Ti, Zi, taui, Hi in zip(T, Z, tau, H):
                w.writerow([r["method"], r["fluid.boundary.slip"], f"{taui * math.sqrt(A / G):.3f}", f"{Ti:.4f}",
                            f"{Zi:.4f}", f"{taui:.4f}", f"{Hi:.4f}"])
    print(f"wrote {OUT} ({len(runs)} runs)")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
