"""Resume: a run killed after a checkpoint and continued with `sphfsi run --resume DIR` ends in the same
state as an uninterrupted run, to 1e-10 relative (issue 5's criterion; both runs take the same windows,
so the only allowed difference is none at all, and the bound leaves room for nothing but round-off)."""
import os
import shutil
import signal
import subprocess
import time

import numpy as np

import harness

SCENE = os.path.join(harness.ROOT, "scenarios", "beam_only.toml")
SETTINGS = ["--set", "run.end_time=3.0", "--set", "run.checkpoint_interval=0.5", "--set", "run.output_interval=0.05"]


def kill_after_first_checkpoint(scene, settings, name):
    """Starts the scene and SIGKILLs the coordinator as soon as a checkpoint exists; returns the output folder."""
    cut = harness.out_dir(name)
    run = harness.Running("run", scene, "--out", cut, "--quiet", *settings)
    checkpoint = os.path.join(cut, "checkpoint.bin")
    deadline = time.time() + 120
    while not os.path.exists(checkpoint) and time.time() < deadline and run.proc.poll() is None:
        time.sleep(0.01)
    assert os.path.exists(checkpoint), "no checkpoint was written"
    run.proc.send_signal(signal.SIGKILL)
    run.proc.wait(timeout=10)
    return cut


def killed_after_first_checkpoint(scene, settings, name):
    """kill_after_first_checkpoint, then resumed to the end; returns the output folder."""
    cut = kill_after_first_checkpoint(scene, settings, name)
    code, text = harness.sphfsi("run", "--resume", cut, "--quiet", timeout=240)
    assert code == 0, text
    assert "resumed at t = " in text, text
    return cut


def final_state(out):
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f.attrs["status"] == "completed", f.attrs["status"]
        return (f["frames/structure/time"][:], f["frames/structure/displacement"][:], f["frames/structure/velocity"][:],
                f["windows/t"][:])


def test_resumed_run_matches_uninterrupted_run():
    full = harness.out_dir("resume-full")
    harness.sphfsi("run", SCENE, "--out", full, "--quiet", *SETTINGS, check=0, timeout=120)

    cut = kill_after_first_checkpoint(SCENE, SETTINGS, "resume-cut")
    # A kill can cut watchpoints.csv's last row short; "0." reads as a time before the checkpoint, and a
    # resume once kept it as a row of its own.
    csv_path = os.path.join(cut, "watchpoints.csv")
    with open(csv_path) as f:
        text = f.read()
    with open(csv_path, "w") as f:
        f.write(text + "0.")
    code, text = harness.sphfsi("run", "--resume", cut, "--quiet", timeout=240)
    assert code == 0 and "resumed at t = " in text, text
    with open(os.path.join(full, "watchpoints.csv")) as a, open(csv_path) as b:
        assert a.read() == b.read(), "the resumed run's watchpoints differ from the uninterrupted run's"

    t_a, d_a, v_a, w_a = final_state(full)
    t_b, d_b, v_b, w_b = final_state(cut)
    assert np.array_equal(t_a, t_b), "frame times differ"
    assert np.array_equal(w_a, w_b), "the resumed run took different windows"
    scale = np.abs(d_a[-1]).max()
    err = np.abs(d_a[-1] - d_b[-1]).max() / scale
    verr = np.abs(v_a[-1] - v_b[-1]).max() / np.abs(v_a[-1]).max()
    print(f"final displacement differs by {err:.1e} relative, velocity by {verr:.1e}")
    assert err <= 1e-10 and verr <= 1e-10
    # every frame, not only the last: the record of the resumed run is one clean history
    assert np.abs(d_a - d_b).max() <= 1e-10 * scale


