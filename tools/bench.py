#!/usr/bin/env -S /usr/bin/python3
"""sphfsi's benchmark command (the benchmark command the performance issue asks for): fixed, deterministic
workloads, each run as its own process, repeated, medians printed.

usage: /usr/bin/python3 tools/bench.py [--bin build/bin] [--repeats 5] [--quick]
                                       [--only fluid|standard|pcisph|coupled]

  --bin DIR     where the binaries are (default build/bin)
  --repeats N   runs of each case (default 5)
  --quick       the fluid workloads at ~10k particles only; the coupled cases are unchanged
  --only W      one workload (below) instead of all four

Only the fluid and coupled workloads: the messaging, structure, whole-run memory and record-write
benchmarks are commands of their own (docs/benchmarks.md).

Workloads:
  fluid    the dam break of docs/benchmarks.md (Wendland, h = 1.41 dp, WCSPH with Fourtakas diffusion,
           artificial viscosity, symplectic Euler) at ~10k, ~40k and ~160k particles, 1 and 2 threads
  standard the same with the thesis's standard SPH (p = k (rho - rho0), summation densities)
  pcisph   the same with PCISPH (fewer steps: each costs 15-30 WCSPH steps)
  coupled  the elastic gate (scenarios/elastic_gate.toml) through the coordinator, to 0.05 s: as the scene
           stands (dp = 1 mm, windows of up to 10 fluid steps) with the fluid on 2 threads, with the
           participants' default wait policy and sleeping at once; with one window per fluid step (the
           thesis's rule) and the fluid on 1 thread (the scene until 2026-11-25); and at the quick
           dp = 2 mm, fluid on 2 threads
Output starts with the machine (CPU model, logical CPUs), the git revision, the date (UTC) and the 1-minute
load average. For each fluid case: particles, steps, wall seconds, particle-steps per second (3 significant
figures), and memory per particle three ways: the solver's own count of its arrays (the figure to quote);
the benchmark process's peak resident set (VmHWM) above a baseline, over the particles, where the baseline
is the median peak of the same model at 50 fluid particles (code, libraries, OpenMP runtime, allocator; one
thread, as the simulation runs anything under 4,000 particles); and that whole peak over the particles,
which carries the fixed 4.5 - 6 MiB and so falls with size (wait4's ru_maxrss would also carry this script's
~10 MiB across exec). The thread count is the one the simulation used. For the coupled run: the share of
the time loop's wall time spent messaging and waiting, the coordinator's own CPU use, and from the record
the fluid's particles, threads, steps, particle-steps per second over the whole loop's wall time
(messaging and recording included) and its own count of its arrays per particle (the participants are not
this script's children, so their peak memory is not read).
"""
import datetime
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


def fluid_bench(bin_dir, model, size, threads, steps):
    """One run of sphfsi-fluid-bench: its output line, split."""
    out, _ = run_measured([os.path.join(bin_dir, "sphfsi-fluid-bench"), "--sizes", size, "--threads", str(threads),
                           "--models", model, "--steps", str(steps)])
    # model threads fluid particles steps iters wall_s rate bytes/part peak_rss/part peak_rss_kB
    return [l for l in out.splitlines() if l.startswith(model)][0].split()


def fluid_rows(bin_dir, model, sizes, threads, steps, repeats):
    # The process's fixed peak (code, libraries, runtime), measured on the same model with almost no
    # particles, so that the peak's share per particle does not fall with size just by dividing it.
    baseline_kib = statistics.median(float(fluid_bench(bin_dir, model, "50", 1, 1)[10]) for _ in range(repeats))
    rows = []
    for size in sizes:
        for t in threads:
            rates, walls, arrays, above, whole, last = [], [], [], [], [], None
            for _ in range(repeats):
                line = last = fluid_bench(bin_dir, model, size, t, steps)
                n = int(line[3])
                rates.append(float(line[7]))
                walls.append(float(line[6]))
                arrays.append(float(line[8]))
                whole.append(float(line[9]))  # the bench's own VmHWM per particle (wait4's carries Python's)
                above.append((float(line[10]) - baseline_kib) * 1024 / n)
            rows.append((model, int(last[1]), int(last[3]), int(last[4]), statistics.median(walls), statistics.median(rates),
                         min(rates), max(rates), statistics.median(arrays), statistics.median(above), statistics.median(whole)))
    return rows, baseline_kib


