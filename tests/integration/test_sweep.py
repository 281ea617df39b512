"""Sweeps, metrics, charts, bisection and the regression guard (tools/sweep.py, docs/sweeps.md), on the
cantilever scene with the real coordinator and structure participant.

What theory says and the tests hold the tools to:
  * Hermite beam elements are nodally exact for a tip load: the static tip deflection equals
    P L^3 / (3 E I) to round-off at every mesh;
  * the first natural frequency converges from above as O(h^4) with consistent mass;
  * against a much finer run, newmark and generalized-alpha converge as O(dt^2), backward Euler as O(dt).
"""
import csv
import json
import math
import os
import re
import subprocess
import sys
import time
import tomllib

import harness

sys.path.insert(0, os.path.join(harness.ROOT, "tools"))
import chart  # noqa: E402
import metrics  # noqa: E402
from sweeplib import bisect as bisection  # noqa: E402
from sweeplib import results  # noqa: E402
from sweeplib import spec as specs  # noqa: E402

SWEEP = os.path.join(harness.ROOT, "tools", "sweep.py")
BEAM = os.path.join(harness.ROOT, "scenarios", "beam_only.toml")
GUARD = os.path.join(harness.ROOT, "sweeps", "guard_structure.toml")
MM_CSV = os.path.join(harness.ROOT, "tests", "fluid", "data", "martin_moyce_1952_front_n2_2.csv")
MM_HEIGHT_CSV = os.path.join(harness.ROOT, "tests", "fluid", "data", "martin_moyce_1952_height_n2_2.csv")
EI = 2.1e11 * 0.02 ** 3 / 12
F1 = 1.87510407 ** 2 / (2 * math.pi) * math.sqrt(EI / (7850.0 * 0.02))
# The corotational cantilever under a sudden P L^2 / (E I) = 2, undamped: newmark fails above some step.
BIG_LOAD = {"structure.formulation": "corotational", "structure.point_loads[0].force": [0.0, -2.8e5],
            "structure.damping.model": "none", "structure.time.integrator": "newmark",
            "structure.time.resolved_modes": 1, "structure.time.steps_per_period": 2, "run.end_time": 0.3}


def sweep(*args, timeout=120):
    """Runs tools/sweep.py under Debian's interpreter; returns (exit status, stdout + stderr)."""
    p = subprocess.run(["/usr/bin/python3", SWEEP, *args, "--bin", harness.BIN], capture_output=True, text=True,
                       timeout=timeout)
    return p.returncode, p.stdout + p.stderr


def write(path, text):
    with open(path, "w") as f:
        f.write(text)
    return path


def rows_of(out):
    with open(os.path.join(out, "results.csv"), newline="") as f:
        return list(csv.DictReader(f))


def num(x):
    return float(x) if x not in ("", None) else math.nan


def expect_metric_error(name, run_dir, params, ctx, says):
    """metrics.compute must refuse with a MetricError whose message contains `says`."""
    try:
        metrics.compute(name, run_dir, params, ctx)
    except metrics.MetricError as err:
        assert says in str(err), err
        return
    raise AssertionError(f"expected a MetricError ({says})")


def order(e_coarse, e_fine):
    return math.log(e_coarse / e_fine) / math.log(2.0)


# ---------------------------------------------------------------------------------------------------
# The mesh sweep, with a run that fails, one that is invalid and one that never ends.

_MESH = {}


def mesh_sweep():
    if _MESH:
        return _MESH["out"], _MESH["text"], _MESH["rc"]
    d = harness.shared_out_dir("sweep-mesh")
    scene = os.path.relpath(BEAM, d)  # the scene is found relative to the sweep file
    path = write(os.path.join(d, "mesh.toml"), f'''
[sweep]
scene = "{scene}"
title = "cantilever: mesh"
timeout_s = 30
grace_s = 5
threads_per_run = 1

[fixed]
"run.end_time" = 0.05
"structure.initial.static_equilibrium" = true

[grid]
"structure.members[0].n_elements" = [2, 4, 8]
"structure.time.integrator" = ["newmark", "backward_euler"]

[[case]]
name = "newton_starved"
set = {{ "structure.formulation" = "corotational", "structure.point_loads[0].force" = [0.0, -7e5], "structure.newton.max_iterations" = 2, "structure.initial.static_equilibrium" = false }}

[[case]]
name = "unknown_integrator"
set = {{ "structure.time.integrator" = "leapfrog" }}

[[case]]
name = "endless"
set = {{ "run.end_time" = 1e4 }}
timeout_s = 2

[[metric]]
name = "participant_info"
label = "f1"
key = "natural_frequencies_hz.mode_1"
exact = "1.87510407**2 / (2*pi*L**2) * sqrt(E*I/(rho*A))"
constants = {{ L = 1.0, E = 2.1e11, rho = 7850.0, t = 0.02, A = "t", I = "t**3/12" }}

[[metric]]
name = "watchpoint_mean_after"
label = "static"
watchpoint = "tip"
t_start = 0.01
exact = "P * L**3 / (3 * E * I)"
constants = {{ P = -100.0, L = 1.0, E = 2.1e11, t = 0.02, I = "t**3 / 12" }}

[chart]
series = ["structure.time.integrator"]
x = ["cpu_s", "element_steps"]
y = ["f1.rel_error"]
annotate = "structure.members[0].n_elements"
''')
    out = os.path.join(d, "out")
    start = time.time()
    rc, text = sweep(path, "--out", out, "--jobs", "2")
    print(text)
    print(f"mesh sweep: {time.time() - start:.1f} s")
    _MESH.update(out=out, text=text, rc=rc, path=path)
    return out, text, rc


def test_mesh_sweep_rows_columns_and_errors():
    out, text, rc = mesh_sweep()
    assert rc == 0, text
    rows = rows_of(out)
    assert len(rows) == 9, [r["run"] for r in rows]  # 3 x 2 grid + 3 cases: one row per run
    header = list(rows[0])
    for col in ["run", "case", "structure.members[0].n_elements", "structure.time.integrator", *results.RUN_COLUMNS,
                "f1.value", "f1.rel_error", "static.value", "static.rel_error", "notes"]:
        assert col in header, (col, header)
    assert len({r["run"] for r in rows}) == 9
    # Run folders: deterministic names, the same as --list prints.
    rc2, listing = sweep(_MESH["path"], "--list")
    assert rc2 == 0, listing
    listed = re.findall(r"^(\S+-[0-9a-f]{8})", listing, re.M)
    assert listed == [r["run"] for r in rows], (listed, [r["run"] for r in rows])
    grid = [r for r in rows if not r["case"]]
    assert len(grid) == 6 and all(r["status"] == "completed" for r in grid), [(r["run"], r["status"]) for r in grid]
    for r in grid:
        d = os.path.join(out, "runs", r["run"])
        assert os.path.isfile(os.path.join(d, "record.h5")) and os.path.isfile(os.path.join(d, "result.json"))
        wall, cpu = num(r["wall_s"]), num(r["cpu_s"])
        assert 0 < cpu and 0 < wall < 30, (wall, cpu)
        # Structure alone: one coupling iteration per window, element-steps = elements x sub-steps, no particles.
        assert int(r["coupling_iterations"]) == int(r["windows"]) > 0
        assert int(r["element_steps"]) == int(r["structure_elements"]) * int(r["structure_substeps"])
        assert int(r["structure_elements"]) == int(r["structure.members[0].n_elements"])
        assert r["particle_steps"] == "" and r["fluid_particles"] == ""
        assert abs(num(r["t_end"]) - 0.05) < 1e-12
        assert abs(num(r["f1.exact"]) - F1) < 1e-9 * F1
    for integrator in ("newmark", "backward_euler"):
        series = sorted((int(r["structure.members[0].n_elements"]), r) for r in grid
                        if r["structure.time.integrator"] == integrator)
        f1 = [num(r["f1.rel_error"]) for _, r in series]
        static = [num(r["static.rel_error"]) for _, r in series]
        print(f"{integrator}: f1 relative errors {['%.3g' % e for e in f1]} for n = 2, 4, 8; "
              f"static tip deflection errors {['%.2g' % e for e in static]}")
        # O(h^4): 16 per halving asymptotically; at least 8 here. From above: consistent mass gives a
        # Rayleigh-Ritz upper bound (rel_error is |f - f_exact| / f_exact, so the sign is checked on the values).
        assert all(e > 0 for e in f1) and f1[0] / f1[1] > 8 and f1[1] / f1[2] > 8, f1
        assert all(num(r["f1.value"]) > num(r["f1.exact"]) for _, r in series), [r["f1.value"] for _, r in series]
        # Nodally exact: round-off of the 12 digits watchpoints.csv keeps.
        assert all(0 <= e < 1e-9 for e in static), static
        for _, r in series:
            assert abs(num(r["static.value"]) - (-100.0 / (3 * EI))) < 1e-9 * 100.0 / (3 * EI)


