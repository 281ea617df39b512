"""A structure run alone under a prescribed load, with the Python participant written from
docs/protocol.md only. Its response is compared with the SDOF oscillator's analytic step response."""
import csv
import math
import os

import harness
from rigid_plate import step_response

SCENE = os.path.join(harness.SCENES, "rigid_plate_step.toml")
M, K, C, F = 10.0, 4000.0, 40.0, -100.0  # as in the scene


def test_step_response_matches_analytic():
    out = harness.out_dir("plate")
    harness.sphfsi("run", SCENE, "--out", out, "--quiet", check=0)
    # The participant integrates exactly and the coordinator spreads the load exactly: agreement is to
    # round-off, so the tolerance is 1e-9 of the static deflection.
    static = abs(F / K)
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f.attrs["status"] == "completed"
        t = f["frames/structure/time"][:]
        y = f["frames/structure/y"][:].ravel()
        assert len(t) == 41, len(t)
        worst = max(abs(yy - step_response(tt, M, C, K, F)) for tt, yy in zip(t, y))
        assert worst < 1e-9 * static, worst
        # Under a constant load the coordinator asks for one window per output interval (40 over 2 s) and
        # the participant sub-steps at its dt_max = 2 ms inside them: 1000 steps in all.
        assert f["windows/t"].shape[0] == 40
        assert f["windows/structure_substeps"][:].sum() == 1000
    with open(os.path.join(out, "watchpoints.csv")) as fh:
        rows = list(csv.DictReader(fh))
    last = rows[-1]
    assert last["name"] == "centre"
    assert abs(float(last["dy"]) - step_response(2.0, M, C, K, F)) < 1e-9 * static
    print(f"max |y - y_analytic| = {worst:.2e} m (static deflection {static} m)")


def test_a_displaced_start_is_recorded_from_t0():
    """protocol 2: the plate reports its state at t0 in READY, so the watchpoint starts at y_initial instead of
    0 (protocol 1 has no field for it); the response is the step response plus the free decay from y0."""
    out = harness.out_dir("plate-displaced")
    y0 = 0.01
    harness.sphfsi("run", SCENE, "--out", out, "--quiet", "--set", f"structure.y_initial={y0}", check=0)
    w = math.sqrt(K / M)
    zeta = C / (2 * math.sqrt(K * M))
    wd = w * math.sqrt(1 - zeta * zeta)

    def expected(t):
        free = y0 * math.exp(-zeta * w * t) * (math.cos(wd * t) + zeta * w / wd * math.sin(wd * t))
        return step_response(t, M, C, K, F) + free

    with open(os.path.join(out, "watchpoints.csv")) as fh:
        rows = list(csv.DictReader(fh))
    assert float(rows[0]["time"]) == 0 and float(rows[0]["dy"]) == y0, rows[0]
    worst = max(abs(float(r["dy"]) - expected(float(r["time"]))) for r in rows)
    assert worst < 1e-9 * abs(F / K), worst  # the participant integrates exactly, as in the step test


def sine_response(t, m, c, k, F, f):
    """Displacement of m y'' + c y' + k y = F sin(2 pi f t) from rest at t = 0: the steady harmonic part plus
    the damped free vibration that starts it from rest."""
    w, wn = 2 * math.pi * f, math.sqrt(k / m)
    zeta = c / (2 * math.sqrt(k * m))
    wd = wn * math.sqrt(1 - zeta * zeta)
    D = (k - m * w * w) ** 2 + (c * w) ** 2
    A, B = F * (k - m * w * w) / D, -F * c * w / D  # y_p = A sin wt + B cos wt
    c1 = -B
    c2 = (zeta * wn * c1 - A * w) / wd
    return A * math.sin(w * t) + B * math.cos(w * t) + math.exp(-zeta * wn * t) * (c1 * math.cos(wd * t) + c2 * math.sin(wd * t))