def test_resumed_coupled_run_matches_uninterrupted_run():
    """The same for a coupled run: the elastic gate, coarse, killed after its first checkpoint; also started
    deflected into its water (the fluid clears the water around the deflected gate, and must do so again on the
    resume, or its particle count no longer matches the checkpoint)."""
    scene = os.path.join(harness.ROOT, "scenarios", "elastic_gate.toml")
    settings = ["--set", "fluid.dp=0.004", "--set", "run.end_time=0.06", "--set", "run.checkpoint_interval=0.02",
                "--set", "run.output_interval=0.005"]
    deflected = ["--set", "structure.initial.mode=1", "--set", "structure.initial.mode_amplitude=0.003"]
    for name, extra in (("gate", []), ("deflected-gate", deflected)):
        full = harness.out_dir(f"resume-{name}-full")
        harness.sphfsi("run", scene, "--out", full, "--quiet", *settings, *extra, check=0, timeout=240)
        cut = killed_after_first_checkpoint(scene, settings + extra, f"resume-{name}-cut")
        with harness.record(os.path.join(full, "record.h5")) as a, harness.record(os.path.join(cut, "record.h5")) as b:
            assert b.attrs["status"] == "completed"
            assert np.array_equal(a["windows/t"][:], b["windows/t"][:]), "the resumed run took different windows"
            for path in ("frames/fluid/position", "frames/fluid/velocity", "frames/structure/displacement"):
                x, y = a[path][-1], b[path][-1]
                err = np.abs(x - y).max() / max(np.abs(x).max(), 1e-300)
                print(f"{name}: {path}: final frames differ by {err:.1e} relative")
                assert err <= 1e-10, (name, path)


def test_a_resumed_iqn_ils_run_iterates_as_the_uninterrupted_one():
    """IQN-ILS reuses the secant pairs of earlier windows (coupling.iqn_reuse = 8): the checkpoint keeps them.
    Before 2026-11-27 it did not (a review), and the resumed run iterated along another path: the plate under
    water of sweeps/stability_added_mass.toml at mass ratio 0.1, where IQN-ILS takes 2 - 5 iterations per
    window, ended with other iteration counts and states after the resume."""
    scene = os.path.join(harness.ROOT, "tests", "integration", "scenes", "swap_builtin.toml")
    settings = ["--set", "structure.material.E=7.0e8", "--set", "structure.members[0].interface_padding=[0.0, 0.03]",
                "--set", "structure.material.rho=100.0", "--set", "coupling.scheme=implicit-iqn-ils",
                "--set", "run.end_time=0.03", "--set", "run.checkpoint_interval=0.01", "--set", "run.output_interval=0.005"]
    full = harness.out_dir("resume-iqn-full")
    harness.sphfsi("run", scene, "--out", full, "--quiet", *settings, check=0, timeout=240)
    cut = killed_after_first_checkpoint(scene, settings, "resume-iqn-cut")
    with harness.record(os.path.join(full, "record.h5")) as a, harness.record(os.path.join(cut, "record.h5")) as b:
        assert b.attrs["status"] == "completed"
        assert np.array_equal(a["windows/t"][:], b["windows/t"][:]), "the resumed run took different windows"
        assert np.array_equal(a["windows/iterations"][:], b["windows/iterations"][:]), "other iteration counts"
        # Pairs are kept by windows of 3 or more iterations: some before the checkpoint at 0.01 s must have them.
        before = a["windows/t"][:] <= 0.01 + 1e-12
        assert a["windows/iterations"][:][before].max() >= 3, "no window before the checkpoint kept pairs"
        for path in ("frames/fluid/position", "frames/fluid/velocity", "frames/structure/displacement"):
            assert np.array_equal(a[path][-1], b[path][-1]), path + ": the final frames differ"


def fluid_history(out, until):
    """The fluid frames' times and positions up to time `until`, from out/record.h5 (which must open)."""
    with harness.record(os.path.join(out, "record.h5")) as f:
        times = f["frames/fluid/time"][:]
        keep = int(np.count_nonzero(times <= until * (1 + 1e-12)))
        return times[:keep], f["frames/fluid/position"][:keep]


