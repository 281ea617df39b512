"""Coupled runs end to end: every scene in scenarios/ at a coarse resolution (issue 5: each runs in a test
and starts only the participants it needs), and the swap test: the Python participant written from
docs/protocol.md and sphfsi-structure run the same coupled scene through the same coordinator."""
import csv
import os
import tomllib

import harness

SCENARIOS = os.path.join(harness.ROOT, "scenarios")

# Coarse settings that keep each scene to seconds; the stated resolutions run by hand (docs/validation.md).
COARSE = {
    "beam_only": ["run.end_time=0.1"],
    "fluid_only": ["run.end_time=0.05", "fluid.dp=0.02"],
    "dam_break": ["run.end_time=0.05", "fluid.dp=0.005"],
    "elastic_gate": ["run.end_time=0.05", "fluid.dp=0.004"],
    "elastic_obstacle": ["run.end_time=0.2", "fluid.dp=0.008"],
    "hydrostatic_plate": ["run.end_time=0.05", "fluid.dp=0.05"],
    "wind_basin": ["run.end_time=0.05", "fluid.dp=0.008"],
}


def run_coarse(name):
    out = harness.out_dir(name)
    args = ["run", os.path.join(SCENARIOS, name + ".toml"), "--out", out, "--quiet"]
    for s in COARSE[name]:
        args += ["--set", s]
    harness.sphfsi(*args, check=0, timeout=240)
    return out


def roles_in(out):
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f.attrs["status"] == "completed", f.attrs["status"]
        return sorted(f["participants"].keys())


def test_every_scenario_has_a_coarse_run():
    names = sorted(f[:-5] for f in os.listdir(SCENARIOS) if f.endswith(".toml"))
    assert names == sorted(COARSE), f"scenarios without a coarse run here: {set(names) ^ set(COARSE)}"


def test_structure_alone_starts_only_the_structure():
    assert roles_in(run_coarse("beam_only")) == ["structure"]


def test_fluid_alone_starts_only_the_fluid():
    assert roles_in(run_coarse("fluid_only")) == ["fluid"]
    out = run_coarse("dam_break")
    assert roles_in(out) == ["fluid"]
    # The dye (issue 4, point 9): the column's halves carry tags 0 (left) and 1 (right) in every frame, so
    # mixing can be seen. At the last frame the right half leads the surge along the floor.
    with harness.record(os.path.join(out, "record.h5")) as f:
        kind, tag, pos = f["frames/fluid/kind"], f["frames/fluid/tag"], f["frames/fluid/position"]
        for k in range(kind.shape[0]):
            fluid = kind[k][:, 0] == 0
            tags = tag[k][fluid, 0]
            assert sorted(set(tags.tolist())) == [0, 1] and (tags == 0).sum() == (tags == 1).sum(), k
            if k == 0:
                x0 = pos[0][fluid, 0]
                assert x0[tags == 0].max() < x0[tags == 1].min()  # split at the middle
        x = pos[-1][kind[-1][:, 0] == 0, 0]
        last = tag[-1][kind[-1][:, 0] == 0, 0]
        assert x[last == 1].max() > x[last == 0].max()
    out = run_coarse("wind_basin")
    assert roles_in(out) == ["fluid"]
    # The wind acts on the whole surface (surface_stress.hpp): tau times the recorded surface is its force.
    # On the initial lattice the shares add up to the tank's 0.4 m exactly; at the window's end, t = 0.05 s,
    # they were 1 - 1.5e-4 of it. Tolerance 0.5 % = 2 mm, a quarter of one particle's 8 mm share (a whole
    # share is 2 % of the length).
    with harness.record(os.path.join(out, "record.h5")) as f:
        carried = f["windows/fluid.wind_surface_length"][...]
        assert len(carried) > 0 and all(abs(c / 0.4 - 1) < 0.005 for c in carried), carried.tolist()


