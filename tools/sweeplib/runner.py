"""Runs one coordinator (`sphfsi run SCENE --out DIR --set ... --quiet`) under a wall-clock limit.

Wall seconds: from fork to reaping the coordinator (participants' start-up included).
CPU seconds: user + system time from os.wait4 on the coordinator. The kernel adds to it the CPU of every
child the coordinator reaped itself, so the participants' CPU is included whenever the coordinator ends on
its own (completed, failed, invalid) or obeys SIGINT. If it must be SIGKILLed, its participants are not
reaped by it; their CPU is then read from /proc just before the kill and added (it misses at most the
last few milliseconds they run after that).

A run that overruns gets SIGINT (the coordinator then stops its participants and closes the record as
`interrupted at t = ...`), and SIGKILL `grace_s` later, sent to its process group and, by pid, to every
process below it (the coordinator starts each participant in a process group of its own).
"""
import os
import select
import signal
import subprocess
import time

CLK_TCK = os.sysconf("SC_CLK_TCK")
POLL_S = 0.2  # longest sleep between looks at the stop request; the exit itself wakes us at once (pidfd)
STDERR_FILE = "sweep_stderr.txt"  # in each run's folder: the coordinator's stdout and stderr


class RunResult:
    def __init__(self):
        self.exit_code = None      # the coordinator's exit status, or -N if killed by signal N
        self.timed_out = False     # we stopped it because it overran its timeout
        self.stopped = False       # we stopped it because the sweep was interrupted
        self.killed = False        # SIGINT was not enough: SIGKILL
        self.wall_s = None
        self.cpu_s = None
        self.stderr_path = None
        self.extra_cpu = 0.0       # participants' CPU read from /proc before a SIGKILL


def run_coordinator(sphfsi, scene, out_dir, set_args, timeout_s, grace_s, env=None, stop_event=None):
    """Runs the coordinator to its end; returns a RunResult. `stop_event` (threading.Event) asks it to
    stop early (SIGINT, then SIGKILL after grace_s)."""
    os.makedirs(out_dir, exist_ok=True)
    res = RunResult()
    res.stderr_path = os.path.join(out_dir, STDERR_FILE)
    argv = [sphfsi, "run", scene, "--out", out_dir, "--quiet"]
    for a in set_args:
        argv += ["--set", a]
    with open(os.path.join(out_dir, "sweep_command.txt"), "w") as f:
        f.write(" ".join(_quote(a) for a in argv) + "\n")
    with open(res.stderr_path, "wb") as err:
        start = time.monotonic()
        # Own session: the terminal's Ctrl-C reaches the sweep only, which then stops each run in order.
        proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=err, stderr=err, env=env,
                                start_new_session=True)
    pid = proc.pid
    try:
        exit_fd = os.pidfd_open(pid)  # readable once the coordinator exits: wall time to the millisecond
    except (AttributeError, OSError):
        exit_fd = None
    deadline = start + timeout_s
    try:
        status, usage = _watch(pid, exit_fd, res, deadline, grace_s, stop_event)
    finally:
        if exit_fd is not None:
            os.close(exit_fd)
    res.wall_s = time.monotonic() - start
    proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
    res.exit_code = proc.returncode
    res.cpu_s = usage.ru_utime + usage.ru_stime + res.extra_cpu
    return res


def _watch(pid, exit_fd, res, deadline, grace_s, stop_event):
    """Waits for the coordinator, stopping it on the deadline or on request; returns (status, rusage)."""
    int_sent_at = None
    res.extra_cpu = 0.0
    while True:
        got, status, usage = os.wait4(pid, os.WNOHANG)
        if got == pid:
            return status, usage
        now = time.monotonic()
        if int_sent_at is None and (now >= deadline or (stop_event is not None and stop_event.is_set())):
            res.timed_out = now >= deadline
            res.stopped = not res.timed_out
            _signal_group(pid, signal.SIGINT)
            _signal_group(pid, signal.SIGCONT)  # a stopped coordinator acts on SIGINT once continued
            int_sent_at = now
        elif int_sent_at is not None and not res.killed and now >= int_sent_at + grace_s:
            below = _descendants(pid)
            res.extra_cpu = sum(_cpu_seconds(p) for p in below)
            _signal_group(pid, signal.SIGKILL)
            for p in below:
                _signal_pid(p, signal.SIGCONT)
                _signal_pid(p, signal.SIGKILL)
            res.killed = True
        wake = deadline if int_sent_at is None else (int_sent_at + grace_s if not res.killed else now + POLL_S)
        wait = min(max(wake - time.monotonic(), 0.0), POLL_S)
        if exit_fd is not None:
            select.select([exit_fd], [], [], wait)
        else:
            time.sleep(min(wait, 0.01))


def _signal_group(pid, sig):
    try:
        os.killpg(pid, sig)  # the coordinator leads its own group (start_new_session)
    except (ProcessLookupError, PermissionError):
        _signal_pid(pid, sig)


def _signal_pid(pid, sig):
    try:
        os.kill(pid, sig)
    except (ProcessLookupError, PermissionError):
        pass


def _stat_fields(pid):
    try:
        with open(f"/proc/{pid}/stat") as f:
            text = f.read()
    except OSError:
        return None
    return text[text.rfind(")") + 2:].split()  # fields from 3 (state) on; the name may hold spaces


def _descendants(root):
    """Pids of every live process below `root` (children, their children, ...)."""
    children = {}
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        f = _stat_fields(name)
        if f is None:
            continue
        children.setdefault(int(f[1]), []).append(int(name))
    out, todo = [], list(children.get(root, []))
    while todo:
        p = todo.pop()
        out.append(p)
        todo += children.get(p, [])
    return out


def _cpu_seconds(pid):
    f = _stat_fields(pid)
    if f is None:
        return 0.0
    # utime, stime, cutime, cstime are fields 14..17 of /proc/PID/stat (f[0] is field 3)
    return sum(int(x) for x in f[11:15]) / CLK_TCK


def _quote(a):
    if a and all(c.isalnum() or c in "-_./=:,+[]" for c in a):
        return a
    return "'" + a.replace("'", "'\\''") + "'"

