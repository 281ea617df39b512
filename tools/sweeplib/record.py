"""What a finished run left behind, as result columns: how it ended, and what it cost.

Costs (docs/sweeps.md, "Columns"):
  particle_steps = fluid particles x sum over windows of fluid_substeps (walls and solid particles are not
                   counted, unless the fluid count falls back to the total: fluid_particle_count; a
                   predictor-corrector step counts once though it evaluates forces twice). The
                   record's fluid_substeps already sums the sub-steps of every implicit coupling iteration
                   (each re-runs the window from the saved state), so this is the work actually done.
  element_steps  = structure elements x sum over windows of structure_substeps;
  coupling_iterations = sum of /windows/iterations.
Either is left empty when the run has no such participant or recorded no window.
"""
import os
import signal

os.environ.setdefault("HDF5_USE_FILE_LOCKING", "FALSE")  # read records of killed writers, too

FLUID_COUNT_KEYS = ("fluid_particles", "n_fluid_particles", "particles_fluid", "num_fluid_particles")
TOTAL_COUNT_KEYS = ("particles", "n_particles", "particles_total", "num_particles", "total_particles")
ELEMENT_KEYS = ("elements", "n_elements", "num_elements")
STATUSES = ("completed", "failed", "timeout", "invalid", "interrupted")


def open_record(run_dir):
    import h5py
    return h5py.File(os.path.join(run_dir, "record.h5"), "r")


def summarize(run_dir, rr, timeout_s):
    """Columns for one run from its RunResult `rr` and what it wrote in `run_dir`."""
    row = {"exit_code": rr.exit_code, "wall_s": rr.wall_s, "cpu_s": rr.cpu_s}
    rec = {}
    if os.path.isfile(os.path.join(run_dir, "record.h5")):
        try:
            rec = read_record(run_dir)
        except Exception as err:  # a record damaged by a kill: say so, keep the row
            rec = {"record_error": f"record.h5 unreadable: {err}"}
    row.update({k: v for k, v in rec.items() if k not in ("record_status", "record_error")})
    stderr = ""
    try:
        with open(rr.stderr_path, errors="replace") as f:
            stderr = f.read()
    except OSError:
        pass
    record_status = rec.get("record_status") or ""
    t_end = rec.get("t_end")
    at = f" at t = {t_end:.6g} s" if t_end is not None else ""
    if rr.timed_out:
        row["status"] = "timeout"
        row["message"] = (f"no end within {timeout_s:g} s; stopped{at}"
                          + (" (SIGKILL: SIGINT was not obeyed)" if rr.killed else ""))
    elif rr.stopped:
        row["status"] = "interrupted"
        row["message"] = f"the sweep was interrupted; stopped{at}"
    elif rr.exit_code == 0:
        if record_status == "completed":
            row["status"], row["message"] = "completed", ""
        else:
            row["status"] = "failed"
            row["message"] = (f"exit status 0 but the record says {record_status!r}" if record_status
                              else "exit status 0 but " + (rec.get("record_error") or "no record.h5"))
    elif rr.exit_code == 2:
        row["status"], row["message"] = "invalid", invalid_message(stderr)
    elif rr.exit_code == 130:
        row["status"], row["message"] = "interrupted", first_line(record_status) or "interrupted" + at
    elif rr.exit_code is not None and rr.exit_code < 0:
        sig = -rr.exit_code
        try:
            name = signal.Signals(sig).name
        except ValueError:
            name = "?"
        row["status"], row["message"] = "failed", f"coordinator killed by signal {sig} ({name}){at}"
    else:
        row["status"] = "failed"
        msg = record_status[len("failed: "):] if record_status.startswith("failed: ") else ""
        msg = first_line(msg) or error_line(stderr) or f"exit status {rr.exit_code}"
        if rr.exit_code != 1:
            msg = f"exit status {rr.exit_code}: {msg}"
        row["message"] = msg
    if rec.get("record_error") and not row.get("message"):
        row["message"] = rec["record_error"]
    return row