def test_coupled_scenes_run_end_to_end():
    for name in ("elastic_gate", "elastic_obstacle", "hydrostatic_plate"):
        out = run_coarse(name)
        assert roles_in(out) == ["fluid", "structure"]
        with open(os.path.join(out, "watchpoints.csv")) as fh:
            rows = list(csv.DictReader(fh))
        assert rows and float(rows[-1]["time"]) > 0
        with harness.record(os.path.join(out, "record.h5")) as f:
            n = f["interface/vertices"].shape[0]
            assert f["interface/force"].shape[1:] == (n, 2)
            assert f["frames/fluid/position"].shape[0] == f["frames/structure/displacement"].shape[0]
            # The run's cost figures (docs/record.md): the time loop holds every window, and the coordinator's
            # CPU time in it is part of the process's.
            a = f.attrs
            assert a["loop_wall_s"] >= a["wall_s"] > 0, (a["loop_wall_s"], a["wall_s"])
            assert 0 < a["coordinator_loop_cpu_s"] <= a["coordinator_cpu_s"]
            assert 0 <= a["messaging_and_waiting_s"] <= a["wall_s"]


def test_messaging_is_timed_to_each_replys_arrival_under_parallel_explicit():
    """Parallel-explicit sends both ADVANCEs and collects the fluid's reply first: the structure's round trip
    was timed when it was collected, so it held the fluid's compute time, and the summed messaging came out
    above the run's wall time (0.294 s against 0.204 s, a review, 2026-11-27)."""
    out = harness.out_dir("parallel-messaging")
    harness.sphfsi("run", os.path.join(harness.SCENES, "swap_python.toml"), "--out", out, "--quiet", "--set",
                   "coupling.scheme=parallel-explicit", "--set", "run.end_time=0.02", check=0, timeout=120)
    with harness.record(os.path.join(out, "record.h5")) as f:
        a = f.attrs
        assert 0 <= a["messaging_and_waiting_s"] <= a["wall_s"], (a["messaging_and_waiting_s"], a["wall_s"])
        w = f["windows"]
        assert (w["structure_roundtrip_s"][:] <= w["wall_s"][:] + 1e-9).all()
        assert (w["messaging_s"][:] <= w["wall_s"][:] + 1e-9).all()  # the overlapping waits counted once


def shared_sections(path):
    with open(path, "rb") as fh:
        scene = tomllib.load(fh)
    return {k: scene[k] for k in ("run", "coupling", "fluid")}


def settled(out, name):
    with open(os.path.join(out, "watchpoints.csv")) as fh:
        rows = [r for r in csv.DictReader(fh) if r["name"] == name and float(r["time"]) >= 0.3]
    return sum(float(r["dy"]) for r in rows) / len(rows)


def test_swap_python_and_builtin_structure_in_the_same_scene():
    py = os.path.join(harness.SCENES, "swap_python.toml")
    cpp = os.path.join(harness.SCENES, "swap_builtin.toml")
    assert shared_sections(py) == shared_sections(cpp), "the two swap scenes must differ only in the structure"
    out_py, out_cpp = harness.out_dir("swap-py"), harness.out_dir("swap-cpp")
    harness.sphfsi("run", py, "--out", out_py, "--quiet", check=0, timeout=240)
    harness.sphfsi("run", cpp, "--out", out_cpp, "--quiet", check=0, timeout=240)
    with harness.record(os.path.join(out_py, "record.h5")) as f:
        assert "rigid_plate.py" in f["participants/structure"].attrs["software"]
    with harness.record(os.path.join(out_cpp, "record.h5")) as f:
        assert "sphfsi-structure" in f["participants/structure"].attrs["software"]
        # READY info keeps its numbers' types: counts are integers (they were float64 before 2026-11-29).
        fluid, structure = f["participants/fluid"].attrs, f["participants/structure"].attrs
        assert fluid["particles"].dtype.kind == "i" and structure["elements"].dtype.kind == "i", \
            (fluid["particles"].dtype, structure["elements"].dtype)
        assert fluid["dp"].dtype.kind == "f" and f.attrs["protocol_version"].dtype.kind == "i"
    # Both carry the water's weight. Tolerance 10 %: the coarse SPH column (20 particles deep) still
    # oscillates acoustically after 0.3 s, and the wall pressure of SPH at this spacing is good to a few %.
    y_py = settled(out_py, "mid")
    expected_py = -1000 * 9.81 * 0.2 * 0.2 / 3.924e5
    w_cpp = settled(out_cpp, "mid")
    expected_cpp = -1962.0 * 0.2 ** 4 / (384 * 70e9 * 0.02 ** 3 / 12)
    print(f"rigid plate: {y_py:.4e} m vs {expected_py:.4e} m; beam: {w_cpp:.4e} m vs {expected_cpp:.4e} m")
    assert abs(y_py / expected_py - 1) < 0.10
    assert abs(w_cpp / expected_cpp - 1) < 0.10