def test_a_sine_load_above_the_structures_step_rate_is_not_aliased():
    """[load] is sampled once per window at its midpoint. At the plate's own 2 ms step a 400 Hz sine was read as
    100 Hz (above half the step rate a frequency folds back), and the plate moved four times as far as it should;
    windows are now at most 1/20 of the load's period. Reference: the SDOF's analytic response to the sine from
    rest. Tolerance 1 % of its largest displacement: a midpoint sample held over 1/20 of a period carries the
    sine's first harmonic at sin(pi/20)/(pi/20) = 0.996 of its amplitude, and the participant integrates each
    window exactly."""
    out = harness.out_dir("plate-sine")
    f_load, end = 400.0, 0.2
    harness.sphfsi("run", SCENE, "--out", out, "--quiet", "--set", 'load.profile="sine"',
                   "--set", f"load.frequency={f_load}", "--set", f"run.end_time={end}", "--set", "run.output_interval=0.01",
                   check=0, timeout=120)
    with open(os.path.join(out, "watchpoints.csv")) as fh:
        rows = list(csv.DictReader(fh))
    t = [float(r["time"]) for r in rows]
    y = [float(r["dy"]) for r in rows]
    exact = [sine_response(tt, M, C, K, F, f_load) for tt in t]
    scale = max(abs(e) for e in exact)
    worst = max(abs(a - b) for a, b in zip(y, exact))
    assert worst < 0.01 * scale, (worst, scale)
    assert abs(t[-1] - end) < 1e-12 and len(t) >= 20 * f_load * end, (t[-1], len(t))
    print(f"400 Hz sine: max |y - y_analytic| = {worst:.2e} m of {scale:.2e} m")


def test_set_override_changes_the_run():
    out = harness.out_dir("plate-set")
    harness.sphfsi("run", SCENE, "--out", out, "--quiet", "--set", "load.force=[0.0, -200.0]", "--set", "run.end_time=0.5",
                   check=0)
    with harness.record(os.path.join(out, "record.h5")) as f:
        y = f["frames/structure/y"][-1, 0, 0]
        t = f["frames/structure/time"][-1]
        assert abs(t - 0.5) < 1e-12
        assert abs(y - step_response(0.5, M, C, K, -200.0)) < 1e-9 * 0.05
        assert f.attrs["overrides"].split("\n") == ["load.force=[0.0, -200.0]", "run.end_time=0.5"]  # one per line


def test_an_earlier_record_is_replaced_only_on_request():
    out = harness.out_dir("plate-again")
    harness.sphfsi("run", SCENE, "--out", out, "--quiet", "--set", "run.end_time=0.5", check=0)
    kept = {name: open(os.path.join(out, name), "rb").read() for name in ("record.h5", "watchpoints.csv", "run.log")}
    # A re-run into the same folder is refused before it touches anything: it might fail at once (a participant
    # that cannot start), and the first run's files would be gone.
    code, text = harness.sphfsi("run", SCENE, "--out", out, "--quiet", "--set", "run.end_time=0.25")
    assert code == 2 and "already holds a run's record" in text and "--overwrite" in text, text
    for name, content in kept.items():
        assert open(os.path.join(out, name), "rb").read() == content, name
    harness.sphfsi("run", SCENE, "--out", out, "--quiet", "--overwrite", "--set", "run.end_time=0.25", check=0)
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f.attrs["status"] == "completed" and abs(f["frames/structure/time"][-1] - 0.25) < 1e-12
    code, text = harness.sphfsi("run", "--resume", out, "--overwrite")
    assert code == 2 and "--overwrite would discard it" in text, text


def test_a_watchpoint_off_the_structure_is_refused():
    # Outside its nearest interface cell a point follows that cell's nearest edge; 49 m off is a typo, not a point
    # of the structure, and used to be recorded as if it were one.
    out = harness.out_dir("plate-far-watchpoint")
    code, text = harness.sphfsi("run", SCENE, "--out", out, "--quiet", "--set", "watchpoint[0].x=50.0")
    assert code != 0 and "watchpoint 'centre': (50.000000, 0.025000) m lies 49.000000 m from the structure's" in text, text