def test_watchpoint_against_data():
    """watchpoint_vs_data on a real run, against data made from its own series plus a known offset."""
    out, text, rc = mesh_sweep()
    run = [r for r in rows_of(out) if r["status"] == "completed"][0]["run"]
    d = os.path.join(out, "runs", run)
    t, v = metrics.watchpoint_series(d, "tip", "dy")
    pick = [1, len(t) // 3, len(t) // 2, len(t) - 2]
    path = write(os.path.join(d, "data.csv"), "# made up: the run's own tip dy plus 1e-6 m\nt,dy\n"
                 + "".join(f"{t[i]!r},{v[i] + 1e-6!r}\n" for i in pick))
    ctx = metrics.Context(metrics.RunInfo(run, d), [], d)
    got = metrics.compute("watchpoint_vs_data", d, {"watchpoint": "tip", "data_csv": "data.csv"}, ctx)
    scale = max(abs(v[i] + 1e-6) for i in pick)
    assert got["n_points"] == 4 and abs(got["rms_abs"] - 1e-6) < 1e-15 and abs(got["max_abs"] - 1e-6) < 1e-15, got
    assert abs(got["l2_rel"] - 1e-6 / scale) < 1e-12 and abs(got["max_rel"] - 1e-6 / scale) < 1e-12, got
    # On the command line a relative data_csv starts at the current folder (in a sweep: at the sweep file).
    p = subprocess.run(["/usr/bin/python3", os.path.join(harness.ROOT, "tools", "metrics.py"), ".", "watchpoint_vs_data",
                        "watchpoint=tip", "data_csv=data.csv"], cwd=d, capture_output=True, text=True, timeout=60)
    assert p.returncode == 0 and "watchpoint_vs_data.n_points = 4" in p.stdout, p.stdout + p.stderr
    write(path, "t,dy\n0.0,0.0\n1.0,0.0\n")  # beyond the run's 0.05 s: reported, not extrapolated
    expect_metric_error("watchpoint_vs_data", d, {"watchpoint": "tip", "data_csv": "data.csv"}, ctx, "covers")


def test_failed_invalid_and_endless_runs_are_rows():
    out, text, rc = mesh_sweep()
    by_case = {r["case"]: r for r in rows_of(out) if r["case"]}
    starved = by_case["newton_starved"]
    assert starved["status"] == "failed" and starved["exit_code"] == "1", starved
    assert "not_converged" in starved["message"] and "\n" not in starved["message"], starved["message"]
    assert starved["f1.rel_error"] == "" and starved["static.rel_error"] == ""  # no errors for failed runs
    bad = by_case["unknown_integrator"]
    assert bad["status"] == "invalid" and bad["exit_code"] == "2", bad
    assert "leapfrog" in bad["message"] and "structure.time.integrator" in bad["message"], bad["message"]
    endless = by_case["endless"]
    assert endless["status"] == "timeout", endless
    # SIGINT at 2 s; the coordinator stops its participant and exits well within the 5 s grace.
    assert 2.0 <= num(endless["wall_s"]) < 2.0 + 5.0, endless["wall_s"]
    assert endless["exit_code"] == "130", endless["exit_code"]
    assert 0 < num(endless["t_end"]) < 1e4 and "stopped at t =" in endless["message"], endless
    with harness.record(os.path.join(out, "runs", endless["run"], "record.h5")) as f:
        assert str(f.attrs["status"]).startswith("interrupted"), f.attrs["status"]
        own = float(f.attrs["coordinator_cpu_s"])
        compute = float(f["windows/structure_compute_s"][:].sum())
    # cpu_s holds the participant's CPU too: more than the coordinator's own by at least (a good part of)
    # the time the participant spent computing.
    assert num(endless["cpu_s"]) - own > 0.5 * compute > 0, (endless["cpu_s"], own, compute)
    assert "3 did not complete" in text, text


def test_charts_are_written():
    out, text, rc = mesh_sweep()
    for x in ("cpu_s", "element_steps"):
        prefix = os.path.join(out, f"chart-f1.rel_error-vs-{x}")
        with open(prefix + ".png", "rb") as f:
            png = f.read()
        assert png.startswith(b"\x89PNG") and len(png) > 20000, len(png)
        with open(prefix + ".svg") as f:
            svg = f.read()
        assert "<svg" in svg and len(svg) > 20000
    # The command line, with a filter: the backward-Euler series alone, three points, Pareto front of 1 to 3.
    prefix = os.path.join(out, "cli")
    p = subprocess.run(["/usr/bin/python3", os.path.join(harness.ROOT, "tools", "chart.py"),
                        os.path.join(out, "results.csv"), "--x", "element_steps", "--y", "f1.rel_error",
                        "--series", "structure.time.integrator", "--where", "structure.time.integrator=backward_euler",
                        "--out", prefix], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stderr
    assert "3 runs in 1 series, 0 did not complete" in p.stdout, p.stdout
    assert os.path.getsize(prefix + ".png") > 10000 and os.path.getsize(prefix + ".svg") > 10000
    # Refinement costs more and errs less: all three points are on the front.
    front = p.stdout.split("Pareto front", 1)[1].strip().splitlines()[1:]
    assert len(front) == 3 and all("integrator=backward_euler" in line for line in front), p.stdout


def test_chart_names_a_completed_run_whose_metric_has_no_value():
    """A run that completed but whose metric could not be computed (an empty cell in results.csv) is drawn
    and counted apart from the plotted points, as not having a value; it was once drawn as a run with no
    positive error, which reads as exact. An empty cell the notes do not explain is the reference run's (a
    metric against itself: drawn as a reference) or a run the metric's `where` leaves out (not drawn); both were
    once drawn and counted as runs that did not complete."""
    rows = [{"status": "completed", "cpu_s": "1.0", "err": "0.1", "m": "a"},
            {"status": "completed", "cpu_s": "2.0", "err": "0.05", "m": "a"},
            {"status": "completed", "cpu_s": "3.0", "err": "", "m": "a", "notes": "err: the frames reach T = 1"},
            {"status": "completed", "cpu_s": "4.0", "err": "0", "m": "a"},
            {"status": "completed", "cpu_s": "5.0", "err": "", "m": "a", "run": "finest"},
            {"status": "completed", "cpu_s": "6.0", "err": "", "m": "a", "notes": "other: no data"},
            {"status": "failed", "cpu_s": "7.0", "err": "", "m": "a"}]
    prefix = os.path.join(harness.out_dir("chart-no-value"), "chart")
    summary = chart.make_chart(rows, "cpu_s", "err", ["m"], prefix, desc={"reference_run": "finest"})
    got = tuple(summary[k] for k in ("plotted", "failed", "no_value", "no_error", "not_applicable"))
    assert got == (2, 1, 1, 2, 1), summary


def test_print_expect_keeps_each_expectations_own_tolerances():
    """--print-expect writes the measured values to paste back into the sweep file; before 2026-11-27 it
    wrote bare numbers, dropping a recorded atol, tolerance or two_sided (the next --check then failed on
    round-off), and left out integer quantities."""
    from sweeplib import expect as guard
    run = specs.Run({"k": 1}, {}, case="c", expect={"status": "completed", "a.rel": {"value": 1e-12, "atol": 1e-9},
                                                      "b.frac": {"value": 1.0, "two_sided": True},
                                                      "c.n": {"value": 4.0}})
    text = guard.expect_toml([run], {run.id: {"status": "completed", "a.rel": 2e-12, "b.frac": 0.5, "c.n": 5}},
                             [], "today")
    assert '"a.rel" = { value = 2e-12, atol = ' + specs.toml_value(1e-9) + ' }' in text, text
    assert '"b.frac" = { value = 0.5, two_sided = true }' in text and '"c.n" = 5' in text, text
    # A grid run's table names it by its settings and by having no case: a [[case]] with the same settings
    # (here a failing one) matched it too, so the pasted tables failed --check at once (a review, 2026-11-27).
    grid_run, case_run = specs.Run({}, {"k": 1}), specs.Run({}, {"k": 1}, case="starved")
    text = guard.expect_toml([grid_run], {grid_run.id: {"status": "completed", "a.rel": 1e-3}}, ["a.rel"], "today")
    where = tomllib.loads(text)["expect"][0]["where"]
    assert specs.matches(grid_run, where) and not specs.matches(case_run, where), text


def test_a_formula_that_is_not_a_real_number_is_named():
    """A negative base to a fractional power is complex in Python: float() of it had raised a TypeError that
    no caller expected (a traceback from metrics.py; a review, 2026-11-27)."""
    from sweeplib import formula
    assert formula.evaluate("P**(1/3)", {"P": 8.0}) == 2.0
    try:
        formula.evaluate("P**(1/3)", {"P": -8.0})
        raise AssertionError("a complex value was accepted")
    except formula.FormulaError as err:
        assert "is not a real number" in str(err), err


FAKE_COORDINATOR = r'''
import os, signal, subprocess, sys, time
# A coordinator that ignores SIGINT, with a "participant" in its own process group that ignores SIGINT and
# SIGTERM and burns CPU: only SIGKILL ends them.
signal.signal(signal.SIGINT, signal.SIG_IGN)
out = sys.argv[sys.argv.index("--out") + 1]
child = subprocess.Popen([sys.executable, "-c", "import signal\nsignal.signal(signal.SIGINT, signal.SIG_IGN)\n"
                          "signal.signal(signal.SIGTERM, signal.SIG_IGN)\nwhile True: pass"], start_new_session=True)
with open(os.path.join(out, "child.pid"), "w") as f:
    f.write(str(child.pid))
while True:
    time.sleep(0.05)
'''


def test_runner_kills_what_ignores_sigint():
    from sweeplib import runner
    d = harness.out_dir("sweep-kill")
    fake = write(os.path.join(d, "fake_sphfsi"), "#!/usr/bin/python3\n" + FAKE_COORDINATOR)
    os.chmod(fake, 0o755)
    out = os.path.join(d, "run")
    res = runner.run_coordinator(fake, BEAM, out, [], timeout_s=1.0, grace_s=1.0)
    with open(os.path.join(out, "child.pid")) as f:
        child = int(f.read())
    deadline = time.time() + 5.0  # the kernel reaps the killed group a moment later on a loaded machine
    while harness.pid_alive(child) and time.time() < deadline:
        time.sleep(0.05)
    assert not harness.pid_alive(child), "the participant outlived the SIGKILL"
    assert res.timed_out and res.killed and res.exit_code == -9, vars(res)
    # SIGINT at the 1 s timeout, SIGKILL 1 s later; 1.5 s of slack for a loaded 2-core machine.
    assert 2.0 <= res.wall_s < 2.0 + 1.5, res.wall_s
    # The participant was never reaped by the coordinator: its CPU (about 1.5 s of a busy loop, less on a
    # loaded machine) was read from /proc before the kill.
    assert res.extra_cpu > 0.2 and res.cpu_s >= res.extra_cpu, vars(res)


def test_pareto_front():
    pts = [(1.0, 5.0), (2.0, 3.0), (2.0, 4.0), (3.0, 3.5), (4.0, 1.0), (5.0, 1.0), (0.5, 9.0), (4.0, 1.0)]
    front = chart.pareto_front(pts)
    assert [pts[i] for i in front] == [(0.5, 9.0), (1.0, 5.0), (2.0, 3.0), (4.0, 1.0)], [pts[i] for i in front]
    assert chart.pareto_front([]) == []
    assert abs(chart.loglog_slope([1, 10, 100], [1, 0.01, 1e-4]) + 2) < 1e-12


# ---------------------------------------------------------------------------------------------------


def beam_against_reference(end_time, integrators, reference_dt, more_grid=""):
    """A sweep file's text up to its [chart] or [bisect]: BEAM's cantilever to end_time with its step set by
    dt_max alone, the integrators (a TOML array) as a grid axis (plus `more_grid` lines), a newmark reference
    run at reference_dt, and the tip's difference from it as the metric."""
    return f'''
[sweep]
scene = "{BEAM}"
timeout_s = 60
threads_per_run = 1

[fixed]
"run.end_time" = {end_time}
"structure.time.resolved_modes" = 1
"structure.time.steps_per_period" = 2
"structure.time.max_numerical_damping" = 0.5

[grid]
"structure.time.integrator" = {integrators}
{more_grid}

[[case]]
name = "reference"
reference = true
set = {{ "structure.time.integrator" = "newmark", "structure.time.dt_max" = {reference_dt} }}

[[metric]]
name = "watchpoint_vs_reference_run"
label = "tip"
watchpoint = "tip"
'''


def test_time_step_convergence_orders():
    d = harness.out_dir("sweep-dt")
    path = write(os.path.join(d, "dt.toml"), beam_against_reference(0.1, '["newmark", "backward_euler"]', 1.5625e-5,
                                                                    '"structure.time.dt_max" = [1e-3, 5e-4, 2.5e-4]') + '''
[chart]
series = ["structure.time.integrator"]
x = ["cpu_s"]
''')
    out = os.path.join(d, "out")
    rc, text = sweep(path, "--out", out, "--jobs", "2")
    assert rc == 0, text
    rows = rows_of(out)
    assert len(rows) == 7
    ref = [r for r in rows if r["case"] == "reference"][0]
    assert ref["status"] == "completed" and ref["tip.l2_rel"] == ""  # nothing against itself
    err = {}
    for r in rows:
        if r["case"]:
            continue
        assert r["status"] == "completed", r
        assert int(r["tip.n_times"]) >= 11  # at least the 11 frames
        err[(r["structure.time.integrator"], num(r["structure.time.dt_max"]))] = num(r["tip.l2_rel"])
    nm = [err[("newmark", dt)] for dt in (1e-3, 5e-4, 2.5e-4)]
    be = [err[("backward_euler", dt)] for dt in (1e-3, 5e-4, 2.5e-4)]
    print(f"newmark L2 errors {['%.3g' % e for e in nm]}, orders {order(nm[0], nm[1]):.2f} {order(nm[1], nm[2]):.2f}")
    print(f"backward Euler L2 errors {['%.3g' % e for e in be]}, orders {order(be[0], be[1]):.2f} {order(be[1], be[2]):.2f}")
    assert 1.7 < order(nm[1], nm[2]) < 2.3 and order(nm[0], nm[1]) > 1.5, nm
    assert 0.7 < order(be[1], be[2]) < 1.3 and order(be[0], be[1]) > 0.6, be
    assert all(n < b for n, b in zip(nm, be))
    assert os.path.getsize(os.path.join(out, "chart-tip.l2_rel-vs-cpu_s.png")) > 10000


# ---------------------------------------------------------------------------------------------------


def test_bisection_finds_the_stability_limit():
    d = harness.out_dir("sweep-bisect")
    fixed = "\n".join(f'"{k}" = {specs.toml_value(v)}' for k, v in BIG_LOAD.items())
    path = write(os.path.join(d, "bisect.toml"), f'''
[sweep]
scene = "{BEAM}"
timeout_s = 60
threads_per_run = 1

[fixed]
{fixed}

[bisect]
key = "structure.time.dt_max"
low = 1e-4
high = 5e-3
rel_tol = 0.1
max_runs = 12
''')
    out = os.path.join(d, "out")
    rc, text = sweep(path, "--out", out)
    print(text)
    assert rc == 0, text
    with open(os.path.join(out, "thresholds.csv")) as f:
        th = list(csv.DictReader(f))
    assert len(th) == 1, th
    t, bad = num(th[0]["threshold"]), num(th[0]["first_failing"])
    assert th[0]["passes"] == "below" and th[0]["converged"] == "true", th[0]
    assert 0 < bad - t <= 0.1 * t, (t, bad)
    runs = int(th[0]["runs"])
    assert runs <= 12, runs
    with open(os.path.join(out, "probes.csv")) as f:
        probes = list(csv.DictReader(f))
    assert len(probes) == runs
    beyond = [num(v) for v in th[0]["passes_beyond"].split()]
    for p in probes:  # every probe up to the threshold passed; above it, passes only where reported
        v = num(p["value"])
        if v <= t:
            assert p["passed"] == "true", (v, p["status"], p["message"])
        elif v <= bad or p["passed"] != "true":
            assert p["passed"] != "true" and p["status"] == "failed" and p["message"], p
        else:
            assert th[0]["non_monotonic"] == "true" and v in beyond, (v, th[0])
    assert any(num(p["value"]) == bad and p["passed"] == "false" for p in probes)
    # Independently of the tool: the coordinator completes at the threshold and fails just above it.
    base = [x for k, v in BIG_LOAD.items() for x in ("--set", f"{k}={specs.toml_value(v)}")]
    code, msg = harness.sphfsi("run", BEAM, "--out", os.path.join(d, "at"), "--quiet", *base,
                               "--set", f"structure.time.dt_max={t!r}")
    assert code == 0, msg
    code, msg = harness.sphfsi("run", BEAM, "--out", os.path.join(d, "above"), "--quiet", *base,
                               "--set", f"structure.time.dt_max={bad!r}")
    # Newton's divergence stopped it until 2026-11-27; the structure's energy check now stops it first.
    assert code == 1 and ("not_converged" in msg or "energy created" in msg), msg
    assert os.path.getsize(os.path.join(out, "thresholds.png")) > 5000
    print(f"newmark, corotational, P L^2/EI = 2: stable up to dt = {t:g} s, fails at {bad:g} s ({runs} runs)")


def test_a_bisection_bounded_by_a_reference_metric_sees_the_reference_run():
    """fail_if on a metric against the reference run (docs/sweeps.md's own [bisect] example): the reference
    runs first and every probe's metrics see it. Before 2026-11-27 each probe saw only itself, every probe
    failed with 'no reference run', and the bisection reported that neither end passes."""
    d = harness.out_dir("sweep-bisect-reference")
    path = write(os.path.join(d, "bisect.toml"), beam_against_reference(0.05, '["backward_euler", "generalized_alpha"]', 1e-5) + '''
[bisect]
key = "structure.time.dt_max"
low = 1e-4
high = 1e-2
rel_tol = 0.3
max_runs = 8
fail_if = { "tip.max_rel" = 0.05 }
''')
    out = os.path.join(d, "out")
    rc, text = sweep(path, "--out", out)
    print(text)
    assert rc == 0 and "the reference run reference first" in text, text
    with open(os.path.join(out, "probes.csv")) as f:
        probes = list(csv.DictReader(f))
    assert probes and not any("no reference run" in p["reason"] for p in probes), probes
    assert all(p["tip.max_rel"] for p in probes if p["status"] == "completed"), probes
    assert any(p["passed"] == "true" for p in probes), probes
    # An accuracy limit found through the reference: larger steps fail on the metric, not on completing.
    assert any(p["passed"] == "false" and p["status"] == "completed" and "tip.max_rel" in p["reason"] for p in probes), probes


def one_beam_run(end_time, sweep_keys=""):
    """A sweep file of one case: the beam to `end_time`, with `sweep_keys` added to its [sweep] table."""
    return f'''
[sweep]
scene = "{BEAM}"
threads_per_run = 1
{sweep_keys}
[fixed]
"run.end_time" = {end_time}
[[case]]
name = "beam"
'''


def test_resume_reruns_a_timeout_under_a_longer_limit():
    """--resume keeps finished runs, but a run that timed out under a shorter limit than today's is run again
    (it was kept as a timeout for ever, and --check then failed on a limit already raised)."""
    d = harness.out_dir("sweep-resume-timeout")
    path = os.path.join(d, "s.toml")
    out = os.path.join(d, "out")
    write(path, one_beam_run(0.05, "timeout_s = 0.01\ngrace_s = 5"))
    sweep(path, "--out", out, "--no-charts")
    assert [r["status"] for r in rows_of(out)] == ["timeout"], rows_of(out)
    write(path, one_beam_run(0.05, "timeout_s = 60\ngrace_s = 5"))
    rc, text = sweep(path, "--out", out, "--no-charts", "--resume")
    assert rc == 0 and [r["status"] for r in rows_of(out)] == ["completed"], (text, rows_of(out))
    assert "(kept)" not in text, text


def test_resume_reads_a_kept_runs_record_again():
    """A kept run's columns come from its record.h5 as today's tools read it, not from the row an older tool
    wrote (a resumed sweep had kept an over-counted particle_steps): a result.json whose counts disagree with
    its record is corrected; the exit status and times it holds are kept."""
    d = harness.out_dir("sweep-resume-reread")
    path = write(os.path.join(d, "s.toml"), one_beam_run(0.01))
    out = os.path.join(d, "out")
    rc, text = sweep(path, "--out", out, "--no-charts")
    first = rows_of(out)[0]
    assert rc == 0 and first["status"] == "completed", text
    run_dir = os.path.join(out, "runs", first["run"])
    with open(os.path.join(run_dir, "result.json")) as f:
        data = json.load(f)
    data["row"].update(coupling_iterations=9999, element_steps=123456789, windows=1)
    data.pop("run_result", None)  # as written before it was saved: rebuilt from the row
    with open(os.path.join(run_dir, "result.json"), "w") as f:
        json.dump(data, f)
    rc, text = sweep(path, "--out", out, "--no-charts", "--resume")
    kept = rows_of(out)[0]
    assert rc == 0 and "(kept)" in text, text
    for col in ("coupling_iterations", "element_steps", "windows", "t_end", "status", "wall_s", "cpu_s", "exit_code"):
        assert kept[col] == first[col], (col, kept[col], first[col])


_ONLY = {}


def only_sweep():
    """A reference run, a coarse run and one never run: all three but the last run first; then, after the
    reference's result.json is made to name another build and thread count, --only coarse (no --resume)."""
    if _ONLY:
        return _ONLY
    d = harness.shared_out_dir("sweep-only")
    path = write(os.path.join(d, "s.toml"), f'''
[sweep]
scene = "{BEAM}"
threads_per_run = 1
[fixed]
"run.end_time" = 0.01
[[case]]
name = "finest"
reference = true
set = {{ "structure.time.dt_max" = 1e-4 }}
[[case]]
name = "coarse"
set = {{ "structure.time.dt_max" = 1e-3 }}
[[case]]
name = "never"
set = {{ "structure.time.dt_max" = 5e-4 }}
[[metric]]
name = "watchpoint_vs_reference_run"
label = "tip"
watchpoint = "tip"
[chart]
x = ["cpu_s"]
y = ["tip.l2_rel"]
''')
    out = os.path.join(d, "out")
    rc, text = sweep(path, "--out", out, "--only", "finest", "--only", "coarse")
    assert rc == 0 and [r["status"] for r in rows_of(out)] == ["completed", "completed"], text
    reference = [r for r in rows_of(out) if r["case"] == "finest"][0]["run"]
    result = os.path.join(out, "runs", reference, "result.json")
    with open(result) as f:
        data = json.load(f)
    data.update(build="another build", threads=7)
    with open(result, "w") as f:
        json.dump(data, f)
    rc, text = sweep(path, "--out", out, "--only", "coarse")
    print(text)
    _ONLY.update(out=out, rc=rc, text=text, rows={r["case"]: r for r in rows_of(out)})
    return _ONLY


def test_only_keeps_the_other_runs_in_the_table_and_charts():
    """--only reruns the selected runs; the table and the charts still hold every run of the sweep with a
    usable result on disk (they had held the subset alone, overwriting the whole sweep's), and a run with
    none is left out and counted."""
    s = only_sweep()
    assert s["rc"] == 0, s["text"]
    assert sorted(s["rows"]) == ["coarse", "finest"], s["rows"]
    assert s["rows"]["finest"]["status"] == "completed" and s["rows"]["finest"]["tip.l2_rel"] == ""
    assert num(s["rows"]["coarse"]["tip.l2_rel"]) > 0, s["rows"]["coarse"]
    assert "1 run(s) not selected kept in the table" in s["text"] and "1 not selected have none usable" in s["text"]
    assert "[1/1]" in s["text"] and "(kept)" not in s["text"], s["text"]  # only the selected run ran
    # The chart has the coarse run as a point and the kept reference run as a triangle.
    assert re.search(r"chart: \S+chart-tip\.l2_rel-vs-cpu_s\.png/\.svg \(1 runs in 1 series, 0 did not complete, "
                     r"0 no value, 1 without error", s["text"]), s["text"]


def test_only_compares_the_build_of_a_reference_run_not_selected():
    """A reference run that --only leaves out is compared like a run --resume keeps: metrics against a
    reference made by another build, or timed with another thread count, are warned about and noted in its
    row (they had been computed against it silently)."""
    s = only_sweep()
    notes = s["rows"]["finest"]["notes"]
    assert "kept: made by another build of sphfsi" in notes and "kept: ran with 7 threads per run, not 1" in notes, notes
    assert re.search(r"note: 1 kept result\(s\) \(finest-[0-9a-f]{8}\) were made by another build", s["text"]), s["text"]
    assert "ran with another thread count than this sweep's 1" in s["text"], s["text"]
    assert "kept" not in s["rows"]["coarse"]["notes"], s["rows"]["coarse"]["notes"]


def test_reference_curve_lines_are_two_numbers():
    """read_reference_curve: exactly two comma-separated numbers a line, after '#' lines and an optional
    header of two fields that are not numbers. A three-column file had been read as its first two columns, and
    a first row that did not parse (another separator) had been taken for the header and lost, both silently."""
    d = harness.out_dir("sweep-reference-curve")
    path = os.path.join(d, "curve.csv")
    for text, line in (("t,dx,dy\n0,1,9\n0.1,2,9\n", 1),  # a third column
                       ("0.0;1.0\n0.1;2.0\n", 1),  # another separator: no header to lose
                       ("# data\nt,dx\n0,1\n0.1,2,3\n", 4),
                       ("t,dx\n0,1\n0.1\n", 3),
                       ("t,dx\n0,1\nx,2\n", 3),
                       ("t,1\n0,1\n0.1,2\n", 1),  # a header holds no number
                       ("t,dx\n0,1\n0.1,inf\n", 3),
                       ("t,dx\n0,1\nt,dx\n0.1,2\n", 3)):  # a second header
        write(path, text)
        try:
            metrics.read_reference_curve(path)
            raise AssertionError(f"accepted {text!r}")
        except metrics.MetricError as err:
            assert f"{path}:{line}: " in str(err), (text, str(err))
    for text in ("0.0,1.0\n0.1,2.0\n", "# a comment\n\nT,Z\n0.0, 1.0\n0.1,2.0\n"):
        x, y = metrics.read_reference_curve(write(path, text))
        assert list(x) == [0.0, 0.1] and list(y) == [1.0, 2.0], (text, x, y)


def test_chart_draws_no_infinite_error_as_exact():
    """An infinite or NaN error (results.cell writes inf as "inf") has no value to draw: a cross with a note,
    counted as no value; it had been drawn as a triangle, "no positive error (reference / exact)", i.e. as
    exact. A triangle is kept for an error of exactly 0; a negative value (a signed column) is counted apart."""
    rows = [{"status": "completed", "cpu_s": "1.0", "err": "0.1"},
            {"status": "completed", "cpu_s": "2.0", "err": "0.05"},
            {"status": "completed", "cpu_s": "3.0", "err": "inf"},
            {"status": "completed", "cpu_s": "4.0", "err": "nan"},
            {"status": "completed", "cpu_s": "5.0", "err": "-inf"},
            {"status": "completed", "cpu_s": "6.0", "err": "0.0"},
            {"status": "completed", "cpu_s": "7.0", "err": "-0.02"}]
    prefix = os.path.join(harness.out_dir("chart-not-finite"), "chart")
    summary = chart.make_chart(rows, "cpu_s", "err", [], prefix)
    got = tuple(summary.get(k) for k in ("plotted", "failed", "no_value", "no_error", "negative"))
    assert got == (2, 0, 3, 1, 1), summary


def test_chart_prints_no_unit_it_does_not_know():
    """A metric's value and abs_error have the unit of what it measures ("as the quantity" in sweep.json):
    the axis label had printed that as the unit, "[as the quantity]"."""
    desc = {"columns": {"tip.abs_error": {"meaning": "watchpoint_final: |value - exact|", "unit": "as the quantity"},
                        "tip.rms_abs": {"meaning": "RMS of u - u_data", "unit": "m"},
                        "tip.rel_error": {"meaning": "|value - exact| / |exact|", "unit": "-"}}}
    assert chart.axis_label("tip.abs_error", desc) == "tip.abs_error: watchpoint_final: |value - exact|"
    assert chart.axis_label("tip.rms_abs", desc).endswith("[m]") and chart.axis_label("tip.rel_error", desc).endswith("[-]")


def test_elastic_gate_table_has_the_sweeps_columns():
    """The committed table of sweeps/elastic_gate.toml has the columns the sweep writes today. The minimum of
    /windows/converged (1: every window converged) was labelled "unconverged", which reads the other way."""
    sw = specs.load(os.path.join(harness.ROOT, "sweeps", "elastic_gate.toml"))
    cols = [f"{m['label']}.{k}" for m in sw.metrics for k in metrics.METRICS[m["name"]].columns]
    with open(os.path.join(harness.ROOT, "docs", "validation", "elastic_gate.csv"), newline="") as f:
        header = next(csv.reader(f))
    assert header == results.columns(sw.setting_columns, cols), header
    assert "converged_min.value" in header and not any("unconverged" in c for c in header), header


def test_fluid_count_falls_back_to_the_total():
    """docs/sweeps.md (particle_steps) says walls are counted when the fluid reports no fluid count and its
    frames hold no kind: the count falls back to the total, as tools/sweeplib/record.py does."""
    import h5py
    from sweeplib import record
    d = harness.out_dir("sweep-fluid-count")
    with h5py.File(os.path.join(d, "record.h5"), "w") as f:
        f.create_group("participants/fluid").attrs["particles"] = 12
        f.create_dataset("frames/fluid/position", (1, 12, 2), dtype="float64")
    with record.open_record(d) as f:
        assert record.fluid_particle_count(f, f["participants/fluid"].attrs) == 12


def test_watchpoint_rows_stop_at_a_row_cut_short():
    """A killed run's watchpoints.csv may end inside a row: whole rows only, by the coordinator's own rule
    (a cut inside a number had been read as a wrong value, a cut between fields had crashed the plot)."""
    d = harness.out_dir("sweep-watchpoint-cut")
    whole = "time,name,x,y,dx,dy\n0,tip,0.3,0.2,0,0\n0.001,tip,0.3,0.2,1e-05,-2.5e-05\n"
    for tail in ("", "0.002,tip,0.3,0.2,3e-05,-1.2", "0.002,tip,0.3", "0.0"):
        path = write(os.path.join(d, "watchpoints.csv"), whole + tail)
        rows = metrics.watchpoint_rows(path)
        assert [(r["time"], r["dy"]) for r in rows] == [(0.0, 0.0), (0.001, -2.5e-05)], (tail, rows)
        t, v = metrics.watchpoint_series(d, "tip", "dy")
        assert list(t) == [0.0, 0.001] and list(v) == [0.0, -2.5e-05], (tail, t, v)
    p = subprocess.run(["/usr/bin/python3", os.path.join(harness.ROOT, "tools", "plot_watchpoints.py"), path,
                        os.path.join(d, "plot.png")], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0 and os.path.getsize(os.path.join(d, "plot.png")) > 0, p.stderr


def test_integer_bisection_upwards():
    """Newton's iteration cap: too few iterations fail, so the smallest passing value is sought."""
    d = harness.out_dir("sweep-bisect-int")
    path = write(os.path.join(d, "newton.toml"), f'''
[sweep]
scene = "{BEAM}"
timeout_s = 60

[fixed]
"structure.formulation" = "corotational"
"structure.point_loads[0].force" = [0.0, -7e5]
"run.end_time" = 0.02

[bisect]
key = "structure.newton.max_iterations"
low = 1
high = 25
''')
    out = os.path.join(d, "out")
    rc, text = sweep(path, "--out", out)
    assert rc == 0, text
    with open(os.path.join(out, "thresholds.csv")) as f:
        th = list(csv.DictReader(f))[0]
    n, bad = int(th["threshold"]), int(th["first_failing"])
    assert th["passes"] == "above" and th["converged"] == "true" and bad == n - 1, th
    # A clean boundary: bisection from both ends, then two confirming probes below (n - 1 is the failing one).
    assert int(th["runs"]) <= bisection.bound_on_runs(1, 25, "linear", True, 0.05, 2) and th["non_monotonic"] == "false", th
    sets = ["--set", "structure.formulation=corotational", "--set", "structure.point_loads[0].force=[0.0, -7e5]",
            "--set", "run.end_time=0.02"]
    code, msg = harness.sphfsi("run", BEAM, "--out", os.path.join(d, "n"), "--quiet", *sets,
                               "--set", f"structure.newton.max_iterations={n}")
    assert code == 0, msg
    code, msg = harness.sphfsi("run", BEAM, "--out", os.path.join(d, "n-1"), "--quiet", *sets,
                               "--set", f"structure.newton.max_iterations={n - 1}")
    assert code == 1 and "not_converged" in msg, msg
    print(f"smallest Newton cap that completes: {n} ({th['runs']} runs)")


def test_bisection_helpers():
    assert bisection.midpoint(1e-4, 1e-2, "log", False, 0.1) == 1e-3
    assert bisection.midpoint(3, 4, "linear", True, 0.1) is None
    assert bisection.midpoint(1, 25, "linear", True, 0.1) == 13
    seen = []

    def probe(v):  # a synthetic method, stable below 0.37
        seen.append(v)
        return v < 0.37, {}
    cfg = dict(low=0.01, high=1.0, rel_tol=0.01, max_runs=30, scale="log", integer=False)
    s = bisection.bisect(cfg, probe)
    assert s["converged"] and s["threshold"] < 0.37 <= s["first_failing"] <= s["threshold"] * 1.01, s
    assert len(seen) == s["runs"] <= bisection.bound_on_runs(0.01, 1.0, "log", False, 0.01, 2)
    assert not s["non_monotonic"] and s["passes"] == "below"
    s = bisection.bisect(dict(cfg, low=0.5), probe)
    assert s["threshold"] is None and "neither" in s["note"], s

    def ragged(v):  # stable below 0.345, unstable in [0.345, 0.35), stable again in [0.35, 0.37)
        return v < 0.345 or 0.35 <= v < 0.37, {}
    s = bisection.bisect(dict(cfg, confirm=8, max_runs=40), ragged)
    # Bisection alone lands at 0.37; the probes just below it find the gap and the threshold moves to 0.345.
    assert s["non_monotonic"] and s["passes_beyond"] and s["threshold"] < 0.345 <= s["first_failing"], s
    assert s["first_failing"] <= 0.345 * 1.01 + 1e-12 and s["converged"], s

    def upward(v):  # an iteration cap: 7 and more pass
        return v >= 7, {}
    s = bisection.bisect(dict(low=1, high=50, rel_tol=0.05, max_runs=20, scale="linear", integer=True), upward)
    assert (s["passes"], s["threshold"], s["first_failing"]) == ("above", 7, 6), s


# ---------------------------------------------------------------------------------------------------


def test_guard_passes_and_catches_regressions():
    d = harness.out_dir("sweep-guard")
    out = os.path.join(d, "out")
    rc, text = sweep(GUARD, "--out", out, "--check")
    print(text)
    assert rc == 0 and "check: 9 guarded run(s) as recorded" in text, text
    rows = {r["case"]: r for r in rows_of(out)}
    measured = num(rows["newmark_dt1e-3"]["tip.l2_rel"])
    with open(GUARD) as f:
        body = f.read().replace('scene = "../scenarios/beam_only.toml"', f'scene = "{BEAM}"')

    def guarded(recorded, name):
        value = recorded if not isinstance(recorded, dict) else \
            "{ " + ", ".join(f"{k} = {specs.toml_value(v)}" for k, v in recorded.items()) + " }"
        path = write(os.path.join(d, name + ".toml"), body + f'''
[[expect]]
where = {{ case = "newmark_dt1e-3" }}
"tip.l2_rel" = {value}
''')
        return sweep(path, "--out", out, "--check", "--resume", "--no-charts")

    # The measured value 15 % above the recorded one passes, 25 % above fails: the 20 % rule.
    rc, text = guarded(measured / 1.15, "loose")
    assert rc == 0, text
    assert text.count("(kept)") == 9, text  # --resume: nothing re-run, metrics recomputed
    rc, text = guarded(measured / 1.25, "tight")
    assert rc == 1, text
    assert re.search(r"check: FAIL newmark_dt1e-3: tip\.l2_rel = \S+, recorded \S+: \+25\.0 %", text), text
    # A fall passes as an improvement, unless the quantity is two-sided: then more than 20 % either way fails.
    rc, text = guarded(measured * 1.25, "fallen")
    assert rc == 0 and "improved on the recorded" in text, text
    rc, text = guarded({"value": measured * 1.3, "two_sided": True}, "fallen_two_sided")  # 23 % below
    assert rc == 1 and "moved by more than 0.2 of it" in text, text
    rc, text = guarded({"value": measured * 1.15, "two_sided": True}, "within_two_sided")
    assert rc == 0, text
    # A run expected to complete that does not.
    path = write(os.path.join(d, "starved.toml"), body + '''
[[case]]
name = "starved"
set = { "structure.formulation" = "corotational", "structure.point_loads[0].force" = [0.0, -7e5], "structure.newton.max_iterations" = 1 }
expect = { status = "completed" }
''')
    rc, text = sweep(path, "--out", out, "--check", "--only", "starved", "--no-charts")
    assert rc == 1 and "check: FAIL starved: status 'failed', expected 'completed'" in text, text


def test_sweep_file_mistakes_stop_before_running():
    d = harness.out_dir("sweep-bad")
    cases = {
        "unknown key": ('[sweep]\nscene = "{s}"\nscenery = 1\n[grid]\n"run.end_time" = [0.1]\n', "unknown key(s) 'scenery'"),
        "no scene": ('[sweep]\nscene = "nowhere.toml"\n[grid]\n"run.end_time" = [0.1]\n', "no such file"),
        "grid not an array": ('[sweep]\nscene = "{s}"\n[grid]\n"run.end_time" = 0.1\n', "expected a non-empty array"),
        "unknown metric": ('[sweep]\nscene = "{s}"\n[grid]\n"run.end_time" = [0.1]\n[[metric]]\nname = "magic"\n',
                           "unknown metric 'magic'"),
        "metric parameter": ('[sweep]\nscene = "{s}"\n[grid]\n"run.end_time" = [0.1]\n[[metric]]\n'
                             'name = "watchpoint_final"\nwatchpoint = "tip"\nexact = 1.0\ncomponant = "dy"\n',
                             "unknown parameter(s) componant"),
        "two references": ('[sweep]\nscene = "{s}"\n[[case]]\nreference = true\n[[case]]\nname = "b"\nreference = true\n',
                           "more than one [[case]] has reference = true"),
        # A key set by two axes ran with the last one's value under a label naming the other (a review).
        "two axes, one key": ('[sweep]\nscene = "{s}"\n[grid]\n"run.end_time" = [0.1, 0.2]\n[[grid.m]]\n'
                              'label = "short"\n"run.end_time" = 0.05\n',
                              "'run.end_time' is set by both 'run.end_time' and 'm'"),
        # Two bundles with the same keys: one of them vanished without a word.
        "equal bundles": ('[sweep]\nscene = "{s}"\n[[grid.m]]\nlabel = "A"\n"run.end_time" = 0.1\n'
                          '[[grid.m]]\nlabel = "B"\n"run.end_time" = 0.1\n', "two grid runs have the same settings"),
        # A misspelt fail_if column failed every probe: "neither end passes".
        "fail_if column": ('[sweep]\nscene = "{s}"\n[[case]]\nname = "a"\n[[metric]]\nname = "window_stat"\n'
                           'label = "it"\ncolumn = "iterations"\n[bisect]\nkey = "run.end_time"\nlow = 0.01\n'
                           'high = 0.1\nfail_if = { "it.valeu" = 3 }\n', "fail_if: 'it.valeu' is not a column"),
    }
    for name, (body, needle) in cases.items():
        path = write(os.path.join(d, name.replace(" ", "_") + ".toml"), body.replace("{s}", BEAM))
        rc, text = sweep(path, "--out", os.path.join(d, "out"))
        assert rc == 2 and needle in text, (name, rc, text)
    assert not os.listdir(os.path.join(d, "out", "runs")) if os.path.isdir(os.path.join(d, "out")) else True


def test_override_values_round_trip():
    import tomllib
    for v in [0.001, 1e-05, 2.0, 7, -3, True, "wcsph", [0.0, -9.81], 1e300, 'a "quoted" word']:
        text = specs.toml_value(v)
        assert tomllib.loads(f"v = {text}")["v"] == v, (v, text)
    assert specs.toml_value(2.0) == "2.0" and specs.toml_value(2) == "2"  # integers stay integers


# ---------------------------------------------------------------------------------------------------
# The dam-break metrics (surge front, column height) on records built by hand, then the surge front on the
# real fluid participant if it is built.


def write_fluid_frames(d, times, frames, dp):
    """A completed record holding only /frames/fluid (time, position, kind) and the fluid's dp: frames is a
    list of (positions n x 2, kinds n), padded to one length with wall particles far left."""
    import h5py
    import numpy as np
    n = max(len(p) for p, _ in frames)
    with h5py.File(os.path.join(d, "record.h5"), "w") as f:
        f.attrs["status"] = "completed"
        f.create_group("participants/fluid").attrs["dp"] = dp
        pos = f.create_dataset("frames/fluid/position", (len(times), n, 2), dtype="float64")
        kind = f.create_dataset("frames/fluid/kind", (len(times), n, 1), dtype="int32")
        f["frames/fluid/time"] = times
        for i, (p, k) in enumerate(frames):
            full_p = np.full((n, 2), -1.0)
            full_k = np.ones((n,), dtype=np.int32)
            full_p[:len(p)], full_k[:len(k)] = p, k
            pos[i] = full_p
            kind[i] = full_k[:, None]


def scaled_reference(t, t_ref, y_ref, factor):
    """factor times a reference curve at t, the curve extended to 1 / factor at t = 0 (so the scaled one
    starts at 1, the initial Z or Hn)."""
    import numpy as np
    return factor * np.interp(t, np.concatenate([[0.0], t_ref]), np.concatenate([[1.0 / factor], y_ref]))


def test_surge_front_metric_on_a_constructed_record():
    import numpy as np
    a, g, dp = 0.1, 9.81, 0.0025
    scale = math.sqrt(2 * g / a)
    Tref, Zref = metrics.read_reference_curve(MM_CSV)
    d = harness.out_dir("surge")
    # A fluid block whose front (last centre + dp/2) is 10 % ahead of the experiment at every reference T,
    # plus a lone droplet far ahead and wall particles further right, which must not count.
    T = np.concatenate([Tref[Tref <= 2.6], np.linspace(0.0, 2.6, 27)])
    T = np.unique(T)
    frames = []
    for Ti in T:
        Z = scaled_reference(Ti, Tref, Zref, 1.1)
        front = Z * a - dp / 2
        xs = np.arange(front, front - 0.05, -dp)
        ys = np.arange(dp / 2, 0.02, dp)
        block = np.array([(x, y) for x in xs for y in ys])
        droplet = np.array([[front + 10 * dp, 0.05]])
        wall = np.array([[0.6, y] for y in ys])
        frames.append((np.vstack([block, droplet, wall]),
                       np.array([0] * len(block) + [0] + [1] * len(wall), dtype=np.int32)))
    write_fluid_frames(d, T / scale, frames, dp)
    ctx = metrics.Context(metrics.RunInfo("r", d), [], harness.ROOT)
    out = metrics.compute("surge_front", d, {"a": a, "reference_csv": MM_CSV}, ctx)
    assert out["n_points"] == 9, out
    assert abs(out["mean_rel"] - 0.1) < 1e-9 and abs(out["max_rel"] - 0.1) < 1e-9, out
    assert abs(out["mean_signed_rel"] - 0.1) < 1e-9, out
    # Without the neighbour rule the droplet is taken for the front.
    bad = metrics.compute("surge_front", d, {"a": a, "reference_csv": MM_CSV, "k_neighbours": 0}, ctx)
    assert bad["max_rel"] > 0.15, bad
    # Frames that stop early (at T = 2.6) are reported, not extrapolated.
    expect_metric_error("surge_front", d, {"a": a, "reference_csv": MM_CSV, "T_max": 3.0}, ctx, "reach")


def test_column_height_metric_on_a_constructed_record():
    import numpy as np
    a, g, dp = 0.1, 9.81, 0.0025
    scale = math.sqrt(g / a)
    tref, href = metrics.read_reference_curve(MM_HEIGHT_CSV)
    d = harness.out_dir("height")
    # Water 5 % higher than the experiment at the back wall at every reference tau (top centre + dp/2), its
    # first column one spacing lower (the wall lag the two-column band looks past), a droplet above it and
    # a higher block beyond the band, neither of which may count.
    tau = np.unique(np.concatenate([tref[tref <= 2.6], np.linspace(0.0, 2.6, 27)]))
    frames = []
    for ti in tau:
        top = scaled_reference(ti, tref, href, 1.05) * 2 * a
        block = [(x, y) for x in np.arange(dp / 2, 10 * dp, dp) for y in np.arange(dp / 2, top - dp / 2 + 1e-12, dp)
                 if not (x < dp and y > top - dp)]
        block = np.array(block)
        block[:, 1] += (top - dp / 2) - block[:, 1].max()  # the highest centre exactly at top - dp/2
        droplet = np.array([[dp, top + 5 * dp]])
        beyond = np.array([[x, top + 3 * dp] for x in np.arange(5 * dp, 8 * dp, dp)])
        frames.append((np.vstack([block, droplet, beyond]), np.zeros(len(block) + 1 + len(beyond), dtype=np.int32)))
    write_fluid_frames(d, tau / scale, frames, dp)
    ctx = metrics.Context(metrics.RunInfo("r", d), [], harness.ROOT)
    out = metrics.compute("column_height", d, {"a": a, "reference_csv": MM_HEIGHT_CSV}, ctx)
    assert out["n_points"] == 11, out
    assert abs(out["mean_rel"] - 0.05) < 1e-9 and abs(out["max_rel"] - 0.05) < 1e-9, out
    assert abs(out["mean_signed_rel"] - 0.05) < 1e-9, out
    # Without the neighbour rule the droplet is taken for the top; with a one-column band, the lagging column.
    assert metrics.compute("column_height", d, {"a": a, "reference_csv": MM_HEIGHT_CSV,
                                                "k_neighbours": 0}, ctx)["max_rel"] > 0.06
    assert metrics.compute("column_height", d, {"a": a, "reference_csv": MM_HEIGHT_CSV,
                                                "band_dp": 1.0}, ctx)["mean_signed_rel"] < 0.05 - 1e-6
    # The frames stop at tau = 2.6.
    expect_metric_error("column_height", d, {"a": a, "reference_csv": MM_HEIGHT_CSV, "tau_max": 3.5}, ctx, "reach")


def test_wind_basin_metric_on_a_constructed_record():
    """A layer whose surface is tilted by the set-up (depth h(x) = D + b (x - 0.2), b = 3 tau / (2 rho g D),
    columns of 20 particles spaced h(x)/20 apart and dense in proportion), whose x-velocity is 0.9 times the
    closed-basin profile at the local depth and whose pressure holds the set-up gradient exactly:
    velocity_scale 0.9, l2_rel 0.1, setup_ratio 1, depth_ratio 1 (against the nominal depth, as this metric
    measured before 2026-11-26, the same record gave l2_rel 0.114). Particles outside the section (moving at
    1 m/s) and wall particles must not count."""
    import h5py
    import numpy as np
    tau, D, nu, rho0, g, dp, n = 5.0, 0.04, 1e-3, 1000.0, 9.81, 0.002, 20
    mu = rho0 * nu
    xs = np.arange(dp / 2, 0.4, dp)
    depth = D + 3 * tau / (2 * rho0 * g * D) * (xs - 0.2)
    fluid = np.array([(x, (k + 0.5) * h / n) for x, h in zip(xs, depth) for k in range(n)])
    fluid_rho = np.array([rho0 * dp * n / h for h in depth for _ in range(n)])
    wall = np.array([(x, -dp / 2) for x in xs])
    pos = np.vstack([fluid, wall])
    rho = np.concatenate([fluid_rho, np.full(len(wall), rho0)])
    kind = np.array([0] * len(fluid) + [1] * len(wall), dtype=np.int32)
    h = np.concatenate([np.repeat(depth, n), np.full(len(wall), D)])
    s = pos[:, 1] / h
    u = np.where((pos[:, 0] > 0.1) & (pos[:, 0] < 0.3), 0.9 * tau * h / (4 * mu) * (3 * s * s - 2 * s), 1.0)
    vel = np.stack([np.where(kind == 0, u, 0.0), np.zeros(len(pos))], axis=1)
    G = 3 * tau / (2 * D)
    pressure = rho0 * g * D + G * (pos[:, 0] - 0.2) - rho * g * pos[:, 1]
    d = harness.out_dir("wind-metric")
    times = [2.5, 3.0, 3.5, 4.0]
    with h5py.File(os.path.join(d, "record.h5"), "w") as f:
        f.attrs["status"] = "completed"
        f.create_group("participants/fluid").attrs["dp"] = dp
        f["frames/fluid/time"] = np.array(times)
        for name, value in (("position", pos), ("velocity", vel), ("kind", kind[:, None]),
                            ("pressure", pressure[:, None]), ("density", rho[:, None])):
            f[f"frames/fluid/{name}"] = np.stack([value] * len(times))
    ctx = metrics.Context(metrics.RunInfo("r", d), [], harness.ROOT)
    params = {"tau": tau, "depth": D, "nu": nu, "x_from": 0.1, "x_to": 0.3, "t_from": 3.0}
    out = metrics.compute("wind_basin_profile", d, params, ctx)
    assert out["frames"] == 3, out
    assert abs(out["velocity_scale"] - 0.9) < 1e-9 and abs(out["l2_rel"] - 0.1) < 1e-9, out
    assert abs(out["setup_ratio"] - 1.0) < 1e-6 and abs(out["depth_ratio"] - 1.0) < 1e-9, out
    expect_metric_error("wind_basin_profile", d, dict(params, t_from=5.0), ctx, "no frame")  # none after t = 4


def test_fluid_sweep_counts_particle_steps():
    assert os.path.isfile(os.path.join(harness.BIN, "sphfsi-fluid")), "the fluid participant is not built"
    d = harness.out_dir("sweep-fluid")
    scene = os.path.join(harness.ROOT, "scenarios", "dam_break.toml")
    path = write(os.path.join(d, "fluid.toml"), f'''
[sweep]
scene = "{scene}"
timeout_s = 120
threads_per_run = 1

[fixed]
"run.end_time" = 0.19
"run.output_interval" = 0.005

[grid]
"fluid.dp" = [0.01, 0.005]

[[metric]]
name = "surge_front"
label = "front"
a = 0.1
reference_csv = "{MM_CSV}"

[[metric]]
name = "max_density_error"
label = "density"
''')
    out = os.path.join(d, "out")
    rc, text = sweep(path, "--out", out, "--jobs", "2")
    print(text)
    assert rc == 0, text
    for r in rows_of(out):
        assert r["status"] == "completed", r
        with harness.record(os.path.join(out, "runs", r["run"], "record.h5")) as f:
            fluid_now = int((f["frames/fluid/kind"][0][:, 0] == 0).sum())
            substeps = int(f["windows/fluid_substeps"][:].sum())
        assert int(r["fluid_particles"]) == fluid_now
        assert int(r["particle_steps"]) == fluid_now * substeps == int(r["fluid_particles"]) * int(r["fluid_substeps"])
        assert int(r["front.n_points"]) == 9
        # What the columns must hold, not a validation (test_dam_break.cpp is): a mean error of the front under
        # 0.25 (these runs, with the scene's own settings, measure 0.073 at a/10 and 0.116 at a/20; the methods
        # sweep's runs 0.036 - 0.131, docs/validation.md). The density column is the fluid's per-step largest compression with the scene's
        # own settings (not the methods sweep's, whose WCSPH stays at 0.5 - 0.65 %): measured 3.3 % at a/10 and
        # 4.4 % at a/20 over the whole run (which ends at T = 2.7, before the surge meets the far wall); under 5 %.
        # (An earlier comment here quoted the sweep's 0.5 - 0.65 % for these runs; a review's suggested 1 %
        # bound failed on them.)
        assert 0 < num(r["front.mean_rel"]) < 0.25, r["front.mean_rel"]
        assert 0 < num(r["density.max"]) < 0.05, r["density.max"]


# ---------------------------------------------------------------------------------------------------


def test_docs_describe_every_column_and_metric():
    with open(os.path.join(harness.ROOT, "docs", "sweeps.md")) as f:
        doc = f.read()
    for col in results.RUN_COLUMNS:
        assert f"`{col}`" in doc, f"docs/sweeps.md does not describe the column {col}"
    for name in metrics.METRICS:
        assert f"`{name}`" in doc, f"docs/sweeps.md does not describe the metric {name}"
    for key in list(specs.SWEEP_KEYS) + list(specs.BISECT_KEYS):
        assert f"`{key}`" in doc, f"docs/sweeps.md does not describe the key {key}"


def test_every_repository_sweep_passes_check():
    """Each sweeps/*.toml loads, its metrics take their parameters and find their data files, and every run it
    would start (a bisection's at both ends of its range) passes `sphfsi check` with its overrides (the scene
    schema's checks; what a participant checks at start-up is not run here). The docs quote these files as the
    commands behind their tables; a renamed or re-ranged scene key, or a moved data file, must fail here, in
    seconds, not an hour into a documented sweep."""
    folder = os.path.join(harness.ROOT, "sweeps")
    names = sorted(n for n in os.listdir(folder) if n.endswith(".toml"))
    assert names, folder
    checked = 0
    for name in names:
        sw = specs.load(os.path.join(folder, name))
        ctx = metrics.Context(None, [], sw.dir)  # where tools/sweep.py resolves a metric's data files
        for m in sw.metrics:
            metrics.check_params(m["name"], m["params"])
            for key, value in m["params"].items():
                if key.endswith("_csv"):
                    assert os.path.isfile(ctx.resolve(value)), f"sweeps/{name}: {key} = {value}: no such file"
        ends = [[]]
        if sw.bisect is not None:
            b = sw.bisect
            ends = [[f"{b['key']}={specs.toml_value(b[end])}"] for end in ("low", "high")]
        for run in sw.runs:
            for extra in ends:
                args = [x for a in run.set_args() + extra for x in ("--set", a)]
                rc, text = harness.sphfsi("check", sw.scene, *args)
                assert rc == 0, f"sweeps/{name}, run {run.id} {extra}: {text}"
                checked += 1
    print(f"{len(names)} sweep files, {checked} runs checked")


FLUID_GUARD = os.path.join(harness.ROOT, "sweeps", "guard_fluid.toml")
COUPLED_GUARD = os.path.join(harness.ROOT, "sweeps", "guard_coupled.toml")


def test_fluid_guard_passes():
    rc, text = sweep(FLUID_GUARD, "--out", os.path.join(harness.out_dir("sweep-guard-fluid"), "out"), "--check", "--no-charts")
    assert rc == 0 and "check: 6 guarded run(s) as recorded" in text, text


def test_coupled_guard_passes():
    rc, text = sweep(COUPLED_GUARD, "--out", os.path.join(harness.out_dir("sweep-guard-coupled"), "out"), "--check",
                     "--no-charts")
    assert rc == 0 and "check: 3 guarded run(s) as recorded" in text, text


def test_added_mass_explicit_diverges_implicit_holds():
    """The added-mass map (docs/validation.md): a light, flexible plate under water. At mass ratio 0.01 serial
    explicit coupling diverges while Aitken with one window per fluid step stays stable; at 0.003 IQN-ILS over
    multi-rate windows stays stable. At 0.0003 Aitken with the structure sub-cycled in thesis windows diverges,
    and with one backward-Euler structure step per window (coupling.structure_steps = "window") Aitken and
    IQN-ILS hold, while explicit coupling on the same steps diverges already at 0.001. Stable: max |u - w| < |w|
    at mid-span from t = 5 ms on, w the static deflection (the undamped overshoot of the sudden load), with the
    mean deflection within half of w (a plate that never moved would sit at |u - w| = |w| exactly). The
    blow-ups are stopped by the total energy check ("coupling diverged", docs/coupling.md)."""
    scene = os.path.join(harness.ROOT, "tests", "integration", "scenes", "swap_builtin.toml")
    d = harness.out_dir("added-mass")
    w = -1.7517857e-5

    def run(name, rho, *extra):
        out = os.path.join(d, name)
        code, msg = harness.sphfsi("run", scene, "--out", out, "--quiet", "--set", "structure.material.E=7.0e8",
                                   "--set", f"structure.material.rho={rho}",
                                   "--set", "structure.members[0].interface_padding=[0.0, 0.03]", *extra, timeout=240)
        if code != 0:
            return code, msg, float("inf")
        with open(os.path.join(out, "watchpoints.csv")) as f:
            dy = [float(r["dy"]) for r in csv.DictReader(f) if r["name"] == "mid" and float(r["time"]) >= 0.005]
        # A plate that never moved (a coupling that delivers no force) would sit exactly at |u - w| = |w|: it
        # must carry the load too, its mean deflection within half of w (the step response swings about w).
        mean = sum(dy) / len(dy)
        assert abs(mean / w - 1) < 0.5, (name, mean, w)
        return code, msg, max(abs(u - w) / abs(w) for u in dy)

    code, msg, dev = run("explicit", 100.0)
    assert code == 1 and "coupling diverged" in msg, (code, dev, msg)
    code, msg, dev = run("aitken", 100.0, "--set", 'coupling.scheme="implicit-aitken"')
    assert code == 0 and dev < 1.0, (code, dev, msg)
    code, msg, dev = run("iqn", 30.0, "--set", 'coupling.scheme="implicit-iqn-ils"', "--set", 'coupling.window="multi-rate"',
                         "--set", "coupling.max_fluid_steps=10")
    assert code == 0 and dev < 1.0, (code, dev, msg)

    aitken, iqn = ("--set", 'coupling.scheme="implicit-aitken"'), ("--set", 'coupling.scheme="implicit-iqn-ils"')
    one_step = ("--set", 'coupling.structure_steps="window"', "--set", 'structure.time.integrator="backward_euler"')
    code, msg, dev = run("aitken-sub-cycled-3e-4", 3.0, *aitken)
    assert code == 1 and "coupling diverged" in msg, (code, dev, msg)
    assert "coupling.structure_steps" in msg, msg  # the energy check names the remedy
    for name, scheme in (("aitken", aitken), ("iqn", iqn)):
        code, msg, dev = run(f"{name}-one-step-3e-4", 3.0, *scheme, *one_step)
        assert code == 0 and dev < 1.0, (name, code, dev, msg)
        assert "warning: coupling.structure_steps" not in msg, msg
    code, msg, dev = run("explicit-one-step-1e-3", 10.0, *one_step)
    assert code == 1 and "coupling diverged" in msg, (code, dev, msg)
    # One step per window with the structure's default integrator (generalized-alpha) is warned about.
    code, msg, dev = run("aitken-one-gen-alpha-step", 10000.0, *aitken, "--set", 'coupling.structure_steps="window"',
                         "--set", "run.end_time=0.01")
    assert code == 0 and 'warning: coupling.structure_steps = "window" is meant with' in msg, (code, msg)


if __name__ == "__main__":
    harness.main(globals())
