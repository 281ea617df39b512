#!/usr/bin/env -S /usr/bin/python3
"""Error metrics of a run, for sweeps (docs/sweeps.md, "Metrics").

A metric is  metric(run_dir, params, context) -> dict[str, float]  reading the run's record.h5 and
watchpoints.csv; params are the keys of its [[metric]] table; context gives the run's settings and the
other runs of the same sweep (for the "vs reference run" metrics). Each metric's docstring states its
formula and the source of its reference values. In the results CSV the quantities become columns
LABEL.QUANTITY (LABEL defaults to the metric's name).

usage:
  /usr/bin/python3 tools/metrics.py --list
  /usr/bin/python3 tools/metrics.py RUN_DIR METRIC [key=TOML_VALUE ...] [--reference REF_RUN_DIR]
e.g.
  tools/metrics.py out/beam watchpoint_mean_after watchpoint='"tip"' t_start=0.3 exact=-2.381e-4
A relative data_csv or reference_csv starts at the current folder here, and at the sweep file in a sweep.
"""
import math
import os
import sys
import tomllib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sweeplib import formula  # noqa: E402
from sweeplib.record import open_record  # noqa: E402

REQUIRED = object()
METRICS = {}


class MetricError(ValueError):
    """The metric cannot be computed for this run (missing data, bad parameters): the cell stays empty
    and the message goes to the row's notes."""


def metric(name, params, columns, errors, uses_reference=False):
    """Registers a metric. params: name -> default (REQUIRED if none); columns: quantity -> (meaning, unit);
    errors: the quantities that are errors (>= 0, lower is better): chart defaults and --print-expect."""
    def register(f):
        f.metric_name = name
        f.params = params
        f.columns = columns
        f.errors = tuple(errors)
        f.uses_reference = uses_reference
        METRICS[name] = f
        return f
    return register


class RunInfo:
    """What a metric may know about a run of the sweep."""

    def __init__(self, id, dir, status="", settings=None, overrides=None, case="", reference=False):
        self.id, self.dir, self.status, self.case, self.reference = id, dir, status, case, reference
        self.settings = dict(settings or {})
        self.overrides = dict(overrides or {})


class Context:
    """The run being measured, all runs of its sweep, and where relative paths in params start."""

    def __init__(self, run, runs=(), base_dir="."):
        self.run = run
        self.runs = list(runs)
        self.base_dir = base_dir

    @property
    def reference(self):
        refs = [r for r in self.runs if r.reference]
        return refs[0] if refs else None

    def resolve(self, path):
        return path if os.path.isabs(path) else os.path.normpath(os.path.join(self.base_dir, path))


# Parameters that are names or paths: on the command line their text is taken as typed (quotes optional).
TEXT_PARAMS = {"watchpoint", "component", "data_csv", "reference_csv", "participant", "key", "column", "reduce",
               "source", "mode"}


def check_params(name, params):
    """Raises MetricError for an unknown metric, an unknown parameter or a missing one."""
    if name not in METRICS:
        raise MetricError(f"unknown metric {name!r}; known: {', '.join(sorted(METRICS))}")
    f = METRICS[name]
    unknown = sorted(set(params) - set(f.params))
    if unknown:
        raise MetricError(f"metric {name}: unknown parameter(s) {', '.join(unknown)}; allowed: "
                          f"{', '.join(sorted(f.params))}")
    missing = [k for k, v in f.params.items() if v is REQUIRED and k not in params]
    if missing:
        raise MetricError(f"metric {name}: missing parameter(s) {', '.join(missing)}")


def compute(name, run_dir, params, context):
    """Runs metric `name` with defaults filled in; returns its dict (values as float)."""
    check_params(name, params)
    f = METRICS[name]
    full = {k: v for k, v in f.params.items() if v is not REQUIRED}
    full.update(params)
    out = f(run_dir, full, context)
    return {k: (int(v) if isinstance(v, (int, np.integer)) and not isinstance(v, bool) else float(v))
            for k, v in out.items()}


# ---------------------------------------------------------------------------------------------------
# Reading helpers


def watchpoint_rows(path):
    """The whole rows of a watchpoints.csv as dicts of time, name, x, y, dx, dy (floats but name), by the
    coordinator's own rule on resume (coordinator/src/watchpoints.cpp): a row ends in a newline, has six
    fields and numbers where numbers belong, and reading stops at the first one that does not (a kill can
    cut the last row short; half a number would be a wrong value, not a missing one)."""
    with open(path, newline="") as f:
        lines = f.read().split("\n")
    rows = []
    for line in lines[1:-1]:  # the header, and after the last newline nothing or a row cut short
        fields = line.split(",")
        if len(fields) != 6:
            break
        try:
            t, x, y, dx, dy = (float(fields[i]) for i in (0, 2, 3, 4, 5))
        except ValueError:
            break
        rows.append({"time": t, "name": fields[1], "x": x, "y": y, "dx": dx, "dy": dy})
    return rows


