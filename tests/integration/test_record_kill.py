"""A recording stopped between any two of its file writes leaves no record or one that plain h5py reads whole.

integration.lifecycle SIGKILLs a running coordinator at random moments, and rarely lands inside a flush.
Here record_writer (tests/coordinator) writes a recording with kill_at_write preloaded: run k dies just
before the file's k-th write (pwrite, ftruncate or fallocate), for every k of a whole recording. Two recordings:
- the coordinator's Recorder: 24 frames of two participants with their windows and interface rows (its
  creation, first frames and windows, and the frames after them);
- the record's file layer alone with chunk index nodes of 4 entries, so that 70 frames make the indexes 4
  levels deep (a parent's update and its child's must reach the disk in the right order at every level),
  and a dataset added to one group with each of the first 12 frames (a group's names outgrowing the room
  HDF5 gives them by default, one flush after another).
Each kill must leave no record (killed before the record's first flush was done) or one that opens, whose
every dataset reads back holding what was written (a row counted before its data was indexed would read as
zeros), losing at most the frame being flushed.
"""
import os
import subprocess

import harness

PARTICLES = 100
FRAMES = {False: 24, True: 70}  # by recording: the Recorder's, the deep indexes


def write(path, deep, kill_at=None):
    env = dict(os.environ, LD_PRELOAD=os.path.join(harness.BIN, "kill_at_write.so"))
    if kill_at:
        env["SPHFSI_KILL_AT_WRITE"] = str(kill_at)
    mode = ["--deep-index"] if deep else []
    return subprocess.run([os.path.join(harness.BIN, "record_writer"), *mode, path, str(PARTICLES), str(FRAMES[deep])],
                          capture_output=True, text=True, env=env, timeout=60)


def frames_in(path, deep):
    """The frames of the record, after checking that every dataset reads back and holds what was written."""
    import numpy as np
    with harness.record(path) as f:
        read = {}
        f.visititems(lambda name, obj: read.__setitem__(name, obj[()]) if hasattr(obj, "shape") else None)
        frames = {}
        for role in ("fluid",) if deep else ("fluid", "structure"):
            times = read.get(f"frames/{role}/time", [])
            for name, data in read.items():
                if name.startswith(f"frames/{role}/"):
                    assert len(data) >= len(times), (name, len(data), len(times))
            frames[role] = len(times)
        n = frames["fluid"]
        if n:
            t = read["frames/fluid/time"][:, None]
            assert np.array_equal(t[:, 0], 1e-3 * np.arange(n))
            assert np.allclose(read["frames/fluid/position"][:n, :, 0], np.cos(t + np.arange(PARTICLES)), atol=1e-12)
            assert np.allclose(read["frames/fluid/position"][:n, :, 1], np.sin(t + np.arange(PARTICLES)), atol=1e-12)
            assert np.array_equal(read["frames/fluid/tag"][:n], (np.arange(PARTICLES) + np.arange(n)[:, None]) % 7)
            if not deep:  # record_writer --deep-index writes no pressure
                assert np.array_equal(read["frames/fluid/pressure"][:n].reshape(n, PARTICLES),
                                      t * np.arange(PARTICLES)), "pressure"
        if deep:
            for name, data in read.items():
                if name.startswith("extras/"):
                    assert list(data) in ([], [int(name.rsplit("_", 1)[1])]), (name, data)
        else:
            m = frames["structure"]
            assert np.array_equal(read.get("frames/structure/y", np.zeros((0, 8, 2)))[:m, 0, 0],
                                  read.get("frames/structure/time", []))
            for name, value in (("dt", 2e-4), ("iterations", 1.0)):
                assert np.all(read.get(f"windows/{name}", np.ones(0) * value) == value), name
            # The windows' times and interface rows as record_writer appends them: 5 windows a frame at
            # t_frame + 2e-4 w, vertex 0 displaced by t_frame in x and pushed by -t_frame in y, all else zero
            # (a row counted before its data was written would read as zeros). A kill during a flush may leave
            # these datasets rows apart (docs/record.md), so each is checked on its own rows.
            wt = read.get("windows/t", np.zeros(0))
            k = np.arange(len(wt))
            assert np.allclose(wt, 1e-3 * (k // 5) + 2e-4 * (k % 5), rtol=0, atol=1e-15), "windows/t"
            disp, force = read.get("interface/displacement"), read.get("interface/force")
            if disp is not None:
                rows = len(disp)
                expect = np.zeros((rows, 8, 2))
                expect[:, 0, 0] = 1e-3 * (np.arange(rows) // 5)
                assert np.array_equal(disp, expect), "interface/displacement"
            if force is not None:
                expect = np.zeros_like(force)
                expect[:, 0, 1] = -1e-3 * (np.arange(len(force)) // 5)
                assert np.array_equal(force, expect), "interface/force"
            assert f.attrs["status"] in ("running", "completed"), f.attrs["status"]
        return min(frames.values())


def kill_at_every_write(name, deep):
    out = harness.out_dir(name)
    path = os.path.join(out, "record.h5")
    whole = write(path, deep)
    assert whole.returncode == 0, whole.stderr
    writes = int(whole.stderr.split("writes: ")[1])
    with harness.record(path) as f:
        assert len(f["frames/fluid/time"]) == FRAMES[deep]
    first_record, kept = None, 0
    for k in range(1, writes + 1):
        for stale in (path, path + ".creating"):
            if os.path.exists(stale):
                os.remove(stale)
        killed = write(path, deep, kill_at=k)
        assert killed.returncode == -9, (k, killed.returncode, killed.stderr)
        if not os.path.exists(path):  # killed while the file was built beside its name: no record at all
            assert first_record is None, f"killed before write {k}: no record, though a kill before {first_record} left one"
            continue
        first_record = first_record or k
        try:
            frames = frames_in(path, deep)
        except Exception as e:
            raise AssertionError(f"killed before write {k} of {writes}: {e!r}") from e
        assert frames >= kept - 1, (k, frames, kept)  # at most the frame being flushed is lost
        kept = max(kept, frames)
    assert first_record is not None and first_record < writes / FRAMES[deep], first_record
    print(f"{name}: {writes} writes; a kill before any of writes 1 - {first_record - 1} left no record, before any "
          f"of {first_record} - {writes} a record that reads back whole")


def test_a_kill_between_any_two_writes_of_a_recording_leaves_a_readable_record():
    kill_at_every_write("record-kill", deep=False)


def test_a_kill_between_any_two_writes_to_deep_chunk_indexes_leaves_a_readable_record():
    kill_at_every_write("record-kill-deep", deep=True)


if __name__ == "__main__":
    harness.main(globals())
