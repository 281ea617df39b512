"""Resume: a run killed after a checkpoint and continued with `sphfsi run --resume DIR` ends in the same
state as an uninterrupted run, to 1e-10 relative (issue 5's criterion; both runs take the same windows,
so the only allowed difference is none at all, and the bound leaves room for nothing but round-off)."""
import os
import signal
import time

import numpy as np

import harness

SCENE = os.path.join(harness.ROOT, "scenarios", "beam_only.toml")
SETTINGS = ["--set", "run.end_time=3.0", "--set", "run.checkpoint_interval=0.5", "--set", "run.output_interval=0.05"]


def killed_after_first_checkpoint(scene, settings, name):
    """Starts the scene, SIGKILLs the coordinator as soon as a checkpoint exists, resumes it to the end;
    returns the output folder."""
    cut = harness.out_dir(name)
    run = harness.Running("run", scene, "--out", cut, "--quiet", *settings)
    checkpoint = os.path.join(cut, "checkpoint.bin")
    deadline = time.time() + 120
    while not os.path.exists(checkpoint) and time.time() < deadline and run.proc.poll() is None:
        time.sleep(0.01)
    assert os.path.exists(checkpoint), "no checkpoint was written"
    run.proc.send_signal(signal.SIGKILL)
    run.proc.wait(timeout=10)
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

    cut = killed_after_first_checkpoint(SCENE, SETTINGS, "resume-cut")

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
    """The same for a coupled run: the elastic gate, coarse, killed after its first checkpoint."""
    scene = os.path.join(harness.ROOT, "scenarios", "elastic_gate.toml")
    settings = ["--set", "fluid.dp=0.004", "--set", "run.end_time=0.06", "--set", "run.checkpoint_interval=0.02",
                "--set", "run.output_interval=0.005"]
    full = harness.out_dir("resume-gate-full")
    harness.sphfsi("run", scene, "--out", full, "--quiet", *settings, check=0, timeout=240)
    cut = killed_after_first_checkpoint(scene, settings, "resume-gate-cut")
    with harness.record(os.path.join(full, "record.h5")) as a, harness.record(os.path.join(cut, "record.h5")) as b:
        assert b.attrs["status"] == "completed"
        assert np.array_equal(a["windows/t"][:], b["windows/t"][:]), "the resumed run took different windows"
        for path in ("frames/fluid/position", "frames/fluid/velocity", "frames/structure/displacement"):
            x, y = a[path][-1], b[path][-1]
            err = np.abs(x - y).max() / max(np.abs(x).max(), 1e-300)
            print(f"{path}: final frames differ by {err:.1e} relative")
            assert err <= 1e-10, path


if __name__ == "__main__":
    harness.main(globals())