def watchpoint_series(run_dir, name, component):
    """(t, value) of one watchpoint from watchpoints.csv; component is dx, dy, x, y or magnitude
    (sqrt(dx^2 + dy^2)). A time written twice (a resumed run) keeps its last row."""
    path = os.path.join(run_dir, "watchpoints.csv")
    if not os.path.isfile(path):
        raise MetricError(f"{path}: no such file (the scene needs a [[watchpoint]])")
    rows = {}
    names = set()
    if component not in ("dx", "dy", "x", "y", "magnitude"):
        raise MetricError(f"component {component!r}; allowed: dx, dy, x, y, magnitude")
    for r in watchpoint_rows(path):
        names.add(r["name"])
        if r["name"] == name:
            rows[r["time"]] = math.hypot(r["dx"], r["dy"]) if component == "magnitude" else r[component]
    if not rows:
        raise MetricError(f"no watchpoint {name!r} in {path} (has: {', '.join(sorted(names)) or 'none'})")
    t = np.array(sorted(rows))
    return t, np.array([rows[x] for x in t])


def time_mean(t, v, t0, t1):
    """(1 / (t1 - t0)) * integral of the piecewise-linear v(t) over [t0, t1] (trapezoidal, exact for it)."""
    if not t1 > t0:
        raise MetricError(f"empty averaging window [{t0}, {t1}]")
    if t0 < t[0] - 1e-12 or t1 > t[-1] + 1e-9 * max(1.0, abs(t[-1])):
        raise MetricError(f"averaging window [{t0:g}, {t1:g}] s is not inside the recorded [{t[0]:g}, {t[-1]:g}] s")
    t1 = min(t1, t[-1])
    inside = (t > t0) & (t < t1)
    tt = np.concatenate([[t0], t[inside], [t1]])
    vv = np.interp(tt, t, v)
    return float(np.trapz(vv, tt) / (t1 - t0))


def _exact(params, context, key="exact"):
    try:
        return formula.exact_value(params, context.run.overrides if context and context.run else {}, key)
    except formula.FormulaError as err:
        raise MetricError(str(err)) from None


def _errors(value, exact):
    err = abs(value - exact)
    return {"value": value, "exact": exact, "abs_error": err,
            "rel_error": err / abs(exact) if exact != 0 else math.nan}


VALUE_COLUMNS = {
    "value": ("the measured value", "as the quantity"),
    "exact": ("the analytic value it is compared with", "as the quantity"),
    "abs_error": ("|value - exact|", "as the quantity"),
    "rel_error": ("|value - exact| / |exact|", "-"),
}
VALUE_ERRORS = ("rel_error", "abs_error")
EXACT_PARAMS = {"exact": REQUIRED, "constants": {}, "bind": {}}


# ---------------------------------------------------------------------------------------------------
# Metrics


@metric("watchpoint_final", dict(watchpoint=REQUIRED, component="dy", **EXACT_PARAMS), VALUE_COLUMNS, VALUE_ERRORS)
def watchpoint_final(run_dir, params, context):
    """A watchpoint's displacement at the last recorded time, against an analytic value.

    value = u(t_last) of watchpoint `watchpoint`, component `component` (dx, dy, x, y, magnitude);
    abs_error = |value - exact|, rel_error = abs_error / |exact|. `exact` is a number or a formula
    (sweeplib/formula.py) with `constants` and `bind` (names bound to the run's override values), e.g. the
    cantilever's static tip deflection P L^3 / (3 E I) (Euler-Bernoulli beam theory) for a run started in
    static equilibrium. For a dynamic response prefer watchpoint_mean_after.
    """
    t, v = watchpoint_series(run_dir, params["watchpoint"], params["component"])
    return _errors(float(v[-1]), _exact(params, context))


@metric("watchpoint_mean_after",
        dict(watchpoint=REQUIRED, component="dy", t_start=REQUIRED, t_end=None, **EXACT_PARAMS),
        dict(VALUE_COLUMNS, value=("time mean of the watchpoint over [t_start, t_end]", "as the quantity")),
        VALUE_ERRORS)
def watchpoint_mean_after(run_dir, params, context):
    """A watchpoint's settled mean over a time window, against an analytic static value.

    value = (1 / (t1 - t0)) * integral_{t0}^{t1} u(t) dt, with u the watchpoint component linearly
    interpolated between recorded windows (trapezoidal rule, exact for that interpolant), t0 = t_start,
    t1 = t_end (default: the last recorded time; the run must reach it). abs_error = |value - exact|,
    rel_error = abs_error / |exact|.

    Analytic values, e.g.: cantilever tip under a tip load P: w = P L^3 / (3 E I) (Euler-Bernoulli);
    a clamped-clamped plate strip under water of depth H: w = -(rho_f g H + rho_s g t) L^4 / (384 D),
    D = E t^3 / (12 (1 - nu^2)) (Timoshenko & Woinowsky-Krieger, cylindrical bending).
    A damped oscillation about the static value biases the mean by at most its amplitude divided by
    (omega (t1 - t0)): average over many periods, or start the run in static equilibrium.
    """
    t, v = watchpoint_series(run_dir, params["watchpoint"], params["component"])
    t1 = t[-1] if params.get("t_end") is None else float(params["t_end"])
    out = _errors(time_mean(t, v, float(params["t_start"]), t1), _exact(params, context))
    return out


@metric("watchpoint_vs_reference_run",
        dict(watchpoint=REQUIRED, component="dy", t_start=None, t_end=None, min_common=10),
        {"l2_rel": ("RMS in time of (u - u_ref) / max |u_ref|", "-"),
         "max_rel": ("max |u - u_ref| / max |u_ref|", "-"),
         "n_times": ("number of compared times", "-")},
        ("l2_rel", "max_rel"), uses_reference=True)
