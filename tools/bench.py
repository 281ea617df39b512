#!/usr/bin/env -S /usr/bin/python3
"""sphfsi's benchmark command (the benchmark command the performance issue asks for): fixed, deterministic
workloads, each run as its own process, repeated, medians printed.

usage: /usr/bin/python3 tools/bench.py [--bin build/bin] [--repeats 5] [--quick]
                                       [--only fluid|standard|pcisph|coupled]

Workloads:
  fluid    the dam break of docs/benchmarks.md (Wendland, h = 1.41 dp, WCSPH with Fourtakas diffusion,
           artificial viscosity, symplectic Euler) at ~10k, ~40k and ~160k particles, 1 and 2 threads
  standard the same with the thesis's standard SPH (p = k (rho - rho0), summation densities)
  pcisph   the same with PCISPH (fewer steps: each costs 15-30 WCSPH steps)
  coupled  the elastic gate (scenarios/elastic_gate.toml) through the coordinator, to 0.05 s: as the scene
           stands (dp = 1 mm, fluid on 2 threads, windows of up to 10 fluid steps) with the participants'
           default wait policy and sleeping at once; with one window per fluid step (the thesis's rule) and
           the fluid on 1 thread (the scene until 2026-11-25); and at the quick dp = 2 mm
For each: particles, steps, wall seconds, particle-steps per second, peak resident memory per particle
(the benchmark process's own peak resident set, VmHWM, divided by its particle count: wait4's ru_maxrss
would carry this script's ~10 MiB across exec), and for the coupled run the share of
wall time spent messaging and waiting, and the coordinator's own CPU use (its memory column is the fluid's
own count of its arrays per particle, from the record: the participants are not this script's children).
"""
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run_measured(argv, env=None):
    """Runs argv to completion; returns its stdout and the rusage of that process."""
    # stderr goes to a file: read from a second pipe after stdout, a child writing more than a pipe's buffer
    # there would block, and the benchmark with it. Then reap with wait4 (the exit status and rusage of this
    # child alone).
    with tempfile.TemporaryFile(mode="w+") as err_file:
        p = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=err_file, text=True, env=env)
        out = p.stdout.read()
        _, status, usage = os.wait4(p.pid, 0)
        err_file.seek(0)
        err = err_file.read()
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode:
        sys.exit(f"{' '.join(argv)} failed ({p.returncode}):\n{err}")
    return out, usage


def fluid_rows(bin_dir, model, sizes, threads, steps, repeats):
    rows = []
    for size in sizes:
        for t in threads:
            rates, rss, walls, last = [], [], [], None
            for _ in range(repeats):
                out, usage = run_measured([os.path.join(bin_dir, "sphfsi-fluid-bench"), "--sizes", size, "--threads", str(t),
                                           "--models", model, "--steps", str(steps)])
                line = [l for l in out.splitlines() if l.startswith(model)][0].split()
                # model threads fluid particles steps iters wall_s rate bytes/part peak_rss/part
                last = line
                rates.append(float(line[7]))
                walls.append(float(line[6]))
                rss.append(float(line[9]))  # the bench's own VmHWM per particle (wait4's carries Python's)
            rows.append((model, t, int(last[3]), int(last[4]), statistics.median(walls), statistics.median(rates), min(rates),
                         max(rates), statistics.median(rss)))
    return rows


def coupled_row(bin_dir, repeats, spin_us, overrides, end_time):
    """The elastic gate to end_time with the scene overrides given, the participants' wait policy set by
    SPHFSI_WAIT_SPIN_US (None: the runtime's default)."""
    shares, cpu, walls, windows = [], [], [], 0
    env = dict(os.environ)
    if spin_us is not None:
        env["SPHFSI_WAIT_SPIN_US"] = str(spin_us)
    for _ in range(repeats):
        out_dir = tempfile.mkdtemp(prefix="sphfsi-bench-gate-")
        run_measured([os.path.join(bin_dir, "sphfsi"), "run", os.path.join(ROOT, "scenarios", "elastic_gate.toml"), "--out",
                      out_dir, "--quiet", "--set", f"run.end_time={end_time}"] + [a for o in overrides for a in ("--set", o)], env)
        import h5py
        with h5py.File(os.path.join(out_dir, "record.h5"), "r") as f:
            # Both shares over the time loop as a whole (windows, recording, snapshots): its wall time and the
            # coordinator's CPU time in it (until 2026-11-25 the CPU of the whole process, start-up included,
            # was divided by the windows' wall time alone).
            wall = f.attrs["loop_wall_s"]
            shares.append(100 * f.attrs["messaging_and_waiting_s"] / wall)
            cpu.append(100 * f.attrs["coordinator_loop_cpu_s"] / wall)
            walls.append(wall)
            windows = f["windows/t"].shape[0]
            fluid = f["participants/fluid"].attrs
            particles, per_particle = int(fluid["particles"]), fluid["memory_bytes_per_particle"]
            steps = int(f["windows/fluid.steps"][:].sum())
        shutil.rmtree(out_dir)  # a 1 mm record is about 7 MB
    wall = statistics.median(walls)
    return (wall, windows, particles, steps, particles * steps / wall, per_particle, statistics.median(shares), max(shares),
            statistics.median(cpu), max(cpu))