def test_every_coupling_scheme_and_window_rule_carries_the_load():
    """Each scheme and window rule runs the Python plate under water, converges in every window
    (implicit schemes, at a tolerance tight enough to need iterations) and ends near the serial-explicit
    result; SAVE/RESTORE are exercised on both participants."""
    py = os.path.join(harness.SCENES, "swap_python.toml")
    common = ["--quiet", "--set", "run.end_time=0.1"]
    results = {}
    for label, sets in {
        "serial": ["coupling.scheme=serial-explicit"],
        "parallel": ["coupling.scheme=parallel-explicit"],
        "fixed": ["coupling.scheme=implicit-fixed", "coupling.tolerance_rel=1e-6", "coupling.max_iterations=100"],
        "aitken": ["coupling.scheme=implicit-aitken", "coupling.tolerance_rel=1e-6"],
        "iqn": ["coupling.scheme=implicit-iqn-ils", "coupling.tolerance_rel=1e-6"],
        "multirate": ["coupling.window=multi-rate", "coupling.max_fluid_steps=4"],
    }.items():
        out = harness.out_dir("scheme-" + label)
        args = ["run", py, "--out", out, *common]
        for s in sets:
            args += ["--set", s]
        harness.sphfsi(*args, check=0, timeout=240)
        with harness.record(os.path.join(out, "record.h5")) as f:
            w = f["windows"]
            assert (w["converged"][:] == 1).all(), label
            iterations = w["iterations"][:]
            if label in ("fixed", "aitken", "iqn"):
                assert iterations.max() >= 2, f"{label}: never iterated"
            if label == "multirate":
                assert (w["rule"][:] == 1).all() and w["fluid_substeps"][:].max() > 1
            # Interface energy balance (docs/coupling.md): a converged implicit window moves the fluid's side
            # of the interface where the structure's went, so it creates (almost) no energy. Measured at this
            # tolerance: at most 1.2e-6 of the work done on the structure, against 2e-4 to 5e-3 for the
            # explicit schemes; bounded at 1e-4, which tells the two apart.
            work, created = f.attrs["interface_work"], f.attrs["interface_energy_created"]
            assert abs(w["interface_work"][:].sum() - work) <= 1e-9 * abs(work), label
            if label in ("fixed", "aitken", "iqn"):
                assert abs(created) <= 1e-4 * abs(work), (label, created, work)
            results[label] = (f["interface/displacement"][-1][:, 1].mean(), iterations.mean(), len(iterations),
                              created / work)
    base = results["serial"][0]
    for label, (dy, iters, windows, created) in results.items():
        print(f"{label:10s} dy = {dy:.4e} m, {iters:.2f} iterations per window, {windows} windows, "
              f"energy created at the interface {created:+.2e} of the work on the structure")
        # All schemes solve the same problem; they differ by the explicit schemes' lag of a window (O(dt)) and
        # the implicit ones' tolerance: measured 0.15 - 0.18 % from serial-explicit (2026-11-27). 1 % tells a
        # consistent scheme from one that loses or doubles a force (tens of per cent).
        assert abs(dy / base - 1) < 0.01, label


def test_the_work_booked_at_the_interface_is_the_work_the_structure_reports():
    """The coordinator books each window's work on the structure, F_s . du_s with F_s the force it sent the
    structure (docs/coupling.md, "Interface energy balance"); the built-in structure sums its own external
    work from the forces it received. Reference: the two must agree, window by window. Tolerance 1e-6 of the
    largest work: the structure books nodal forces and moments against nodal displacements and rotations,
    which equals the vertices' work through their rigid links to second order in the rotation (measured
    8e-9 of it). parallel-explicit sends the structure the previous window's force; its balance once used
    the new one and was 1.7e-2 off."""
    scene = os.path.join(harness.SCENES, "swap_builtin.toml")
    for scheme in ("serial-explicit", "parallel-explicit", "implicit-aitken"):
        out = harness.out_dir("work-" + scheme)
        harness.sphfsi("run", scene, "--out", out, "--quiet", "--set", "run.end_time=0.1",
                       "--set", f'coupling.scheme="{scheme}"', check=0, timeout=120)
        with harness.record(os.path.join(out, "record.h5")) as f:
            w = f["windows"]
            booked, reported = w["interface_work"][:].cumsum(), w["structure.external_work"][:]
            gap = abs(booked - reported).max()
            print(f"{scheme}: work on the structure {reported[-1]:.6e} J/m, booked {booked[-1]:.6e}, "
                  f"largest gap {gap:.1e} of {abs(reported).max():.1e}")
            assert gap <= 1e-6 * abs(reported).max(), (scheme, gap)