def test_a_resume_stopped_at_any_moment_keeps_the_history():
    """A resume copies the interrupted run's record up to the checkpoint into a new file and only then
    replaces record.h5 with it. So a resume killed at any moment, and a second resume started while one
    runs (refused: one run per output directory), leave record.h5 readable with every frame up to the
    checkpoint. Builds before 2026-11-25 renamed record.h5 away first: a resume killed during the copy,
    followed by another, produced a "completed" record without the first half of the run. The record here
    is ~10 MB, so the copy takes tens of milliseconds and the kill delays below fall before, in and after it."""
    scene = os.path.join(harness.ROOT, "scenarios", "dam_break.toml")
    settings = ["--set", "fluid.dp=0.004", "--set", "run.end_time=0.2", "--set", "run.output_interval=0.0005",
                "--set", "run.checkpoint_interval=0.05"]
    cut = kill_after_first_checkpoint(scene, settings, "resume-killed")
    checkpoint_t = 0.05
    times, positions = fluid_history(cut, checkpoint_t)
    assert times.size > 90 and abs(times[-1] - checkpoint_t) < 1e-9, times[-3:]

    in_copy = 0  # kills that left the resume's copy behind: during the copy or before it took over
    copy = os.path.join(cut, "record.h5.resuming")

    def copy_stamp():  # a copy left by an earlier kill stays until a later resume replaces it
        return os.stat(copy).st_mtime_ns if os.path.exists(copy) else None

    # Later delays too, so that a loaded machine, whose copy starts later, still has kills inside it.
    for delay in (0.0, 0.01, 0.03, 0.06, 0.1, 0.15, 0.2, 0.3, 0.4, 0.6, 1.0):
        before = copy_stamp()
        resume = harness.Running("run", "--resume", cut, "--quiet")
        time.sleep(delay)
        resume.proc.send_signal(signal.SIGKILL)
        resume.proc.wait(timeout=10)
        copy_left = copy_stamp() not in (None, before)
        in_copy += copy_left
        t, x = fluid_history(cut, checkpoint_t)
        print(f"resume killed after {delay:.2f} s{' (its copy left behind)' if copy_left else ''}: {t.size} frames "
              f"up to the checkpoint, as before: {np.array_equal(t, times) and np.array_equal(x, positions)}")
        assert np.array_equal(t, times) and np.array_equal(x, positions), f"history lost (kill after {delay} s)"
    # The delays must have caught the copy at least once, or this test showed nothing about it (a review:
    # on a slow machine every kill could fall before it).
    assert in_copy > 0, "no kill landed while the resume's copy existed"

    # A resume continues the run as it was, where it was: it takes no overrides and no other folder.
    code, text = harness.sphfsi("run", "--resume", cut, "--set", "fluid.dp=0.01")
    assert code == 2 and "--set cannot change it" in text, text
    code, text = harness.sphfsi("run", "--resume", cut, "--out", harness.out_dir("resume-elsewhere"))
    assert code == 2 and "give no --out" in text, text

    first = harness.Running("run", "--resume", cut, "--quiet")
    first.wait_for("resumed at t = ", timeout=60)
    code, text = harness.sphfsi("run", "--resume", cut, "--quiet", timeout=60)
    assert code == 1 and "in use by another sphfsi run" in text, (code, text)
    code, text = first.finish(timeout=120)
    assert code == 0, text
    t, x = fluid_history(cut, 1.0)
    assert np.array_equal(t[:times.size], times) and np.array_equal(x[:times.size], positions)
    assert t.size == 401 and np.all(np.diff(t) > 0) and abs(t[-1] - 0.2) < 1e-9, (t.size, t[-3:])


