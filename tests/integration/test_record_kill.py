"""A recording stopped between any two of its file writes leaves a record that plain h5py reads whole.

integration.lifecycle SIGKILLs a running coordinator at random moments, and rarely lands inside a flush.
Here record_writer (tests/coordinator) drives the coordinator's Recorder through frames, windows and
interface rows, with kill_at_write preloaded: run k dies just before the record's k-th write (pwrite or
ftruncate), for every k of a whole recording. The frames are enough for the chunk indexes of one-frame
chunks to split (a v1 B-tree node holds 64 chunks). Each record must open, every dataset must read back
whole, each frame table must have a row in every field for every time, and no frame may be lost that a
completed flush held.
"""
import os
import subprocess

import harness

PARTICLES = 100
FRAMES = 70


def write(path, kill_at=None):
    env = dict(os.environ, LD_PRELOAD=os.path.join(harness.BIN, "kill_at_write.so"))
    if kill_at:
        env["SPHFSI_KILL_AT_WRITE"] = str(kill_at)
    return subprocess.run([os.path.join(harness.BIN, "record_writer"), path, str(PARTICLES), str(FRAMES)],
                          capture_output=True, text=True, env=env, timeout=60)


def frames_in(path):
    """The frames of the record, after checking that every dataset reads back and holds what was written."""
    import numpy as np
    with harness.record(path) as f:
        read = {}
        f.visititems(lambda name, obj: read.__setitem__(name, obj[()]) if hasattr(obj, "shape") else None)
        frames = {}
        for role in ("fluid", "structure"):
            times = read.get(f"frames/{role}/time", [])
            for name, data in read.items():
                if name.startswith(f"frames/{role}/"):
                    assert len(data) >= len(times), (name, len(data), len(times))
            frames[role] = len(times)
        # What record_writer wrote, row by row: a row counted before its data was indexed would read as zeros.
        n = frames["fluid"]
        if n:
            t = read["frames/fluid/time"][:, None]
            assert np.allclose(read["frames/fluid/position"][:n, :, 0], np.cos(t + np.arange(PARTICLES)), atol=1e-12)
            assert np.array_equal(read["frames/fluid/tag"][:n], (np.arange(PARTICLES) + np.arange(n)[:, None]) % 7)
        m = frames["structure"]
        assert np.array_equal(read.get("frames/structure/y", np.zeros((0, 8, 2)))[:m, 0, 0], read.get("frames/structure/time", []))
        for name in ("dt", "iterations"):
            assert np.all(read.get(f"windows/{name}", np.ones(0)) == {"dt": 2e-4, "iterations": 1.0}[name]), name
        return min(frames.values())


def test_a_kill_between_any_two_writes_leaves_a_readable_record():
    out = harness.out_dir("record-kill")
    path = os.path.join(out, "record.h5")
    whole = write(path)
    assert whole.returncode == 0, whole.stderr
    writes = int(whole.stderr.split("writes: ")[1])
    assert frames_in(path) == FRAMES
    first_record, kept = None, 0
    for k in range(1, writes + 1):
        os.remove(path) if os.path.exists(path) else None
        killed = write(path, kill_at=k)
        assert killed.returncode == -9, (k, killed.returncode, killed.stderr)
        if not os.path.exists(path):  # killed while the file was built beside its name: no record at all
            assert first_record is None, f"killed before write {k}, after a record was left by a kill before {first_record}"
            continue
        first_record = first_record or k
        try:
            frames = frames_in(path)
        except Exception as e:
            raise AssertionError(f"killed before write {k} of {writes}: {e}") from e
        assert frames >= kept - 1, (k, frames, kept)  # at most the frame being flushed is lost
        kept = max(kept, frames)
    assert first_record is not None and first_record < writes / FRAMES, first_record
    print(f"{writes} writes: a kill before any of writes 1 - {first_record - 1} left no record, before any of "
          f"{first_record} - {writes} a record that reads back whole")


if __name__ == "__main__":
    harness.main(globals())