def watchpoint_vs_reference_run(run_dir, params, context):
    """Difference of a watchpoint time series from the sweep's reference run (e.g. the finest one).

    Times: the times present in both series (matching within 1e-9 max(1 s, t_end); every run has a window ending on
    each output time, so these are at least the frame times); if fewer than `min_common`, the reference is
    linearly interpolated at this run's times instead. Only times in [t_start, t_end] (default: the
    overlap of both runs) count. With e = u - u_ref and S = max |u_ref| over those times:
        l2_rel  = sqrt( integral e^2 dt / integral dt ) / S   (trapezoidal over the compared times)
        max_rel = max |e| / S
    The reference run itself gets no value. This is a self-convergence measure: it says how far a run is
    from the best one the sweep has, not from the truth; with a reference far finer than the others,
    the observed order of a method is log(e1 / e2) / log(h1 / h2).
    """
    ref = context.reference if context else None
    if ref is None:
        raise MetricError("no reference run: mark one [[case]] with reference = true")
    if os.path.abspath(ref.dir) == os.path.abspath(run_dir):
        return {}
    if ref.status and ref.status != "completed":
        raise MetricError(f"the reference run {ref.id} did not complete ({ref.status})")
    t, v = watchpoint_series(run_dir, params["watchpoint"], params["component"])
    tr, vr = watchpoint_series(ref.dir, params["watchpoint"], params["component"])
    lo = max(t[0], tr[0]) if params.get("t_start") is None else float(params["t_start"])
    hi = min(t[-1], tr[-1]) if params.get("t_end") is None else float(params["t_end"])
    tol = 1e-9 * max(1.0, abs(hi))
    if hi > min(t[-1], tr[-1]) + tol or lo < max(t[0], tr[0]) - tol:
        raise MetricError(f"window [{lo:g}, {hi:g}] s is not covered by both runs "
                          f"(run [{t[0]:g}, {t[-1]:g}], reference [{tr[0]:g}, {tr[-1]:g}])")
    sel = (t >= lo - tol) & (t <= hi + tol)
    ts, vs = t[sel], v[sel]
    j = np.clip(np.searchsorted(tr, ts), 1, len(tr) - 1)
    nearest = np.where(np.abs(tr[j - 1] - ts) <= np.abs(tr[j] - ts), j - 1, j)
    common = np.abs(tr[nearest] - ts) <= tol
    if common.sum() >= params["min_common"]:
        tc, e, ref_vals = ts[common], vs[common] - vr[nearest[common]], vr[nearest[common]]
    else:
        tc, ref_vals = ts, np.interp(ts, tr, vr)
        e = vs - ref_vals
    if len(tc) < 2:
        raise MetricError("fewer than 2 times to compare")
    scale = float(np.max(np.abs(ref_vals)))
    if scale == 0:
        raise MetricError("the reference series is zero over the window")
    l2 = math.sqrt(float(np.trapz(e * e, tc)) / float(tc[-1] - tc[0]))
    return {"l2_rel": l2 / scale, "max_rel": float(np.max(np.abs(e))) / scale, "n_times": len(tc)}


@metric("watchpoint_vs_data",
        dict(watchpoint=REQUIRED, data_csv=REQUIRED, component="dy", t_start=None, t_end=None),
        {"l2_rel": ("RMS over the data points of (u - u_data) / max |u_data|", "-"),
         "max_rel": ("max |u - u_data| / max |u_data|", "-"),
         "rms_abs": ("RMS over the data points of u - u_data", "m"),
         "max_abs": ("max |u - u_data|", "m"),
         "n_points": ("data points compared", "-")},
        ("l2_rel", "max_rel"))
def watchpoint_vs_data(run_dir, params, context):
    """A watchpoint time series against measured or published data, e.g. the elastic gate's tip
    displacement against Antoci, Gallati & Sibilla (2007) (scenarios/reference/antoci2007_gate_tip_dx.csv).

    data_csv: two columns, time [s] and the value, after '#' comment lines and a header (a relative path
    starts at the sweep file; on the command line, at the current folder). The run's series is
    interpolated linearly at each data time t_k in [t_start, t_end] (default: all data); the run must
    cover those times (no extrapolation). With
    e_k = u(t_k) - u_data,k and S = max_k |u_data,k|:
        rms_abs = sqrt(mean_k e_k^2),  max_abs = max_k |e_k|,  l2_rel = rms_abs / S,  max_rel = max_abs / S
    The mean is over data points, not time-weighted: digitised curves are sampled where the digitiser
    clicked, and each point counts once. Time is never shifted.
    """
    path = context.resolve(params["data_csv"]) if context else params["data_csv"]
    td, ud = read_reference_curve(path)
    lo = td[0] if params.get("t_start") is None else float(params["t_start"])
    hi = td[-1] if params.get("t_end") is None else float(params["t_end"])
    keep = (td >= lo) & (td <= hi)
    td, ud = td[keep], ud[keep]
    if td.size == 0:
        raise MetricError(f"no data point in [{lo:g}, {hi:g}] s")
    t, v = watchpoint_series(run_dir, params["watchpoint"], params["component"])
    tol = 1e-9 * max(1.0, abs(td[-1]))
    if td[0] < t[0] - tol or td[-1] > t[-1] + tol:
        raise MetricError(f"the run covers [{t[0]:g}, {t[-1]:g}] s, the data [{td[0]:g}, {td[-1]:g}] s")
    e = np.interp(td, t, v) - ud
    scale = float(np.max(np.abs(ud)))
    rms, mx = math.sqrt(float(np.mean(e * e))), float(np.max(np.abs(e)))
    return {"l2_rel": rms / scale if scale else math.nan, "max_rel": mx / scale if scale else math.nan,
            "rms_abs": rms, "max_abs": mx, "n_points": int(td.size)}