def test_a_resume_that_stops_before_catching_up_leaves_the_record_as_it_was():
    """The interrupted record goes on past its last checkpoint; a resume copies it up to the checkpoint and the
    copy replaces record.h5 only once the resumed run has reached where the record ended. Before a review on
    2026-11-27 the copy replaced it at once, so a resume that then failed (here: no participant programs beside
    the coordinator) left the record cut back to the checkpoint for good: frames 21 -> 11 of beam_only to 1 s,
    with its interface totals and loop times zero. Now record.h5 and watchpoints.csv stay byte for byte, no
    copy is left behind, and a resume that can run still completes the record."""
    out = harness.out_dir("resume-fails")
    harness.sphfsi("run", SCENE, "--out", out, "--quiet", "--set", "run.end_time=1.0", "--set",
                   "run.checkpoint_interval=0.5", "--set", "run.output_interval=0.05", check=0, timeout=60)
    import h5py
    with h5py.File(os.path.join(out, "record.h5"), "r+", locking=False) as f:
        f.attrs["status"] = "running"  # as a run killed after its checkpoint at 0.5 s leaves it, 0.5 s later
    before = {}
    for name in ("record.h5", "watchpoints.csv"):
        with open(os.path.join(out, name), "rb") as f:
            before[name] = f.read()
    alone = harness.out_dir("coordinator-alone")
    shutil.copy(os.path.join(harness.BIN, "sphfsi"), alone)
    p = subprocess.run([os.path.join(alone, "sphfsi"), "run", "--resume", out, "--quiet"], capture_output=True,
                       text=True, timeout=60)
    assert p.returncode == 1 and "where the interrupted run's record ends" in p.stderr, (p.returncode, p.stderr)
    for name, data in before.items():
        with open(os.path.join(out, name), "rb") as f:
            assert f.read() == data, f"{name} changed"
    left = sorted(n for n in os.listdir(out) if n.endswith(".resuming"))
    assert not left, left
    code, text = harness.sphfsi("run", "--resume", out, "--quiet", timeout=60)
    assert code == 0, text
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f.attrs["status"] == "completed" and f["frames/structure/time"].shape[0] == 21


def test_a_completed_resume_whose_sidecar_cannot_be_written_says_so_in_its_status():
    """A resume writes the XDMF sidecar only once its copy has replaced record.h5 (until then the sidecar
    describes the interrupted record). A copy that takes over only when the run completes (the interrupted
    record reaches past where the resumed run ends; here its last window row is edited to 0.06 s of a 0.05 s
    run) wrote it after the status "completed" was set, and a failure escaped as an exception with
    "completed" on file and nothing in run.log (a review, 2026-11-27; seen so). Now the copy takes over before
    the status is set, and a sidecar that cannot be written (a directory stands where its temporary file
    goes) makes the status "failed: ..." with the history whole."""
    out = harness.out_dir("resume-sidecar")
    scene = os.path.join(harness.ROOT, "scenarios", "fluid_only.toml")
    harness.sphfsi("run", scene, "--out", out, "--quiet", "--set", "run.end_time=0.05", "--set",
                   "run.checkpoint_interval=0.02", "--set", "run.output_interval=0.01", check=0, timeout=60)
    import h5py
    with h5py.File(os.path.join(out, "record.h5"), "r+", locking=False) as f:
        f.attrs["status"] = "running"  # as a run killed at its end, after its last checkpoint, leaves it
        f["windows/t"][-1] = 0.06
        frames = f["frames/fluid/time"].shape[0]
    os.makedirs(os.path.join(out, "record.xdmf.tmp"))
    code, text = harness.sphfsi("run", "--resume", out, "--quiet", timeout=60)
    assert code == 1 and "cannot write the XDMF sidecar" in text, (code, text)
    with open(os.path.join(out, "run.log")) as f:
        assert "error: cannot write the XDMF sidecar" in f.read()
    assert not [n for n in os.listdir(out) if n.endswith(".resuming")], os.listdir(out)
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f.attrs["status"].startswith("failed: cannot write the XDMF sidecar"), f.attrs["status"]
        assert "resumed_by" in f.attrs and f["frames/fluid/time"].shape[0] == frames