def test_check_validates_without_running():
    code, text = harness.sphfsi("check", SCENE)
    assert code == 0 and "valid" in text, text


def test_a_structure_with_nothing_wetted_runs_alone():
    """A structure alone may publish no interface (no wetted member): the run records an empty mesh and no
    interface rows. Before 2026-11-27 HDF5 refused to chunk the empty mesh and the run failed at its start
    ("cannot create dataset /interface/vertices"). A watchpoint needs a wetted surface, which the scene check
    says before anything starts (before 2026-11-27 the structure was started first)."""
    scene = os.path.join(harness.ROOT, "scenarios", "beam_only.toml")
    dry = ["--set", "structure.members[0].wetted=false", "--set", "run.end_time=0.1"]
    out = harness.out_dir("nothing-wetted")
    code, text = harness.sphfsi("run", scene, "--out", out, "--quiet", *dry, "--set", "watchpoint=[]", timeout=60)
    assert code == 0, text
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f.attrs["status"] == "completed"
        assert f["interface/vertices"].shape == (0, 2) and f["interface/cells"].shape == (0, 4)
        assert f["windows/t"].shape[0] == 10 and f["frames/structure/displacement"].shape[0] == 11
    watched = harness.out_dir("nothing-wetted-watched")
    code, text = harness.sphfsi("run", scene, "--out", watched, "--quiet", *dry, timeout=60)
    assert code != 0 and "key 'watchpoint[0]': watchpoints follow the wetted interface" in text, text
    assert "connected" not in text and not os.path.exists(os.path.join(watched, "record.h5")), text


def test_the_end_is_recorded_when_it_is_not_an_output_time():
    """The last frame holds the state at run.end_time, also when end_time is not a multiple of the output
    interval: before 2026-11-27 the run's result was then only in the window rows (beam_only to 0.05 s every
    0.02 s recorded frames at 0, 0.02 and 0.04 s; with output_interval 0.1 s, frame 0 alone)."""
    scene = os.path.join(harness.ROOT, "scenarios", "beam_only.toml")
    for interval, frames in ((0.02, [0.0, 0.02, 0.04, 0.05]), (0.1, [0.0, 0.05])):
        out = harness.out_dir("end-frame")
        harness.sphfsi("run", scene, "--out", out, "--quiet", "--set", "run.end_time=0.05", "--set",
                       f"run.output_interval={interval}", check=0, timeout=60)
        with harness.record(os.path.join(out, "record.h5")) as f:
            times = list(f["frames/structure/time"][:])
            assert len(times) == len(frames) and all(abs(a - b) < 1e-12 for a, b in zip(times, frames)), times
            assert abs(f["windows/t"][-1] - 0.05) < 1e-12