@metric("participant_info",
        dict(participant="structure", key=REQUIRED, **EXACT_PARAMS),
        dict(VALUE_COLUMNS, value=("the participant's READY info value", "as the quantity")), VALUE_ERRORS)
def participant_info(run_dir, params, context):
    """A number a participant reported at READY (record.h5 /participants/ROLE attributes) against an
    analytic value, e.g. the structure's first natural frequency `natural_frequencies_hz.mode_1` against
    the Euler-Bernoulli cantilever's f1 = (1.8751041^2 / (2 pi L^2)) sqrt(E I / (rho A)) (e.g. Blevins,
    Formulas for Natural Frequency and Mode Shape, 1979, ch. 8). abs_error = |value - exact|,
    rel_error = abs_error / |exact|.
    """
    with open_record(run_dir) as f:
        g = f.get(f"participants/{params['participant']}")
        if g is None:
            raise MetricError(f"no participant {params['participant']!r} in the record")
        if params["key"] not in g.attrs:
            raise MetricError(f"participant {params['participant']} has no info {params['key']!r} "
                              f"(has: {', '.join(sorted(g.attrs))})")
        value = float(g.attrs[params["key"]])
    return _errors(value, _exact(params, context))


def windows_after(window_end, t_start):
    """Which windows (by their end times) end after t_start: one ending at t_start lies wholly before it.
    A relative 1e-12 is allowed for round-off in the recorded times."""
    return window_end > float(t_start) * (1 + 1e-12)


@metric("window_stat", dict(column=REQUIRED, reduce="max", absolute=False, t_start=None, t_end=None),
        {"value": ("the reduced /windows column", "as the column")}, ("value",))
def window_stat(run_dir, params, context):
    """A reduction (sum, max, min, mean, last) of one /windows column, e.g. the largest coupling
    residual or the mean number of coupling iterations; `absolute` takes |x| first; windows ending at or
    before t_start (they lie wholly before it) or after t_end are left out; both bounds allow a relative
    1e-12 for round-off in the recorded times. value = reduce(x over windows)."""
    with open_record(run_dir) as f:
        w = f.get("windows")
        if w is None or params["column"] not in w:
            raise MetricError(f"no /windows/{params['column']} in the record")
        x = w[params["column"]][:]
        t = w["t"][:]
    keep = np.ones(x.shape, dtype=bool)
    if params.get("t_start") is not None:
        keep &= windows_after(t, params["t_start"])
    if params.get("t_end") is not None:
        keep &= t <= float(params["t_end"]) * (1 + 1e-12)
    x = x[keep]
    if params["absolute"]:
        x = np.abs(x)
    if x.size == 0:
        raise MetricError("no window to reduce")
    ops = {"sum": np.sum, "max": np.max, "min": np.min, "mean": np.mean, "last": lambda a: a[-1]}
    if params["reduce"] not in ops:
        raise MetricError(f"reduce {params['reduce']!r}; allowed: {', '.join(ops)}")
    return {"value": float(ops[params["reduce"]](x))}


DENSITY_WINDOW_COLUMNS = ("fluid.max_density_error", "fluid_max_density_error", "max_density_error", "fluid_density_error")


@metric("max_density_error", dict(rho0=None, t_start=None, source="auto", mode="compression"),
        {"max": ("largest density error of a fluid particle (see mode)", "-"),
         "mean": ("mean over windows (or frames) of the largest density error", "-")}, ("max", "mean"))
def max_density_error(run_dir, params, context):
    """Compressibility error: the largest density error of a fluid particle over the run.

    mode = "compression" (default): e_i = max(rho_i / rho0 - 1, 0), the measure PCISPH's eta and WCSPH's
    1 % rule bound; "absolute": e_i = |rho_i / rho0 - 1|, which also counts the density deficit of
    free-surface particles under summation densities (kernel truncation: down to about 0.5 rho0 on the
    surface of a dam break at any resolution), not a compressibility error.
    source = "windows": the participant's per-window statistic (a /windows column named in
    DENSITY_WINDOW_COLUMNS: every sub-step is seen; mode does not apply, the participant's definition
    does); "frames": from /frames/fluid/density of fluid particles (kind == 0) at the recorded frames
    only; "auto": windows if present, else frames. rho0: the param, else the fluid's READY info `rho0`,
    else 1000 kg/m^3. Windows ending at or before t_start (as in window_stat) and frames before it are left out.
        max = max over time of max_i e_i,   mean = mean over windows/frames of max_i e_i
    """
    t_start = params.get("t_start")
    if params["source"] not in ("auto", "windows", "frames"):
        raise MetricError(f"source {params['source']!r}; allowed: auto, windows, frames")
    if params["mode"] not in ("compression", "absolute"):
        raise MetricError(f"mode {params['mode']!r}; allowed: compression, absolute")
    with open_record(run_dir) as f:
        w = f.get("windows")
        col = next((c for c in DENSITY_WINDOW_COLUMNS if w is not None and c in w), None)
        if params["source"] == "windows" and col is None:
            raise MetricError("no per-window density error column in /windows")
        if col is not None and params["source"] != "frames":
            per = np.abs(w[col][:])
            if t_start is not None:
                per = per[windows_after(w["t"][:], t_start)]
        else:
            g = f.get("frames/fluid")
            if g is None or "density" not in g or "kind" not in g:
                raise MetricError("no /frames/fluid/density and kind in the record")
            rho0 = params.get("rho0")
            if rho0 is None:
                fl = f.get("participants/fluid")
                rho0 = float(fl.attrs["rho0"]) if fl is not None and "rho0" in fl.attrs else 1000.0
            times = g["time"][:]
            per = []
            for i in range(len(times)):
                if t_start is not None and times[i] < float(t_start):
                    continue
                kind = g["kind"][i][..., 0]
                e = g["density"][i][..., 0][kind == 0] / float(rho0) - 1.0
                if e.size:
                    per.append(float(np.max(np.abs(e))) if params["mode"] == "absolute"
                               else max(float(np.max(e)), 0.0))
            per = np.array(per)
    if per.size == 0:
        raise MetricError("no window or frame to measure")
    return {"max": float(per.max()), "mean": float(per.mean())}