def killed_at_a_rename(args, to, count, when, timeout=60):
    """Runs sphfsi with kill_at_write.so, which SIGKILLs it just `when` ("before" or "after") its `count`-th
    rename onto a path ending in `to`."""
    env = dict(os.environ, LD_PRELOAD=os.path.join(harness.BIN, "kill_at_write.so"), SPHFSI_KILL_AT_RENAME_TO=to,
               SPHFSI_KILL_AT_RENAME_COUNT=str(count), SPHFSI_KILL_AT_RENAME_WHEN=when)
    p = subprocess.run([os.path.join(harness.BIN, "sphfsi"), *args], capture_output=True, text=True, env=env,
                       timeout=timeout)
    assert p.returncode == -signal.SIGKILL, (p.returncode, p.stderr)


def test_a_resumed_copy_that_cannot_take_over_is_kept():
    """A resume whose copy has caught up with record.h5 and cannot be renamed over it (here the rename fails
    with EIO) holds all of the run in that copy; the run stops there. The rename was tried a second time,
    logged twice, and the copy then removed as if the run had stopped short of the interrupted record (a
    review, 2026-11-28). Now the failure is the status, said once, the copy is kept as record.h5.resuming and
    named, the watchpoints' copy still takes over, and record.h5 is as the interrupted run left it."""
    out = kill_after_first_checkpoint(SCENE, SETTINGS, "resume-rename-fails")
    record = os.path.join(out, "record.h5")
    before = os.stat(record).st_ino
    env = dict(os.environ, LD_PRELOAD=os.path.join(harness.BIN, "kill_at_write.so"), SPHFSI_KILL_AT_RENAME_TO="record.h5",
               SPHFSI_KILL_AT_RENAME_WHEN="fail")
    p = subprocess.run([os.path.join(harness.BIN, "sphfsi"), "run", "--resume", out, "--quiet"], capture_output=True,
                       text=True, env=env, timeout=240)
    assert p.returncode == 1 and "cannot rename the resumed run's copy" in p.stderr, (p.returncode, p.stderr)
    with open(os.path.join(out, "run.log")) as f:
        log = f.read()
    assert log.count("cannot rename the resumed run's copy") == 1, log
    assert "is kept as record.h5.resuming" in log and "before t =" not in log, log
    assert os.stat(record).st_ino == before
    with harness.record(record) as f:
        assert f.attrs["status"] == "running", f.attrs["status"]  # as the kill left it
        interrupted_end = f["windows/t"][-1]
    with harness.record(record + ".resuming") as f:
        assert f.attrs["status"].startswith("failed: cannot rename the resumed run's copy"), f.attrs["status"]
        end = f["windows/t"][-1]
        assert end >= interrupted_end - 1e-12, (end, interrupted_end)  # all of the interrupted record, and on
    assert not os.path.exists(os.path.join(out, "watchpoints.csv.resuming"))
    with open(os.path.join(out, "watchpoints.csv")) as f:
        assert abs(float(f.read().strip().splitlines()[-1].split(",")[0]) - end) < 1e-9