def main():
    args = sys.argv[1:]
    # Anything but the documented options (--help included) prints the usage instead of starting a long run.
    valid = {"--bin": lambda v: True, "--repeats": lambda v: v.isdigit() and int(v) > 0,
             "--only": lambda v: v in ("fluid", "standard", "pcisph", "coupled")}
    i = 0
    while i < len(args):
        if args[i] in valid and i + 1 < len(args) and valid[args[i]](args[i + 1]):
            i += 2
        elif args[i] == "--quick":
            i += 1
        elif args[i] in ("-h", "--help"):
            print(__doc__)
            sys.exit(0)
        else:
            sys.exit(__doc__)  # status 1, the usage on stderr
    opt = lambda name, default: args[args.index(name) + 1] if name in args else default
    bin_dir = os.path.abspath(opt("--bin", os.path.join(ROOT, "build", "bin")))
    repeats = int(opt("--repeats", "5"))
    only = opt("--only", None)
    quick = "--quick" in args
    sizes = ["10k"] if quick else ["10k", "40k", "160k"]
    print(f"sphfsi benchmarks, {repeats} repeats each, medians (min - max); binaries in {bin_dir}")
    header = "| workload | threads | particles | steps | wall [s] | particle-steps/s | min - max | peak RSS / particle [B] |"
    if only in (None, "fluid", "standard", "pcisph"):
        print(header)
        print("|---|---|---|---|---|---|---|---|")
        for workload, model, steps in (("fluid", "wcsph", 200), ("standard", "standard", 200), ("pcisph", "pcisph", 30)):
            if only not in (None, workload):
                continue
            for m, t, n, s, wall, rate, lo, hi, rss in fluid_rows(bin_dir, model, sizes, [1, 2], steps, repeats):
                print(f"| dam break {m} | {t} | {n} | {s} | {wall:.3f} | {rate / 1e6:.2f} M | {lo / 1e6:.2f} - {hi / 1e6:.2f} M | {rss:.0f} |")
    if only in (None, "coupled"):
        # The scene as it stands with the default wait policy and sleeping at once (docs/benchmarks.md, "Coupled
        # run"), the scene's coupling until 2026-11-25 for comparison, and the quick resolution. A window costs
        # about the same messaging at any resolution; the fluid's step costs about 4 times more at 1 mm than at 2.
        thesis = ["coupling.window=thesis", "fluid.threads=1"]
        cases = (("as the scene stands", [], "participants spin 1 ms after each reply (the default)", None),
                 ("as the scene stands", [], "participants sleep at once", 0),
                 ("one window per fluid step, fluid on 1 thread", thesis, "the default wait policy", None),
                 ("quick look, dp = 2 mm", ["fluid.dp=0.002"], "the default wait policy", None))
        end_time = 0.05
        for label, overrides, policy, spin_us in cases:
            wall, windows, n, steps, rate, per_particle, share, share_max, cpu, cpu_max = coupled_row(
                bin_dir, repeats, spin_us, overrides, end_time)
            print(f"\nelastic gate, {label}, {end_time} s, {policy}: {n} particles, {steps} fluid steps in {windows} "
                  f"windows, wall {wall:.2f} s, {rate / 1e6:.2f} M particle-steps/s, {per_particle:.0f} B/particle (the "
                  f"fluid's arrays); messaging and waiting {share:.2f} % of wall (max {share_max:.2f} %); coordinator "
                  f"CPU {cpu:.2f} % of one core (max {cpu_max:.2f} %)")

if __name__ == "__main__":
    main()