def read_reference_curve(path):
    """Two numeric columns after '#' comment lines and an optional header line (e.g. T,Z), in increasing
    order of the first. Every other line must be exactly two comma-separated finite numbers; anything else
    is an error naming the file and line, not skipped. The header is the first line only, and only when
    it has two fields and neither is a number: a first row of data that fails to parse (a third column,
    another separator, e.g. 0.0;1.0) had been taken for the header and silently lost, and a three-column
    file had been read as its first two."""
    xs, ys = [], []
    seen_line = False
    with open(path) as f:
        for number, line in enumerate(f, 1):
            s = line.strip()
            if not s or s.startswith("#"):
                continue
            first, seen_line = not seen_line, True
            parts = [p.strip() for p in s.split(",")]
            if len(parts) != 2:
                raise MetricError(f"{path}:{number}: {len(parts)} comma-separated field(s), not 2 "
                                  f"(time and value): {s!r}")
            values = []
            for p in parts:
                try:
                    values.append(float(p))
                except ValueError:
                    values.append(None)
            if first and values == [None, None]:
                continue  # the header
            if None in values:
                raise MetricError(f"{path}:{number}: not two numbers"
                                  + (" (a header has no number in it)" if first else "") + f": {s!r}")
            if not all(math.isfinite(v) for v in values):
                raise MetricError(f"{path}:{number}: not finite: {s!r}")
            xs.append(values[0])
            ys.append(values[1])
    if not xs:
        raise MetricError(f"{path}: no data rows")
    if any(b <= a for a, b in zip(xs, xs[1:])):
        raise MetricError(f"{path}: the first column must increase from row to row")
    return np.array(xs), np.array(ys)


def reference_points(params, context, time_name):
    """The rows of params["reference_csv"] (resolved against context.base_dir: the sweep file's folder, or on
    the command line the current folder) up to params[time_name + "_max"]."""
    x, y = read_reference_curve(context.resolve(params["reference_csv"]) if context else params["reference_csv"])
    x_max = float(params[time_name + "_max"])
    keep = x <= x_max
    if not keep.any():
        raise MetricError(f"no reference point with {time_name} <= {x_max}")
    return x[keep], y[keep]


def relative_errors(x_ref, y_ref, x, y, time_name):
    """(y - y_ref) / y_ref at each reference point, the measured curve y(x) interpolated linearly over its
    finite points; the curve must cover the first and the last of them (never extrapolated)."""
    ok = np.isfinite(y)
    x, y = x[ok], y[ok]
    if x.size < 2 or x[-1] < x_ref[-1] - 1e-9:
        raise MetricError(f"the frames reach {time_name} = {x[-1] if x.size else 0:.3g}, not the last reference "
                          f"point {time_name} = {x_ref[-1]:.3g}")
    if x[0] > x_ref[0] + 1e-9:
        raise MetricError(f"the frames with a value start at {time_name} = {x[0]:.3g}, after the first reference "
                          f"point {time_name} = {x_ref[0]:.3g}")
    return (np.interp(x_ref, x, y) - y_ref) / y_ref


def compare_with_reference(x_ref, y_ref, x, y, time_name):
    """Mean, largest and signed mean of relative_errors."""
    rel = relative_errors(x_ref, y_ref, x, y, time_name)
    return {"mean_rel": float(np.mean(np.abs(rel))), "max_rel": float(np.max(np.abs(rel))),
            "mean_signed_rel": float(np.mean(rel)), "n_points": int(x_ref.size)}


def outermost(p, axis, dp, k=1, radius_dp=1.5):
    """Largest coordinate `axis` among the points p (n x 2) that have at least k others within radius_dp * dp:
    a lone droplet or a pair thrown off the water does not count as its edge."""
    if len(p) == 0:
        return math.nan
    if k <= 0:
        return float(p[:, axis].max())
    r = radius_dp * dp
    order = np.argsort(p[:, axis])
    cs = p[order, axis]
    for idx in order[::-1]:
        c = p[idx, axis]
        lo, hi = np.searchsorted(cs, c - r), np.searchsorted(cs, c + r, side="right")
        near = p[order[lo:hi]]
        n = int(np.count_nonzero(np.sum((near - p[idx]) ** 2, axis=1) <= r * r)) - 1
        if n >= k:
            return float(c)
    return math.nan


def fluid_spacing(f, dp):
    """dp as given, else the particle spacing the fluid reported at READY (/participants/fluid attribute dp)."""
    if dp is not None:
        return float(dp)
    fl = f.get("participants/fluid")
    if fl is None or "dp" not in fl.attrs:
        raise MetricError("no particle spacing: give dp (the fluid reported none)")
    return float(fl.attrs["dp"])