def test_added_mass_blow_ups_are_stopped_by_the_energy_checks():
    """The plate under water made 100 times more flexible and 100 times lighter than the steel of
    swap_builtin.toml (mass ratio 0.01): serial-explicit coupling blows up (fluid at 9 m/s in a tank at
    rest) while each participant stays within its own bounds. Two checks stop it (docs/coupling.md):
    - the interface balance alone (the total check off): the created energy passes the fluid's mechanical
      energy at t = 0.157 s;
    - the total mechanical energy of fluid and structure, which without external work can only fall: it
      rises by more than 5 % of the fluid's energy within a few windows, with the linear predictor and
      without one (whose blow-up the interface balance does not see: it ran to the end before).
    The same plate 3 times heavier (mass ratio 0.03) is stable and completes, creating 3 % of that energy
    at the interface and gaining less than 0.1 % in total."""
    scene = os.path.join(harness.SCENES, "swap_builtin.toml")
    common = ["--quiet", "--set", "structure.material.E=7.0e8", "--set",
              "structure.members[0].interface_padding=[0.0, 0.03]", "--set", "coupling.scheme=serial-explicit"]

    def energies(w):
        fluid = w["fluid.kinetic_energy"][:] + w["fluid.potential_energy"][:]
        return fluid, fluid + w["structure.kinetic_energy"][:] + w["structure.strain_energy"][:]

    out = harness.out_dir("energy-blow-up-interface")
    code, text = harness.sphfsi("run", scene, "--out", out, "--set", "structure.material.rho=100",
                                "--set", "coupling.max_energy_gain=0", *common, timeout=240)
    assert code != 0 and "coupling diverged" in text and "interface vertex" in text, text
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f.attrs["status"].startswith("failed: coupling diverged"), f.attrs["status"]
        w = f["windows"]
        fluid, _ = energies(w)
        assert w["interface_energy_created"][:].sum() > fluid[0]
        assert w["t"][-1] < 0.25, w["t"][-1]  # named while the run is young, not at its end (0.4 s)
    for predictor in ("linear", "none"):
        out = harness.out_dir(f"energy-blow-up-total-{predictor}")
        code, text = harness.sphfsi("run", scene, "--out", out, "--set", "structure.material.rho=100",
                                    "--set", f"coupling.predictor={predictor}", *common, timeout=240)
        assert code != 0 and "coupling diverged" in text and "more mechanical energy" in text, (predictor, text)
        with harness.record(os.path.join(out, "record.h5")) as f:
            w = f["windows"]
            fluid, total = energies(w)
            print(f"mass ratio 0.01, predictor {predictor}: stopped at t = {w['t'][-1]:.4f} s, total energy "
                  f"{(total[-1] - total[0]) / fluid[0]:+.3f} of the fluid's")
            assert total[-1] - total[0] > 0.05 * fluid[0]
            assert w["t"][-1] < 0.05, w["t"][-1]
    out = harness.out_dir("energy-stable")
    harness.sphfsi("run", scene, "--out", out, "--set", "structure.material.rho=300", *common, check=0, timeout=240)
    with harness.record(os.path.join(out, "record.h5")) as f:
        w = f["windows"]
        fluid, total = energies(w)
        created = f.attrs["interface_energy_created"]
        gain = (total.max() - total[0]) / fluid[0]
        print(f"mass ratio 0.03: created {created:.3g} J/m of the fluid's {fluid[0]:.3g} J/m; largest total gain "
              f"{gain:.2e} of it")
        assert 0 < created < 0.1 * fluid[0]
        assert gain < 0.01


