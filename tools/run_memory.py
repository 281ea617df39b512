#!/usr/bin/env -S /usr/bin/python3
"""Peak memory of a whole run per particle: the coordinator and the fluid participant, each process's own
peak resident set (VmHWM, read from /proc every 0.1 s while it runs), at two resolutions of the dam break;
the slope between them is the cost of one more particle without each process's fixed start-up share.
fluid/include/sphfsi/fluid/footprint.hpp rounds their sum up to the bytes per particle the scene check uses.

usage: /usr/bin/python3 tools/run_memory.py [--bin build/bin] [--dp 3.2e-4,1.6e-4]
"""
import argparse
import os
import shutil
import subprocess
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def peak_kib(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return None


def children(pid):
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as f:
            return [int(c) for c in f.read().split()]
    except OSError:
        return []


def measure(sphfsi, dp):
    """Runs the dam break for one short window at spacing dp; returns (particles, coordinator KiB, fluid KiB)."""
    out = tempfile.mkdtemp(prefix="sphfsi-run-memory-")
    # stderr goes to a file: a pipe nobody reads while the run goes on would stall the run once full
    with tempfile.TemporaryFile() as err:
        try:
            p = subprocess.Popen([sphfsi, "run", os.path.join(ROOT, "scenarios", "dam_break.toml"), "--out", out,
                                  "--overwrite", "--quiet", "--set", f"fluid.dp={dp}", "--set", "run.end_time=0.0005",
                                  "--set", "run.output_interval=0.0005"], stdout=subprocess.DEVNULL, stderr=err)
            coordinator = fluid = 0
            # The peaks only grow, so the last reading before each process ends is its peak (to within what it
            # adds in its last 0.1 s; the coordinator then only closes the record).
            while p.poll() is None:
                coordinator = peak_kib(p.pid) or coordinator
                for c in children(p.pid):
                    fluid = peak_kib(c) or fluid
                time.sleep(0.1)
            if p.returncode != 0:
                err.seek(0)
                raise SystemExit(f"dp = {dp}: sphfsi exited {p.returncode}: {err.read().decode(errors='replace')}")
            if fluid == 0 or coordinator == 0:
                raise SystemExit(f"dp = {dp}: no peak read for the {'fluid participant' if fluid == 0 else 'coordinator'} "
                                 "(it ended before the first 0.1 s reading?): use a finer dp")
            import h5py
            with h5py.File(os.path.join(out, "record.h5"), "r", locking=False) as f:
                particles = int(f["participants/fluid"].attrs["particles"])
            return particles, coordinator, fluid
        finally:
            shutil.rmtree(out, ignore_errors=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--dp", default="3.2e-4,1.6e-4", help="two spacings, coarse first")
    a = ap.parse_args()
    coarse, fine = (measure(os.path.join(a.bin, "sphfsi"), float(d)) for d in a.dp.split(","))
    print("particles  coordinator_MiB  fluid_MiB")
    for n, c, f in (coarse, fine):
        print(f"{n:9d}  {c / 1024:15.1f}  {f / 1024:9.1f}")
    dn = fine[0] - coarse[0]
    per_c = (fine[1] - coarse[1]) * 1024 / dn
    per_f = (fine[2] - coarse[2]) * 1024 / dn
    print(f"per particle (slope): coordinator {per_c:.0f} B, fluid {per_f:.0f} B, together {per_c + per_f:.0f} B")


if __name__ == "__main__":
    main()
