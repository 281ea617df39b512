"""Dam break with a lifted gate: the front's error at each Martin & Moyce (1952) point, and the speed of the
water coming out under the gate.

For each run of a sweep folder (sweeps/dam_break_gate.toml, or sweeps/dam_break_methods.toml for the column
released at once) or each run folder given, prints one line: the run's label, (Z - Z_exp) / Z_exp in % at
each reference T <= 2.5 (tools/metrics.py surge_front: front = largest x of a fluid particle with a neighbour
within 1.5 dp, plus dp / 2; T = t sqrt(2 g / a), never shifted), their mean and largest magnitude, and the
x-velocity of that front particle at t = 10 and 30 ms (frames every 5 ms). Read it against Torricelli's
sqrt(2 g H) = 1.98 m/s for water leaving under the full 0.2 m head (docs/validation.md, "Dam break").
A run that did not complete is named and skipped; a run whose frames stop short of the last reference
point, or lack a frame at 10 or 30 ms, stops the script with a MetricError.
usage: /usr/bin/python3 docs/validation/dam_break_gate.py DIR...
"""
import csv
import math
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import metrics  # noqa: E402  (tools/metrics.py: the front as the surge_front metric measures it)

A, G = 0.1, 9.81
REFERENCE = os.path.join(ROOT, "tests", "fluid", "data", "martin_moyce_1952_front_n2_2.csv")
JET_TIMES = (0.010, 0.030)


def front_speeds(run_dir, at):
    """x-velocity of the fluid particle metrics.outermost picks as the front, in the frame at each time of
    `at` (a frame must lie within 0.1 ms of it: a speed at another time would be printed under the wrong
    heading)."""
    speeds = []
    with metrics.open_record(run_dir) as f:
        g = f["frames/fluid"]
        times = g["time"][:]
        dp = metrics.fluid_spacing(f, None)
        for t in at:
            i = int(np.argmin(np.abs(times - t)))
            if abs(times[i] - t) > 1e-4:
                raise metrics.MetricError(f"{run_dir}: no frame at t = {t} s (nearest {times[i]:.4g} s)")
            fluid = g["kind"][i][..., 0] == 0
            x, v = g["position"][i][fluid], g["velocity"][i][fluid]
            front = metrics.outermost(x, 0, dp)
            if not np.isfinite(front):
                raise metrics.MetricError(f"{run_dir}: no front at t = {t} s")
            speeds.append(float(v[int(np.argmin(np.abs(x[:, 0] - front))), 0]))
    return speeds


def report(label, run_dir, T_ref, Z_ref):
    T, Z = metrics.surge_front_series(run_dir, A, G)
    rel = 100.0 * metrics.relative_errors(T_ref, Z_ref, T, Z, "T")  # as the surge_front metric: never extrapolated
    jets = " ".join(f"{u:.2f}" for u in front_speeds(run_dir, JET_TIMES))
    points = " ".join(f"{e:+5.1f}" for e in rel)
    print(f"{label:<44} {points} | {np.mean(np.abs(rel)) / 100:.3f}, {np.max(np.abs(rel)) / 100:.3f} | {jets}")


def runs(folder):
    """(label, run folder) for each completed run of a sweep folder, or the folder itself."""
    table = os.path.join(folder, "results.csv")
    if not os.path.exists(table):
        return [(os.path.basename(os.path.normpath(folder)), folder)]
    with open(table) as f:
        rows = list(csv.DictReader(f))
    out = []
    for r in rows:
        if r["status"] != "completed":
            print(f"skipped {r['run']}: {r['status']} {r.get('message', '')}")
            continue
        dp, speed = float(r["fluid.dp"]), float(r.get("fluid.gate.lift_speed") or 0.0)
        label = f"a/{round(A / dp)} {r.get('method', '')}" + (f" gate {speed:g} m/s" if speed else "")
        out.append(((-dp, r.get("method", ""), speed), label, os.path.join(folder, "runs", r["run"])))
    return [(label, d) for _, label, d in sorted(out)]


def main(folders):
    T_ref, Z_ref = metrics.read_reference_curve(REFERENCE)
    keep = T_ref <= 2.5
    T_ref, Z_ref = T_ref[keep], Z_ref[keep]
    print(f"{'run':<44} " + " ".join(f"{t:5.2f}" for t in T_ref) + " | mean, largest | front u at "
          + ", ".join(f"{t * 1e3:.0f}" for t in JET_TIMES) + " ms (m/s)")
    print(f"Torricelli sqrt(2 g H), H = 2a: {math.sqrt(2 * G * 2 * A):.2f} m/s")
    for folder in folders:
        for label, run_dir in runs(folder):
            report(label, run_dir, T_ref, Z_ref)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
