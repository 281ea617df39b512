"""Shared helpers for the integration tests: real processes on 127.0.0.1, every wait bounded.

Run a test file as  /usr/bin/python3 FILE --bin BUILD/bin [TEST_NAME ...]; with no names it runs all
its tests. Each test is a function named test_*; a failed assertion fails the process.
"""
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SCENES = os.path.join(HERE, "scenes")
PARTICIPANTS = os.path.join(ROOT, "tests", "participants")
sys.path.insert(0, PARTICIPANTS)

BIN = None
_test_dirs = []    # the output folders of the test now running: removed if it passes, kept and named if it fails
_shared_dirs = []  # folders several tests read: removed when the whole file passes


def sphfsi(*args, timeout=60, env=None, check=None, preexec_fn=None):
    """Runs the coordinator to completion; returns (exit code, stderr text). `preexec_fn` runs in the child
    before the coordinator starts (resource limits)."""
    e = dict(os.environ)
    e.update(env or {})
    p = subprocess.run([os.path.join(BIN, "sphfsi"), *args], capture_output=True, text=True, timeout=timeout, env=e,
                       preexec_fn=preexec_fn)
    if check is not None and p.returncode != check:
        raise AssertionError(f"sphfsi {' '.join(args)} exited {p.returncode}, expected {check}:\n{p.stderr}")
    return p.returncode, p.stdout + p.stderr


class Running:
    """A coordinator started in the background; a thread collects its stderr lines."""

    def __init__(self, *args, env=None):
        e = dict(os.environ)
        e.update(env or {})
        self.proc = subprocess.Popen([os.path.join(BIN, "sphfsi"), *args], stderr=subprocess.PIPE, stdout=subprocess.DEVNULL,
                                     text=True, env=e)
        self.lines = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self):
        for line in self.proc.stderr:
            self.lines.append(line.rstrip("\n"))

    def wait_for(self, needle, timeout=20):
        """Waits until a stderr line contains `needle`; returns that line."""
        end = time.time() + timeout
        seen = 0
        while time.time() < end:
            while seen < len(self.lines):
                if needle in self.lines[seen]:
                    return self.lines[seen]
                seen += 1
            if self.proc.poll() is not None and not self._reader.is_alive():
                break
            time.sleep(0.02)
        raise AssertionError(f"no line with {needle!r} within {timeout} s; got:\n" + "\n".join(self.lines))

    def finish(self, timeout=30):
        """Waits for exit; returns (code, all stderr)."""
        try:
            self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            raise AssertionError("coordinator did not exit within %s s" % timeout)
        self._reader.join(timeout=5)
        return self.proc.returncode, "\n".join(self.lines)


def pid_alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie is dead for our purposes
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(")")[-1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def participant_pid(line):
    """The pid from a 'ROLE connected: ... (pid N, ...' log line."""
    return int(line.split("(pid ")[1].split(",")[0])


def out_dir(name):
    """A fresh output folder for the running test. main() removes it when the test passes (a run's record is
    up to 40 MB, and a suite run makes about 200 of them) and keeps it, naming it, when the test fails."""
    path = tempfile.mkdtemp(prefix=f"sphfsi-{name}-")
    _test_dirs.append(path)
    return path


def shared_out_dir(name):
    """An output folder that several tests of one file read (a run made once for all of them): removed after
    the last test if every test passed, kept and named otherwise."""
    path = tempfile.mkdtemp(prefix=f"sphfsi-{name}-")
    _shared_dirs.append(path)
    return path


def record(path):
    import h5py
    # The writer may have been killed: open read-only, without file locking.
    os.environ.setdefault("HDF5_USE_FILE_LOCKING", "FALSE")
    return h5py.File(path, "r")


def main(module_globals):
    global BIN
    args = sys.argv[1:]
    if "--bin" in args:
        i = args.index("--bin")
        BIN = os.path.abspath(args[i + 1])
        del args[i:i + 2]
    assert BIN, "pass --bin BUILD_DIR/bin"
    names = args or sorted(n for n in module_globals if n.startswith("test_"))
    failed = 0
    for name in names:
        start = time.time()
        _test_dirs.clear()
        try:
            module_globals[name]()
            print(f"PASS {name} ({time.time() - start:.1f} s)")
            for path in _test_dirs:
                shutil.rmtree(path, ignore_errors=True)
        except Exception as e:  # report every failure, then fail the process
            failed += 1
            import traceback
            traceback.print_exc()
            print(f"FAIL {name}: {e}")
            for path in _test_dirs:
                print(f"  kept for inspection: {path}")
    for path in _shared_dirs:
        if failed:
            print(f"kept for inspection: {path}")
        else:
            shutil.rmtree(path, ignore_errors=True)
    print(f"{len(names) - failed} passed, {failed} failed")
    # Leave without the interpreter's finalization. A Running's daemon thread may still be blocked reading a
    # child's stderr (a participant can outlive its SIGKILLed coordinator for a moment and hold the pipe open),
    # and CPython can then abort at shutdown ("could not acquire lock ... at interpreter shutdown, possibly due
    # to daemon threads", python/cpython#86883). On 2026-11-27 integration.resume failed once in a full suite
    # run with no test failing and no folder kept for inspection, as that abort would; its output was not
    # kept, so the cause is likely, not proven.
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(1 if failed else 0)