def fluid_frames(run_dir, dp, time_scale, time_max=None):
    """(time * time_scale, fluid particle positions, dp) for each recorded fluid frame, up to the first one
    past time_max (enough to interpolate at time_max). dp: as given, else the fluid's READY info."""
    with open_record(run_dir) as f:
        grp = f.get("frames/fluid")
        if grp is None or "position" not in grp or "kind" not in grp:
            raise MetricError("no /frames/fluid/position and kind in the record")
        dp = fluid_spacing(f, dp)
        times = grp["time"][:] * time_scale
        for i, t in enumerate(times):
            if time_max is not None and i > 0 and times[i - 1] > time_max:
                return
            yield t, grp["position"][i][grp["kind"][i][..., 0] == 0], dp


def surge_front_series(run_dir, a, g=9.81, x0=0.0, dp=None, k=1, radius_dp=1.5, extent_dp=0.5, T_max=None):
    """(T, Z) of the dam-break surge front at the recorded fluid frames: T = t sqrt(2 g / a),
    Z = (x_front + extent_dp * dp - x0) / a, x_front the largest x of a fluid particle centre with k others
    within radius_dp * dp."""
    T, Z = [], []
    for Ti, fluid, dp in fluid_frames(run_dir, dp, math.sqrt(2.0 * g / a), T_max):
        T.append(Ti)
        Z.append((outermost(fluid, 0, dp, k, radius_dp) + extent_dp * dp - x0) / a)
    return np.array(T), np.array(Z)


@metric("surge_front",
        dict(a=REQUIRED, reference_csv=REQUIRED, T_max=2.5, g=9.81, x0=0.0, dp=None, k_neighbours=1,
             radius_dp=1.5, extent_dp=0.5),
        {"mean_rel": ("mean over reference points of |Z - Z_exp| / Z_exp", "-"),
         "max_rel": ("largest |Z - Z_exp| / Z_exp", "-"),
         "mean_signed_rel": ("mean of (Z - Z_exp) / Z_exp: > 0 when the simulation leads", "-"),
         "n_points": ("reference points compared (T <= T_max)", "-")},
        ("mean_rel", "max_rel"))
def surge_front(run_dir, params, context):
    """Dam-break surge front against Martin & Moyce (1952).

    Front: x_front = the largest x of a fluid particle (/frames/fluid/kind == 0) that has at least
    k_neighbours other fluid particles within radius_dp * dp (defaults 1 and 1.5: a lone droplet thrown
    ahead of the surge has none, while a particle of the surge, even at a one-particle-thick tip, has the
    one behind it at about dp; a percentile of x would instead depend on the particle count), plus
    extent_dp * dp (a particle centre sits half a spacing inside the water it represents). Measured on a
    WCSPH dam break at dp = a/40: tip particles have 1 to 3 neighbours within 1.5 dp; k = 0 and 1 give the
    same front at every reference point, k = 2 moved one point back by 0.5 dp, k = 3 by up to 1.5 dp.
    Z = (x_front - x0) / a with a the initial column width and x0 the back wall, T = t sqrt(2 g / a)
    (Martin & Moyce's T = n t sqrt(g / a) with n^2 = 2); time is never shifted or scaled otherwise.
    Z_sim is linearly interpolated between frames at each reference T <= T_max; the frames must reach
    the last of those points (T = 2.32 for T_max = 2.5). Record often enough: output_interval <= 0.1 sqrt(a / (2 g)) is Delta T <= 0.1 between frames,
    over which the front moves less than the data's own resolution (0.22 a, fronts timed at 0.5 in marks).
        mean_rel = mean |Z_sim - Z_exp| / Z_exp,  max_rel = max |Z_sim - Z_exp| / Z_exp
    Reference: Martin, J. C. & Moyce, W. J. (1952), Phil. Trans. R. Soc. A 244, 312-324, tables 2 and 6,
    n^2 = 2 (reference_csv: columns T,Z after '#' lines, e.g. tests/fluid/data/martin_moyce_1952_front_n2_2.csv).
    Simulations released at once lead it by 10-20 % for 0.8 < T < 2.3, commonly put down to its gate; a
    modelled gate does not reproduce that, and the experiment's column height (column_height) says a late
    release explains at most a third of it (docs/validation.md, "Dam break").
    """
    Tref, Zref = reference_points(params, context, "T")
    T, Z = surge_front_series(run_dir, float(params["a"]), float(params["g"]), float(params["x0"]),
                              params.get("dp"), int(params["k_neighbours"]), float(params["radius_dp"]),
                              float(params["extent_dp"]), float(params["T_max"]))
    return compare_with_reference(Tref, Zref, T, Z, "T")


def column_height_series(run_dir, a, n2=2.0, g=9.81, x0=0.0, y0=0.0, dp=None, band_dp=2.0, k=1, radius_dp=1.5,
                         extent_dp=0.5, tau_max=None):
    """(tau, Hn) of the dam-break column at the back wall at the recorded fluid frames: tau = t sqrt(g / a),
    Hn = (y_top + extent_dp * dp - y0) / (n2 a), y_top the highest fluid particle centre within band_dp * dp
    of the back wall x0 that has k others of that band within radius_dp * dp."""
    tau, H = [], []
    for ti, fluid, dp in fluid_frames(run_dir, dp, math.sqrt(g / a), tau_max):
        band = fluid[fluid[:, 0] - x0 <= band_dp * dp]
        tau.append(ti)
        H.append((outermost(band, 1, dp, k, radius_dp) + extent_dp * dp - y0) / (n2 * a))
    return np.array(tau), np.array(H)