def test_a_structures_own_loads_are_not_counted_as_a_coupling_gain():
    """A point load on the plate does work from outside the pair, as wind would: the total check takes it out
    (the structure's external_work less the interface's work). Before 2026-11-27 this stable run (the plate of
    swap_builtin.toml 100 times more flexible, 10 kN at its middle) stopped as 'coupling diverged' in its 4th
    window, its structure holding 8.65 J/m of the load's work against the 0.073 J/m the interface had done."""
    scene = os.path.join(harness.SCENES, "swap_builtin.toml")
    out = harness.out_dir("energy-point-load")
    code, text = harness.sphfsi("run", scene, "--out", out, "--quiet", "--set", "structure.material.E=7.0e8",
                                "--set", "structure.point_loads=[{at=[0.1, 0.09], force=[0.0, -10000.0]}]",
                                "--set", "run.end_time=0.03", timeout=240)
    assert code == 0, text
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f.attrs["status"] == "completed"
        w = f["windows"]
        load_work = w["structure.external_work"][-1] - w["interface_work"][:].sum()
        fluid = w["fluid.kinetic_energy"][0] + w["fluid.potential_energy"][0]
        print(f"the load's work {load_work:.3g} J/m against the 5 % bound's {0.05 * fluid:.3g} J/m")
        assert load_work > 0.05 * fluid, load_work  # enough to have tripped the check without the correction


def test_a_body_force_along_a_periodic_axis_is_not_counted_as_a_coupling_gain():
    """Gravity along a periodic axis drives the channel as a pressure gradient would: the water's potential
    energy jumps by m g L whenever it crosses the seam. The total check treats it as external work (as wind);
    without that this stable run stopped as 'coupling diverged' at t = 0.18 s. The fluid's energy must in fact
    have risen past the check's bound, or the test shows nothing."""
    scene = os.path.join(harness.SCENES, "periodic_channel_post.toml")
    out = harness.out_dir("energy-periodic-channel")
    code, text = harness.sphfsi("run", scene, "--out", out, "--quiet", timeout=240)
    assert code == 0, text
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f.attrs["status"] == "completed"
        w = f["windows"]
        fluid = w["fluid.kinetic_energy"][:] + w["fluid.potential_energy"][:]
        print(f"fluid energy {fluid[0]:.3f} -> {fluid.max():.3f} J/m (the bound: +{0.05 * fluid[0]:.3f})")
        assert fluid.max() - fluid[0] > 0.05 * fluid[0]


def test_a_window_that_ends_the_run_is_recorded_with_its_watchpoints():
    """coupling.on_max_iterations = "error" ends the run on a window that did not converge; before 2026-11-27
    the window was lost from the record (its residual and iteration count are what tell why), and a window
    that tripped the energy checks was recorded without its watchpoint row."""
    scene = os.path.join(harness.SCENES, "swap_builtin.toml")
    out = harness.out_dir("stop-on-cap")
    code, text = harness.sphfsi("run", scene, "--out", out, "--quiet", "--set", "coupling.scheme=implicit-fixed",
                                "--set", "coupling.max_iterations=1", "--set", "coupling.tolerance_rel=1e-12",
                                "--set", "coupling.tolerance_abs=0", "--set", "coupling.on_max_iterations=error",
                                timeout=120)
    assert code != 0 and "coupling did not converge" in text, text
    with harness.record(os.path.join(out, "record.h5")) as f:
        w = f["windows"]
        assert w["t"].shape[0] == 1 and w["converged"][0] == 0 and w["iterations"][0] == 1, w["t"][:]
        assert w["residual"][0] > 0
    with open(os.path.join(out, "watchpoints.csv")) as csv:
        rows = [line for line in csv.read().splitlines()[1:] if line]
    assert len({row.split(",")[0] for row in rows}) == 2, rows  # t0 and the window that ended the run
    out = harness.out_dir("stop-on-energy")
    code, text = harness.sphfsi("run", scene, "--out", out, "--quiet", "--set", "structure.material.E=7.0e8",
                                "--set", "structure.material.rho=100", "--set",
                                "structure.members[0].interface_padding=[0.0, 0.03]", timeout=240)
    assert code != 0 and "coupling diverged" in text, text
    with harness.record(os.path.join(out, "record.h5")) as f:
        windows = f["windows/t"].shape[0]
    with open(os.path.join(out, "watchpoints.csv")) as csv:
        rows = [line for line in csv.read().splitlines()[1:] if line]
    assert len({row.split(",")[0] for row in rows}) == windows + 1, (windows, rows[-3:])