def test_a_resume_on_a_disk_that_fills_leaves_the_record_as_it_was():
    """A resume whose writes start failing with ENOSPC (kill_at_write.so's SPHFSI_FAIL_WRITES_FROM, half way
    through the writes a whole resume makes) before it has caught up: record.h5 stays byte for byte as the
    interrupted run left it, its copy is removed, and both the cause and what was left are said, once. The
    root totals and the status written after the stop failed too and escaped: the copy stayed behind on the
    full disk, with no word of it, and the cause was printed twice (a review, 2026-11-28; seen so). The
    interrupted record's last window is moved to 0.25 s, past the resumed run's end, so the copy never
    catches up and wherever the failure falls it is pending; a resume with room then completes."""
    out = harness.out_dir("resume-disk-full")
    killed_at_a_rename(["run", SCENE, "--out", out, "--quiet", "--set", "run.end_time=0.2", "--set",
                        "run.checkpoint_interval=0.05", "--set", "run.output_interval=0.01"], "checkpoint.bin", 3, "before")
    import h5py
    with h5py.File(os.path.join(out, "record.h5"), "r+", locking=False) as f:
        f["windows/t"][-1] = 0.25
    dry = out + "-dry"
    shutil.copytree(out, dry)
    shim = dict(os.environ, LD_PRELOAD=os.path.join(harness.BIN, "kill_at_write.so"))
    p = subprocess.run([os.path.join(harness.BIN, "sphfsi"), "run", "--resume", dry, "--quiet"], capture_output=True,
                       text=True, env=shim, timeout=60)
    assert p.returncode == 0, p.stderr
    writes = max(int(line.split()[1]) for line in p.stderr.splitlines() if line.startswith("writes: "))
    with open(os.path.join(out, "record.h5"), "rb") as f:
        before = f.read()
    p = subprocess.run([os.path.join(harness.BIN, "sphfsi"), "run", "--resume", out, "--quiet"], capture_output=True,
                       text=True, env=dict(shim, SPHFSI_FAIL_WRITES_FROM=str(writes // 2)), timeout=60)
    print(f"a whole resume makes {writes} writes; failing from write {writes // 2}: exit {p.returncode}")
    assert p.returncode == 1 and p.stderr.count("No space left on device") == 1, (p.returncode, p.stderr)
    assert "record.h5 is left as that run left it" in p.stderr, p.stderr
    assert not [n for n in os.listdir(out) if n.endswith(".resuming")], os.listdir(out)
    with open(os.path.join(out, "record.h5"), "rb") as f:
        assert f.read() == before
    code, text = harness.sphfsi("run", "--resume", out, "--quiet", timeout=60)
    assert code == 0, text


def test_a_checkpoint_is_published_only_after_the_resumed_copy_took_over():
    """The interrupted run is killed just before it publishes its checkpoint at 0.15 s, so its record ends at
    0.15 s and its checkpoint says 0.1 s. The resume catches up at 0.15 s; it is killed just after it
    publishes its own checkpoint of 0.15 s. That checkpoint must stand beside a record that holds 0.15 s: the
    copy has replaced record.h5 before it. The checkpoint used to come first, leaving it beside the interrupted
    record, whose last flush a kill may have cut inside the 0.15 s window's rows; the next resume then kept
    the rows before 0.15 s, started after it, and the window was missing from the completed record (a review
    of the recorder found it with a kill inside that flush, 2026-11-27)."""
    out = harness.out_dir("resume-checkpoint-order")
    killed_at_a_rename(["run", SCENE, "--out", out, "--quiet", "--set", "run.end_time=0.2", "--set",
                        "run.checkpoint_interval=0.05", "--set", "run.output_interval=0.01"], "checkpoint.bin", 3, "before")
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert abs(f["windows/t"][-1] - 0.15) < 1e-12, f["windows/t"][:]
    killed_at_a_rename(["run", "--resume", out, "--quiet"], "checkpoint.bin", 1, "after")
    assert not [n for n in os.listdir(out) if n.endswith(".resuming")], os.listdir(out)
    code, text = harness.sphfsi("run", "--resume", out, "--quiet", timeout=60)
    assert code == 0, text
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f.attrs["status"] == "completed"
        assert f.attrs["resumed_by"] == f'{f.attrs["software_version"]} ({f.attrs["git_revision"]})'  # the same build
        t = f["windows/t"][:]
        assert len(t) == 20 and max(abs(t - 0.01 * np.arange(1, 21))) < 1e-9, t


def test_a_resume_without_a_readable_record_says_why_and_leaves_nothing():
    """A resume whose record.h5 is missing or damaged stops before anything starts, says why on stderr and in
    run.log, and leaves no copy beside the record. It once said only "HDF5: cannot open record.h5", in stderr
    alone, and left record.h5.resuming behind (a review of the recorder, 2026-11-27)."""
    out = harness.out_dir("resume-no-record")
    harness.sphfsi("run", SCENE, "--out", out, "--quiet", "--set", "run.end_time=0.2", "--set",
                   "run.checkpoint_interval=0.05", check=0, timeout=60)
    import h5py
    with h5py.File(os.path.join(out, "record.h5"), "r+", locking=False) as f:
        f.attrs["status"] = "running"  # as a run killed after its last checkpoint leaves it
    record = os.path.join(out, "record.h5")
    os.rename(record, record + ".kept")
    for damage, says in ((None, "record.h5 is missing"), (b"not a record", "it is not an HDF5 file that can be read")):
        if damage:
            with open(record, "wb") as f:
                f.write(damage)
        code, text = harness.sphfsi("run", "--resume", out, "--quiet", timeout=60)
        assert code == 1 and says in text, text
        with open(os.path.join(out, "run.log")) as f:
            assert says in f.read().splitlines()[-1]
        assert not [n for n in os.listdir(out) if n.endswith(".resuming")], os.listdir(out)
        if damage:
            with open(record, "rb") as f:
                assert f.read() == damage
    os.replace(record + ".kept", record)
    code, text = harness.sphfsi("run", "--resume", out, "--quiet", timeout=60)
    assert code == 0, text


def test_a_resume_that_fails_after_catching_up_replaces_the_record():
    """A resume that has reached where the interrupted record ends holds all of it; when the window that got
    there then fails (here its frame: the participant answers SNAPSHOT at t = 0.5 s with ERROR), the record
    is the resumed one, with this run's failure. The take-over once came only after the window's frames and
    checkpoint, so such a resume was thrown away, and the log said it stopped "at t = 0.5 s, before t = 0.5 s"
    (a review, 2026-11-27)."""
    scene = os.path.join(harness.SCENES, "misbehaving.toml")
    out = harness.out_dir("resume-fails-at-the-end")
    settings = ["--set", 'structure.mode="snapshot_error"', "--set", "structure.fail_at=0.5", "--set",
                "run.end_time=1.0", "--set", "run.output_interval=0.1", "--set", "run.checkpoint_interval=0.2"]
    code, text = harness.sphfsi("run", scene, "--out", out, "--quiet", *settings, timeout=60)
    assert code == 1 and "node 1 at NaN" in text, text
    first = os.stat(os.path.join(out, "record.h5")).st_ino
    code, text = harness.sphfsi("run", "--resume", out, "--quiet", timeout=60)
    assert code == 1 and "node 1 at NaN" in text and "before t =" not in text, text
    assert os.stat(os.path.join(out, "record.h5")).st_ino != first  # the resumed copy, renamed over it
    assert not [n for n in os.listdir(out) if n.endswith(".resuming")]
    with harness.record(os.path.join(out, "record.h5")) as f:
        assert f.attrs["status"].startswith("failed: ") and "node 1 at NaN" in f.attrs["status"], f.attrs["status"]
        assert abs(f["windows/t"][-1] - 0.5) < 1e-12, f["windows/t"][:]
        frames = f["frames/structure/time"][:]
        assert len(frames) == 5 and max(abs(frames - [0.0, 0.1, 0.2, 0.3, 0.4])) < 1e-12, frames


def test_a_resume_keeps_the_window_columns_of_the_interrupted_run():
    """The window columns are those of a run's first window (a stats name first sent later is named and not
    recorded, test_lifecycle.py), and the root totals sum them. A resume keeps both: it once chose the
    columns again from its own first window, so the misbehaving participant's "late" stat, sent from t > 0,
    became a column holding only the resumed windows, shorter than the others, and the next resume cut the
    whole table to its length."""
    scene = os.path.join(harness.SCENES, "misbehaving.toml")
    settings = ["--set", 'structure.mode="stats_late"', "--set", "run.end_time=200.0",
                "--set", "run.checkpoint_interval=0.5", "--set", "run.output_interval=0.5"]
    cut = killed_after_first_checkpoint(scene, settings, "resume-columns")
    with harness.record(os.path.join(cut, "record.h5")) as f:
        rows = {name: f["windows"][name].shape[0] for name in f["windows"]}
        print(f"after the resume: {len(rows)} window columns, rows {sorted(set(rows.values()))}")
        assert "structure.late" not in rows, sorted(rows)
        assert set(rows.values()) == {400}, rows  # a structure alone: a window per frame, 200 s / 0.5 s
        # The root totals are the columns' sums over the whole record (they once counted the resumed windows only).
        for total, column in (("wall_s", "wall_s"), ("messaging_and_waiting_s", "messaging_s")):
            summed = f["windows"][column][:].sum()
            assert abs(f.attrs[total] - summed) <= 1e-9 * max(summed, 1e-300), (total, f.attrs[total], summed)
        # And the loop's wall time covers the same windows: the checkpoint carries the earlier segments' (it
        # once held the resumed segment's alone, and the messaging share came out at 1199 %).
        assert f.attrs["loop_wall_s"] >= f.attrs["wall_s"], (f.attrs["loop_wall_s"], f.attrs["wall_s"])


def test_a_fresh_run_leaves_nothing_of_an_earlier_run_to_resume():
    """A fresh run over an earlier one (--overwrite) removes the checkpoint the earlier run left there: resuming
    from it would glue the earlier run's state onto this run's record (before 2026-11-25 it did, with status
    "completed")."""
    out = harness.out_dir("fresh-over-old")
    harness.sphfsi("run", SCENE, "--out", out, "--quiet", "--set", "run.end_time=1.0", "--set",
                   "run.checkpoint_interval=0.5", check=0, timeout=60)
    assert os.path.exists(os.path.join(out, "checkpoint.bin"))
    leftovers = ["record.h5.interrupted"]  # an older build's failed resume: --resume would refuse to guess
    for name in leftovers:
        with open(os.path.join(out, name), "w") as f:
            f.write("left by an earlier run")
    harness.sphfsi("run", SCENE, "--out", out, "--quiet", "--overwrite", "--set", "run.end_time=0.05", "--set",
                   "run.output_interval=0.01", check=0, timeout=60)  # ends before its first checkpoint
    for name in ["checkpoint.bin"] + leftovers:
        assert not os.path.exists(os.path.join(out, name)), name
    code, text = harness.sphfsi("run", "--resume", out)
    assert code == 2 and "completed; there is nothing to resume" in text, (code, text)  # said first (a review)
    import h5py
    with h5py.File(os.path.join(out, "record.h5"), "r+", locking=False) as f:
        f.attrs["status"] = "running"  # as if killed before its first checkpoint
    code, text = harness.sphfsi("run", "--resume", out)
    # Said as it is (it read "no checkpoint at ... (was the run started with a checkpoint interval?)").
    assert code == 2 and "stopped before its first checkpoint (its record says: running)" in text, (code, text)


def test_a_completed_run_is_not_resumed():
    """A completed run has nothing left to resume; --resume once re-ran its tail from the last checkpoint and
    rewrote the record (a review, 2026-11-27). Now it is refused, and the record is left as it was."""
    out = harness.out_dir("resume-completed")
    harness.sphfsi("run", SCENE, "--out", out, "--quiet", *SETTINGS, check=0, timeout=120)
    before = os.path.getmtime(os.path.join(out, "record.h5"))
    code, text = harness.sphfsi("run", "--resume", out, "--quiet", timeout=60)
    assert code == 2 and "completed; there is nothing to resume" in text, (code, text)
    assert os.path.getmtime(os.path.join(out, "record.h5")) == before


if __name__ == "__main__":
    harness.main(globals())