@metric("column_height",
        dict(a=REQUIRED, reference_csv=REQUIRED, tau_max=2.5, n2=2.0, g=9.81, x0=0.0, y0=0.0, dp=None,
             band_dp=2.0, k_neighbours=1, radius_dp=1.5, extent_dp=0.5),
        {"mean_rel": ("mean over reference points of |H - H_exp| / H_exp", "-"),
         "max_rel": ("largest |H - H_exp| / H_exp", "-"),
         "mean_signed_rel": ("mean of (H - H_exp) / H_exp: < 0 when the simulated column falls faster", "-"),
         "n_points": ("reference points compared (tau <= tau_max)", "-")},
        ("mean_rel", "max_rel"))
def column_height(run_dir, params, context):
    """Dam break: the height of the collapsing column at the back wall against Martin & Moyce (1952).

    Height: the highest fluid particle centre within band_dp * dp of the back wall x0 (default 2: the first
    two columns of particles), counted only with k_neighbours others of that band within radius_dp * dp (so
    a droplet does not count), plus extent_dp * dp; Hn = height / (n2 a), the fraction of the initial height
    n2 a left, against tau = t sqrt(g / a) (Martin & Moyce's time for this table: no factor n, unlike the
    front's T). Time is never shifted or scaled otherwise; Hn is interpolated between frames.
    Why two columns: with no-slip walls and artificial viscosity the particles touching the wall sit below
    the water beside them, in single frames by up to a quarter of the height, while two and four columns
    agree within 8 %; with free-slip walls one, two and four columns agree within 2 % (5 % in one frame).
    Measured on every run of sweeps/dam_break_walls.toml, tau <= 2.5.
    tau_max = 2.5 (t = 0.25 s at a = 0.1 m) ends before the surge reaches the far wall of
    scenarios/dam_break.toml (5 a away, at t = 0.26 s); the paper's tank length is not in our data.
    Reference: Martin, J. C. & Moyce, W. J. (1952), Phil. Trans. R. Soc. A 244, 312-324, tables 2 and 6,
    n^2 = 2 (reference_csv: columns tau,Hn after '#' lines, e.g. tests/fluid/data/martin_moyce_1952_height_n2_2.csv).
    The column's fall is the first place a late release of the experiment's column would show, and it does
    not depend on how the front's thin tip meets the floor.
    """
    tref, href = reference_points(params, context, "tau")
    tau, H = column_height_series(run_dir, float(params["a"]), float(params["n2"]), float(params["g"]),
                                  float(params["x0"]), float(params["y0"]), params.get("dp"),
                                  float(params["band_dp"]), int(params["k_neighbours"]),
                                  float(params["radius_dp"]), float(params["extent_dp"]), float(params["tau_max"]))
    return compare_with_reference(tref, href, tau, H, "tau")


@metric("wind_basin_profile",
        dict(tau=REQUIRED, depth=REQUIRED, nu=REQUIRED, x_from=REQUIRED, x_to=REQUIRED, t_from=REQUIRED,
             t_to=None, rho0=1000.0, g=9.81, dp=None),
        {"l2_rel": ("relative L2 error of the time-averaged u over layers of the local depth", "-"),
         "velocity_scale": ("least-squares k in u = k u_exact: below 1 when the flow is too slow", "-"),
         "setup_ratio": ("d(p + rho g y)/dx over the section, over 3 tau / (2 h) at its centre", "-"),
         "depth_ratio": ("the measured depth at the section's centre over depth", "-"),
         "frames": ("frames averaged", "-")},
        ("l2_rel",))