def test_no_sliver_of_a_window_before_an_output_time():
    """Windows of 1 ms with output times a hair off their multiples (0.01000000001 s): before 2026-11-27 the
    leftover became a window of 1e-11 s whose fluid force was 25 times the force around it, and the quadratic
    predictor, which divides by the last window's length, made the interface create 0.6 J/m and moved the
    plate by 25 %. The rest before an output time is now split into two equal windows, and the run agrees
    with the one whose output times are the window multiples: the same largest energy created in a window
    (the first's, 2.2e-4 J/m) and the same final deflection to 1e-4 of it (measured 4e-6)."""
    scene = os.path.join(harness.SCENES, "swap_builtin.toml")
    results = {}
    for interval in ("0.01", "0.01000000001"):
        out = harness.out_dir("sliver")
        harness.sphfsi("run", scene, "--out", out, "--quiet", "--set", "coupling.window=fixed", "--set",
                       "coupling.window_dt=1e-3", "--set", "coupling.predictor=quadratic", "--set",
                       f"run.output_interval={interval}", "--set", "run.end_time=0.014", check=0, timeout=120)
        with harness.record(os.path.join(out, "record.h5")) as f:
            w = f["windows"]
            assert abs(w["t"][-1] - 0.014) < 1e-12
            results[interval] = (w["dt"][:].min(), abs(w["interface_energy_created"][:]).max(),
                                 f["interface/displacement"][-1, :, 1].min())
    (dt0, created0, deflection0), (dt1, created1, deflection1) = results["0.01"], results["0.01000000001"]
    assert dt1 >= 0.5e-3 * (1 - 1e-9), dt1
    assert created1 <= 1.01 * created0, (created1, created0)
    assert abs(deflection1 - deflection0) <= 1e-4 * abs(deflection0), (deflection1, deflection0)
    # Two stops a hair apart (an output time just before the end) are one: no window of 1e-11 s between them,
    # and one frame there, not two (a review of the fix above found both).
    out = harness.out_dir("sliver-end")
    harness.sphfsi("run", scene, "--out", out, "--quiet", "--set", "coupling.window=fixed", "--set",
                   "coupling.window_dt=1e-3", "--set", "coupling.predictor=quadratic", "--set",
                   "run.output_interval=0.01", "--set", "run.end_time=0.01000000001", check=0, timeout=120)
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f["windows/dt"][:].min() >= 1e-3 * (1 - 1e-6), f["windows/dt"][-3:]
        assert len(f["frames/fluid/time"]) == 2, f["frames/fluid/time"][:]


def quad_distance(p, quad):
    """Distance from point p to a convex quad (0 inside)."""
    import numpy as np
    inside = True
    best = float("inf")
    for i in range(4):
        a, b = quad[i], quad[(i + 1) % 4]
        edge, rel = b - a, p - a
        if edge[0] * rel[1] - edge[1] * rel[0] < 0:
            inside = False
        s = min(1.0, max(0.0, float(np.dot(rel, edge) / np.dot(edge, edge))))
        best = min(best, float(np.linalg.norm(rel - s * edge)))
    return 0.0 if inside else best


def test_solid_particles_follow_the_structure():
    """Every solid particle of the fluid sits inside the structure's deformed cross-section, to a
    fraction of the spacing, at every frame of a coarse elastic-gate run (the explicit scheme's
    predictor error is the only allowed lag)."""
    import numpy as np
    out = run_coarse("elastic_gate")
    dp = 0.004
    with harness.record(os.path.join(out, "record.h5")) as f:
        vertices = f["interface/vertices"][:]
        cells = f["interface/cells"][:]
        t_windows = f["windows/t"][:]
        disp = f["interface/displacement"]
        worst = 0.0
        for k, t in enumerate(f["frames/fluid/time"][:]):
            if t == 0:
                continue
            w = int(np.argmin(abs(t_windows - t)))
            current = vertices + disp[w]
            pos = f["frames/fluid/position"][k]
            solid = pos[f["frames/fluid/kind"][k][:, 0] == 2]
            assert len(solid) > 0
            for p in solid:
                worst = max(worst, min(quad_distance(p, current[c]) for c in cells))
    print(f"largest distance of a solid particle outside the deformed gate: {worst:.2e} m = {worst / dp:.3f} dp")
    assert worst < 0.1 * dp