def test_frames_keep_their_times_and_no_window_passes_the_end():
    """Two stops a sliver apart are taken as one (test_coupled.py), but never past the end and never by moving a
    frame onto a checkpoint's time: before a review on 2026-11-27, an output time a sliver past the end pulled
    the last window there (beam_only to 0.05 s every 0.0101 s ended at 0.0505 s, "completed", with no frame at
    0.05 s), and checkpoints every 0.0101 s moved the frames due every 0.01 s onto them. A structure alone
    counts slivers in its own steps (a quarter of its 1.7e-4 s here), so 1e-4 s apart are two stops; and in the
    output interval where that is shorter: frames every 2e-5 s to 1 ms are 51, none folded into the end's (a
    review of the first version found 49)."""
    scene = os.path.join(harness.ROOT, "scenarios", "beam_only.toml")
    cases = ((["run.output_interval=0.0101"], [0.0, 0.0101, 0.0202, 0.0303, 0.0404, 0.05]),
             (["run.output_interval=0.01", "run.checkpoint_interval=0.0101"], [0.0, 0.01, 0.02, 0.03, 0.04, 0.05]))
    cases += ((["run.end_time=0.001", "run.output_interval=2e-5"], [k * 2e-5 for k in range(51)]),)
    # Under a sine [load] the windows are at most 1/20 of its period, shorter than the structure's step, and
    # the sliver is counted in them: the frame due 0.4 ms before the end was folded into the end's by the
    # step's sliver, and the shorter windows recorded it at 0.10001 s (a review, 2026-11-27).
    plate = os.path.join(harness.SCENES, "rigid_plate_long.toml")
    cases += ((["run.end_time=0.1004", "run.output_interval=0.01", "load.frequency=384.615"],
               [k * 0.01 for k in range(11)] + [0.1004], plate),)
    for settings, frames, *other in cases:
        out = harness.out_dir("stops")
        harness.sphfsi("run", other[0] if other else scene, "--out", out, "--quiet", "--set", "run.end_time=0.05",
                       *[a for s in settings for a in ("--set", s)], check=0, timeout=60)
        with harness.record(os.path.join(out, "record.h5")) as f:
            times = list(f["frames/structure/time"][:])
            assert f.attrs["status"] == "completed", f.attrs["status"]
            assert len(times) == len(frames) and all(abs(a - b) < 1e-12 for a, b in zip(times, frames)), (settings, times)
            assert max(f["windows/t"][:]) <= frames[-1] * (1 + 1e-12), (settings, f["windows/t"][-3:])


def test_an_integrator_creating_energy_stops_the_run():
    """Newmark and generalized-alpha are unconditionally stable for linear problems only. The co-rotational
    cantilever of sweeps/stability_corotational.toml (P L^2/EI = 2 applied suddenly, undamped, to 0.3 s) at
    Newmark's 5.0e-4 s step ended "completed" before 2026-11-27 (a review), its kinetic and strain energy grown
    to 29 kJ against 1.6 kJ of load work, the created energy 7 times larger every 0.05 s. The structure now
    stops the run when the energy created passes failure.max_energy_created = 0.1 of the largest energy it has
    had or been given, naming step, time and energies; it then also records it as the run's failure. The
    check is what stops it (off, the same run completes with 0.12 of that scale created, measured from its
    window rows), and a step half that size completes with under 1e-3 created (measured 3e-4 at most)."""
    scene = os.path.join(harness.ROOT, "scenarios", "beam_only.toml")
    settings = ["run.end_time=0.3", "structure.formulation=corotational", "structure.point_loads[0].force=[0.0, -2.8e5]",
                "structure.damping.model=none", "structure.time.resolved_modes=1", "structure.time.steps_per_period=2",
                "structure.time.integrator=newmark"]
    args = [a for s in settings for a in ("--set", s)]

    def created(f):
        w = f["windows"]
        motion, work = w["structure.kinetic_energy"][:] + w["structure.strain_energy"][:], w["structure.external_work"][:]
        scale = max(max(abs(x) for x in work), max(motion))
        return max(m - x for m, x in zip(motion, work)) / scale

    out = harness.out_dir("energy-created")
    code, text = harness.sphfsi("run", scene, "--out", out, "--quiet", *args, "--set", "structure.time.dt_max=5e-4", timeout=60)
    assert code != 0 and "energy created" in text and "above failure.max_energy_created = 0.1" in text, text
    assert "structure: step " in text and ", t=0.2" in text, text
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert "energy created" in f.attrs["status"], f.attrs["status"]
    out = harness.out_dir("energy-created-off")
    harness.sphfsi("run", scene, "--out", out, "--quiet", *args, "--set", "structure.time.dt_max=5e-4",
                   "--set", "structure.failure.max_energy_created=0", check=0, timeout=60)
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f.attrs["status"] == "completed" and created(f) > 0.1, created(f)
    out = harness.out_dir("energy-created-fine")
    harness.sphfsi("run", scene, "--out", out, "--quiet", *args, "--set", "structure.time.dt_max=2.5e-4", check=0, timeout=60)
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f.attrs["status"] == "completed" and created(f) < 1e-3, created(f)


if __name__ == "__main__":
    harness.main(globals())