def read_record(run_dir):
    """Status, end time and cost counters from record.h5 (any of them may be missing)."""
    out = {}
    with open_record(run_dir) as f:
        status = f.attrs.get("status")
        out["record_status"] = status.decode() if isinstance(status, bytes) else (str(status) if status is not None else "")
        if "wall_s" in f.attrs:
            out["record_wall_s"] = float(f.attrs["wall_s"])
        w = f.get("windows")
        sums = {}
        if w is not None and "t" in w and w["t"].shape[0] > 0:
            out["windows"] = int(w["t"].shape[0])
            out["t_end"] = float(w["t"][-1])
            for col in ("iterations", "fluid_substeps", "structure_substeps", "fluid_solver_iterations",
                        "structure_solver_iterations"):
                if col in w:
                    sums[col] = float(w[col][:].sum())
        else:
            out["windows"] = 0
        out["coupling_iterations"] = _int_or_none(sums.get("iterations"))
        parts = f.get("participants")
        fluid = parts.get("fluid") if parts is not None else None
        structure = parts.get("structure") if parts is not None else None
        if fluid is not None:
            out["fluid_particles"] = fluid_particle_count(f, fluid.attrs)
            out["particles_total"] = _first_attr(fluid.attrs, TOTAL_COUNT_KEYS) or _frame_rows(f, "fluid", "position")
            out["fluid_substeps"] = _int_or_none(sums.get("fluid_substeps"))
            out["fluid_solver_iterations"] = _int_or_none(sums.get("fluid_solver_iterations"))
            if "threads" in fluid.attrs:
                out["fluid_threads"] = int(fluid.attrs["threads"])
            if out["fluid_particles"] is not None and sums.get("fluid_substeps") is not None:
                out["particle_steps"] = int(round(out["fluid_particles"] * sums["fluid_substeps"]))
        if structure is not None:
            out["structure_elements"] = _first_attr(structure.attrs, ELEMENT_KEYS) or _frame_rows(f, "structure", "elements")
            out["structure_substeps"] = _int_or_none(sums.get("structure_substeps"))
            out["structure_solver_iterations"] = _int_or_none(sums.get("structure_solver_iterations"))
            if out["structure_elements"] is not None and sums.get("structure_substeps") is not None:
                out["element_steps"] = int(round(out["structure_elements"] * sums["structure_substeps"]))
    return out


def fluid_particle_count(f, attrs):
    """Fluid particles: a READY info key if there is one, else the kind == 0 rows of the first frame, else
    the total count (and then particle_steps counts walls too; docs/sweeps.md, "Columns", says so under
    particle_steps)."""
    n = _first_attr(attrs, FLUID_COUNT_KEYS)
    if n is not None:
        return n
    g = f.get("frames/fluid")
    if g is not None and "kind" in g and g["kind"].shape[0] > 0:
        return int((g["kind"][0][..., 0] == 0).sum())
    return _first_attr(attrs, TOTAL_COUNT_KEYS) or _frame_rows(f, "fluid", "position")


def _first_attr(attrs, keys):
    for k in keys:
        if k in attrs:
            try:
                return int(round(float(attrs[k])))
            except (TypeError, ValueError):
                continue
    return None


def _frame_rows(f, role, field):
    d = f.get(f"frames/{role}/{field}")
    if d is None or len(d.shape) < 2:
        return None
    return int(d.shape[1])


def _int_or_none(v):
    return None if v is None else int(round(v))


def first_line(text):
    for line in (text or "").splitlines():
        if line.strip():
            return line.strip()
    return ""


NOISE = ("listening on", " connected: ", "waiting for ")


def error_line(stderr):
    """The first line of stderr that says what went wrong, without the 'sphfsi: error: ' prefix."""
    for line in stderr.splitlines():
        s = line.strip()
        if not s or any(n in s for n in NOISE):
            continue
        for prefix in ("sphfsi: ", "error: "):
            if s.startswith(prefix):
                s = s[len(prefix):]
        if s:
            return s
    return ""


def invalid_message(stderr):
    """`sphfsi: invalid scene:` is followed by one line per mistake: the first, and how many more."""
    lines = [l.strip() for l in stderr.splitlines() if l.strip() and not any(n in l for n in NOISE)]
    if lines and lines[0].rstrip(":").endswith("invalid scene"):
        rest = lines[1:]
        if rest:
            return rest[0] + (f" (+{len(rest) - 1} more)" if len(rest) > 1 else "")
    return error_line(stderr) or "invalid scene"