def test_a_deformed_start_reaches_the_fluid_and_the_watchpoints_at_t0():
    """protocol 2: a structure that starts deflected (structure.initial.mode) passes its interface state at t0
    in READY, and the coordinator passes it on to the fluid in INIT. Before, both took the interface to be
    undeformed at t0: the watchpoint read 0 and the solid particles jumped by the whole deflection at the end
    of the first window."""
    import numpy as np
    out = harness.out_dir("deformed-start")
    amplitude, dp = 0.004, 0.008  # half a spacing at the tip: the old jump fails the 0.1 dp bound below
    harness.sphfsi("run", os.path.join(SCENARIOS, "elastic_obstacle.toml"), "--out", out, "--quiet",
                   "--set", f"fluid.dp={dp}", "--set", "run.end_time=0.002", "--set", "run.output_interval=0.002",
                   "--set", "structure.initial.mode=1", "--set", f"structure.initial.mode_amplitude={amplitude}",
                   check=0, timeout=240)
    with open(os.path.join(out, "watchpoints.csv")) as fh:
        first = next(csv.DictReader(fh))
    # The watchpoint is the cantilever's tip, where the mode's largest translation is: exactly the amplitude.
    assert float(first["time"]) == 0 and abs(abs(float(first["dx"])) - amplitude) < 1e-12, first
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f["frames/fluid/time"][0] == 0
        # Where the first window left the structure (a tenth of a millisecond on: it has barely moved).
        current = f["interface/vertices"][:] + f["interface/displacement"][0]
        cells = f["interface/cells"][:]
        pos = f["frames/fluid/position"][0]
        solid = pos[f["frames/fluid/kind"][0][:, 0] == 2]
        worst = max(min(quad_distance(p, current[c]) for c in cells) for p in solid)
    print(f"t = 0: largest distance of a solid particle outside the deflected obstacle: {worst / dp:.4f} dp")
    assert worst < 0.1 * dp
    # Deflected into the water (the gate's tip 3 mm, 0.75 dp, towards the column): the fluid clears the water
    # within dp/2 of the deflected faces. Keeping what lay outside the cross-section but closer blew the first
    # step up (a particle at 41 m/s against max_mach * c0 = 17 m/s).
    out = harness.out_dir("deformed-start-gate")
    code, text = harness.sphfsi("run", os.path.join(SCENARIOS, "elastic_gate.toml"), "--out", out, "--quiet",
                                "--set", "fluid.dp=0.004", "--set", "run.end_time=0.01", "--set", "structure.initial.mode=1",
                                "--set", "structure.initial.mode_amplitude=0.003", timeout=240)
    assert code == 0, text


def test_a_protocol_1_fluid_is_not_started_from_a_deformed_structure():
    # Protocol 1 cannot pass the interface state at t0: such a fluid would put the structure where it is not.
    misbehaving = os.path.join(harness.ROOT, "tests", "participants", "misbehaving.py")
    out = harness.out_dir("deformed-start-v1-fluid")
    code, text = harness.sphfsi("run", os.path.join(SCENARIOS, "elastic_obstacle.toml"), "--out", out, "--quiet",
                                "--set", f'participants.fluid="/usr/bin/python3 {misbehaving}"',
                                "--set", "structure.initial.mode=1", "--set", "structure.initial.mode_amplitude=0.002",
                                env={"MISBEHAVE": "fluid_v1"}, timeout=60)
    assert code == 1 and "fluid speaks protocol 1, which cannot start from the structure's deformed" in text, text


def test_hydrostatic_plate_settles_to_plate_theory():
    """issue 5: the plate under a 2 m water column (Fourey et al. 2017) settles to
    w = -(rho_f g H + rho_s g t) L^4 / (384 D), D = E t^3 / (12 (1 - nu^2)), within 5 %. The weakly
    compressible column keeps ringing acoustically (period 4 H / c0 = 0.13 s, about +-13 % at dp = 0.04),
    so "settles" is judged on the mean over the last half second: eight periods of that ringing."""
    out = harness.out_dir("hydrostatic-plate")
    harness.sphfsi("run", os.path.join(SCENARIOS, "hydrostatic_plate.toml"), "--out", out, "--quiet",
                   "--set", "fluid.dp=0.04", check=0, timeout=300)
    E, nu, t, L = 67.5e9, 0.34, 0.05, 1.0
    D = E * t ** 3 / (12 * (1 - nu ** 2))
    w = -(1000 * 9.81 * 2.0 + 2700 * 9.81 * t) * L ** 4 / (384 * D)
    with open(os.path.join(out, "watchpoints.csv")) as fh:
        late = [float(r["dy"]) for r in csv.DictReader(fh) if float(r["time"]) >= 0.5]
    mean = sum(late) / len(late)
    print(f"mid-span deflection, mean over [0.5, 1] s: {mean:.4e} m; plate theory {w:.4e} m ({mean / w - 1:+.2%})")
    assert abs(mean / w - 1) < 0.05