def wind_basin_profile(run_dir, params, context):
    """Steady wind-driven flow in a closed basin: the mid-basin velocity profile and set-up.

    Reference (lubrication theory of a closed basin under a surface stress tau, no-slip flat bottom at y = 0,
    zero net flux through every section; e.g. the shallow-lake paper, any text on wind set-up): where the
    water is h(x) deep, u(y) = tau h / (4 mu) (3 s^2 - 2 s), s = y / h, mu = rho0 nu, driven by the set-up's
    pressure gradient d(p + rho g y)/dx = 3 tau / (2 h).
    The depth is the local one: the set-up tilts the surface (slope 3 tau / (2 rho g h), 1.9 % in
    scenarios/wind_basin.toml), so over a section 0.2 m long the depth varies by +-5 %, and a particle at a
    fixed height is at a different s at each end. In each frame h(x) is a straight-line fit, over the
    section, of its columns' depths (the fluid volume rho0 dp^2 / rho per column dp wide, over dp).
    Measured over the fluid particles with x_from < x < x_to (away from the end walls by a few depths, where
    the flow is parallel) in the frames with t_from <= t <= t_to: u and the exact value at each particle are
    averaged in round(depth / dp) layers of s (s >= 1 in the top layer), and
        l2_rel = sqrt(sum (u - u_exact)^2 / sum u_exact^2),  velocity_scale = sum u u_exact / sum u_exact^2;
    setup_ratio: the slope of a straight-line fit of p + rho g y against x over the section's particles more
    than 2 dp below the surface (away from the surface layer, whose kernels are cut), over 3 tau / (2 h_c) with
    h_c the mean fitted depth at the section's centre; depth_ratio = h_c / depth (a check of the parameters:
    depth is the basin's mean depth, which the centre keeps to first order).
    """
    tau, D, nu = float(params["tau"]), float(params["depth"]), float(params["nu"])
    rho0, g = float(params["rho0"]), float(params["g"])
    x_from, x_to, t_from = float(params["x_from"]), float(params["x_to"]), float(params["t_from"])
    t_to = math.inf if params.get("t_to") is None else float(params["t_to"])
    mu = rho0 * nu
    x_mid = 0.5 * (x_from + x_to)
    with open_record(run_dir) as f:
        grp = f.get("frames/fluid")
        if grp is None or not all(k in grp for k in ("position", "velocity", "kind", "pressure", "density")):
            raise MetricError("no /frames/fluid position, velocity, kind, pressure and density in the record")
        dp = fluid_spacing(f, params.get("dp"))
        times = grp["time"][:]
        frames = [i for i, t in enumerate(times) if t_from - 1e-12 <= t <= t_to + 1e-12]
        if not frames:
            raise MetricError(f"no frame with {t_from} <= t <= {t_to} (frames reach t = {times[-1]:.4g})")
        columns = max(2, int(round((x_to - x_from) / dp)))
        column_x = x_from + (np.arange(columns) + 0.5) * (x_to - x_from) / columns
        layers = max(1, int(round(D / dp)))
        u_sum, exact_sum, count = np.zeros(layers), np.zeros(layers), np.zeros(layers)
        xs, heads, centre_depths = [], [], []
        for i in frames:
            x, v, rho = grp["position"][i], grp["velocity"][i], grp["density"][i][:, 0]
            inside = (grp["kind"][i][..., 0] == 0) & (x[:, 0] > x_from) & (x[:, 0] < x_to)
            column = np.clip(((x[inside, 0] - x_from) / (x_to - x_from) * columns).astype(int), 0, columns - 1)
            volume = np.zeros(columns)
            np.add.at(volume, column, rho0 * dp * dp / rho[inside])
            width = (x_to - x_from) / columns
            slope, at_mid = np.polyfit(column_x - x_mid, volume / width, 1)
            h = at_mid + slope * (x[:, 0] - x_mid)
            centre_depths.append(at_mid)
            s = x[inside, 1] / h[inside]
            layer = np.clip((s * layers).astype(int), 0, layers - 1)
            np.add.at(u_sum, layer, v[inside, 0])
            np.add.at(exact_sum, layer, tau * h[inside] / (4.0 * mu) * (3.0 * s * s - 2.0 * s))
            np.add.at(count, layer, 1)
            deep = inside & (x[:, 1] < h - 2 * dp)
            xs.append(x[deep, 0])
            heads.append(grp["pressure"][i][deep, 0] + rho[deep] * g * x[deep, 1])
    h_c = float(np.mean(centre_depths))
    if not 0.75 * D < h_c < 1.25 * D:
        raise MetricError(f"the water at the section's centre is {h_c:.4g} m deep, not about depth = {D:.4g} m")
    if np.any(count == 0):
        raise MetricError("a layer of the section holds no particle: is depth the water's depth?")
    u, exact = u_sum / count, exact_sum / count
    slope = np.polyfit(np.concatenate(xs), np.concatenate(heads), 1)[0]
    return {"l2_rel": float(np.sqrt(np.sum((u - exact) ** 2) / np.sum(exact ** 2))),
            "velocity_scale": float(np.sum(u * exact) / np.sum(exact ** 2)),
            "setup_ratio": float(slope / (3.0 * tau / (2.0 * h_c))),
            "depth_ratio": h_c / D,
            "frames": len(frames)}


# ---------------------------------------------------------------------------------------------------


def describe():
    """Text listing every metric, its parameters and its docstring."""
    out = []
    for name in sorted(METRICS):
        f = METRICS[name]
        ps = ", ".join(f"{k}" + ("" if v is REQUIRED else f"={v!r}") for k, v in f.params.items())
        out.append(f"{name}({ps})" + ("   [needs a reference run]" if f.uses_reference else ""))
        out.append("    columns: " + ", ".join(f.columns))
        out += ["    " + line.strip() for line in (f.__doc__ or "").strip().splitlines()]
        out.append("")
    return "\n".join(out)


def main(argv):
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0
    if argv[0] == "--list":
        print(describe())
        return 0
    ref = None
    if "--reference" in argv:
        i = argv.index("--reference")
        if i + 1 >= len(argv):
            print("metrics: --reference needs a run folder after it", file=sys.stderr)
            return 2
        ref = argv[i + 1]
        del argv[i:i + 2]
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    run_dir, name, params = argv[0], argv[1], {}
    for a in argv[2:]:
        k, _, v = a.partition("=")
        if k in TEXT_PARAMS and not v.startswith(('"', "'")):
            params[k] = v  # a name or path as typed: watchpoint=true is the watchpoint "true", not a bool
            continue
        try:
            params[k] = tomllib.loads(f"v = {v}")["v"]
        except tomllib.TOMLDecodeError:
            params[k] = v  # a bare word: a string
    runs = [RunInfo("run", run_dir)]
    if ref:
        runs.append(RunInfo("reference", ref, "completed", reference=True))
    try:
        # Relative paths as the shell sees them, where a sweep takes them from the sweep file's folder.
        out = compute(name, run_dir, params, Context(runs[0], runs, os.getcwd()))
    except MetricError as err:
        print(f"metrics: {err}", file=sys.stderr)
        return 1
    for k, v in out.items():
        print(f"{name}.{k} = {v:.10g}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