def coupled_row(bin_dir, repeats, spin_us, overrides, end_time):
    """The elastic gate to end_time with the scene overrides given, the participants' wait policy set by
    SPHFSI_WAIT_SPIN_US (None: the runtime's default)."""
    shares, cpu, walls, windows, threads = [], [], [], 0, set()
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
            threads.add(int(fluid["threads"]))  # what the fluid used, not what was asked
            steps = int(f["windows/fluid.steps"][:].sum())
        shutil.rmtree(out_dir)  # a 1 mm record is about 7 MB
    wall = statistics.median(walls)
    return (wall, windows, particles, "/".join(map(str, sorted(threads))), steps, particles * steps / wall, per_particle,
            statistics.median(shares), max(shares), statistics.median(cpu), max(cpu))


def machine_header():
    """The machine and the build the figures belong to: the VMs this project ran on differ about 2 times."""
    cpu = "unknown CPU"
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    git = lambda *a: subprocess.run(["git", "-C", ROOT] + list(a), capture_output=True, text=True).stdout.strip()
    try:
        revision = (git("rev-parse", "--short", "HEAD") or "unknown") + ("-dirty" if git("status", "--porcelain") else "")
    except OSError:  # no git on this machine
        revision = "unknown"
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return (f"machine: {cpu}, {os.cpu_count()} logical CPUs; revision {revision}; {date}; "
            f"load average (1 min) {os.getloadavg()[0]:.2f}")


def millions(rate):
    """A rate in millions to 3 significant figures (PCISPH's 0.0312 M, not 0.03 M)."""
    return f"{rate / 1e6:.3g}"


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
    print(machine_header())
    print(f"sphfsi benchmarks, {repeats} repeats each, medians (min - max); binaries in {bin_dir}")
    if only in (None, "fluid", "standard", "pcisph"):
        print("memory per particle [B]: arrays = the solver's own count of its arrays; above baseline = (peak RSS - "
              "peak RSS of the same model at 50 fluid particles) / particles; whole-process peak = the process's peak RSS / "
              "particles, its fixed part included")
        print("| workload | threads | particles | steps | wall [s] | particle-steps/s | min - max | arrays / particle [B] "
              "| peak RSS above baseline / particle [B] | whole-process peak RSS / particle [B] |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        baselines = []
        for workload, model, steps in (("fluid", "wcsph", 200), ("standard", "standard", 200), ("pcisph", "pcisph", 30)):
            if only not in (None, workload):
                continue
            rows, baseline_kib = fluid_rows(bin_dir, model, sizes, [1, 2], steps, repeats)
            for name, t, n, s, wall, rate, lo, hi, arrays, above, whole in rows:
                print(f"| dam break {name} | {t} | {n} | {s} | {wall:.3f} | {millions(rate)} M | {millions(lo)} - {millions(hi)} M | {arrays:.0f} "
                      f"| {above:.0f} | {whole:.0f} |")
            baselines.append(f"{model} {baseline_kib / 1024:.1f} MiB")
        print(f"baselines (peak RSS at 50 fluid particles, median): {', '.join(baselines)}")
    if only in (None, "coupled"):
        # The scene as it stands with the default wait policy and sleeping at once (docs/benchmarks.md, "Coupled
        # run"), the scene's coupling until 2026-11-25 for comparison, and the quick resolution. A window costs
        # about the same messaging at any resolution; the fluid's step costs about 4 times more at 1 mm than at 2.
        # The scene's fluid.threads = 0 takes every core (or OMP_NUM_THREADS), so the rows name 2 threads to
        # mean the same on any machine.
        thesis = ["coupling.window=thesis", "fluid.threads=1"]
        cases = (("as the scene stands, fluid on 2 threads", ["fluid.threads=2"],
                  "participants spin 1 ms after each reply (the default)", None),
                 ("as the scene stands, fluid on 2 threads", ["fluid.threads=2"], "participants sleep at once", 0),
                 ("one window per fluid step, fluid on 1 thread", thesis, "the default wait policy", None),
                 ("quick look, dp = 2 mm, fluid on 2 threads", ["fluid.dp=0.002", "fluid.threads=2"],
                  "the default wait policy", None))
        end_time = 0.05
        for label, overrides, policy, spin_us in cases:
            wall, windows, n, threads, steps, rate, per_particle, share, share_max, cpu, cpu_max = coupled_row(
                bin_dir, repeats, spin_us, overrides, end_time)
            print(f"\nelastic gate, {label}, {end_time} s, {policy}: {n} particles, the fluid on {threads} thread(s) (its "
                  f"record), {steps} fluid steps in {windows} windows, loop wall {wall:.2f} s, {millions(rate)} M particle-steps/s "
                  f"over the loop's wall, {per_particle:.0f} B/particle (the fluid's arrays); messaging and waiting "
                  f"{share:.2f} % of loop wall (max {share_max:.2f} %); coordinator CPU {cpu:.2f} % of one core "
                  f"(max {cpu_max:.2f} %)")
    print(f"\nload average (1 min) at the end: {os.getloadavg()[0]:.2f}")

if __name__ == "__main__":
    main()