def test_elastic_obstacle_follows_the_published_simulations_through_the_impact():
    """The dam break against an elastic obstacle (Walhorn et al. 2005) at the scene's default dp = 4 mm, to
    t = 0.5 s: the obstacle's top-right corner against the two published simulations of
    scenarios/reference/obstacle_tip_dx_*.csv (Meduri et al. 2017, Ryzhakov et al. 2010; there is no experiment).
    Tolerance: the RMS difference over the references' points to 0.5 s within 0.12 of each reference's peak,
    about as close as the references are to each other (0.095 and 0.114); the peak between 0.95 x the lower
    and 1.05 x the higher reference peak (41.0, 49.1 mm), within 10 ms of their 0.235 s. Measured 2026-11-27:
    0.072 and 0.097; 46.0 mm at 0.234 s (docs/validation.md, "Elastic obstacle"). With the obstacle 6 mm
    upstream, as the scene had it until then, the peak came at 0.215 s and the run failed the timing bound and
    the RMS bound against Ryzhakov et al. (0.131)."""
    import numpy as np
    out = harness.out_dir("elastic-obstacle")
    harness.sphfsi("run", os.path.join(SCENARIOS, "elastic_obstacle.toml"), "--out", out, "--quiet",
                   "--set", "run.end_time=0.5", check=0, timeout=300)
    with open(os.path.join(out, "watchpoints.csv")) as fh:
        rows = [r for r in csv.DictReader(fh) if r["name"] == "corner"]
    t = np.array([float(r["time"]) for r in rows])
    dx = np.array([float(r["dx"]) for r in rows])
    peaks = []
    for name in ("meduri2017", "ryzhakov2010"):
        with open(os.path.join(SCENARIOS, "reference", f"obstacle_tip_dx_{name}.csv")) as fh:
            data = np.array([[float(v) for v in line.split(",")] for line in fh
                             if not line.startswith("#") and not line.startswith("t,")])
        peaks.append(data[:, 1].max())
        impact = data[data[:, 0] <= 0.5]
        rms = float(np.sqrt(np.mean((np.interp(impact[:, 0], t, dx) - impact[:, 1]) ** 2))) / peaks[-1]
        print(f"corner against {name} to t = 0.5 s: RMS {rms:.3f} of its peak ({1e3 * peaks[-1]:.1f} mm)")
        assert rms <= 0.12, (name, rms)
    k = int(np.argmax(dx))
    print(f"corner peak {1e3 * dx[k]:.1f} mm at t = {t[k]:.3f} s")
    assert 0.95 * min(peaks) <= dx[k] <= 1.05 * max(peaks), dx[k]
    assert abs(t[k] - 0.235) <= 0.010, t[k]


def test_xdmf_sidecar_points_at_the_frames():
    """record.xdmf is well-formed XDMF 3 whose every HDF5 reference names a dataset of record.h5 with the
    dimensions it claims, one grid per fluid frame (what ParaView needs to open the frames)."""
    import xml.etree.ElementTree as ET
    out = run_coarse("elastic_gate")
    root = ET.parse(os.path.join(out, "record.xdmf")).getroot()
    grids = root.findall("./Domain/Grid/Grid")
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert len(grids) == f["frames/fluid/time"].shape[0]
        for grid in grids:
            for item in grid.iter("DataItem"):
                if item.get("Format") != "HDF":
                    continue
                file_name, path = item.text.strip().split(":", 1)
                assert file_name == "record.h5"
                dims = tuple(int(x) for x in item.get("Dimensions").split())
                shape = f[path].shape
                assert shape == dims or shape + (1,) == dims, (path, shape, dims)
        times = [float(g.find("Time").get("Value")) for g in grids]
        assert times == sorted(times)



if __name__ == "__main__":
    harness.main(globals())
