"""Reads a sweep file (TOML, format in docs/sweeps.md), checks it, and expands it into runs.

Every mistake is reported with the file and the table/key, and nothing runs. Run folder names are
deterministic: a readable slug of the varied settings plus 8 hex digits of a hash of the run's complete
override set (fixed keys included), so the same settings always land in the same folder (--resume).
"""
import hashlib
import itertools
import json
import math
import os
import re
import tomllib

TOP_LEVEL = {
    "sweep": "run-wide settings: scene, name, title, timeout_s, grace_s, threads_per_run, jobs",
    "fixed": "overrides applied to every run (scene key = value)",
    "grid": "overrides varied as a cartesian product (scene key = [values], or named bundles)",
    "case": "[[case]] explicit extra runs: name, set, reference, expect, timeout_s",
    "metric": "[[metric]] error metrics: name, label, and the metric's parameters",
    "chart": "charts drawn after the sweep: series, x, y, annotate",
    "check": "regression guard settings: tolerance, atol",
    "expect": "[[expect]] recorded values for runs selected by `where`",
    "bisect": "stability threshold by bisection: key, low, high, rel_tol, max_runs, scale, integer, confirm, fail_if",
}
SWEEP_KEYS = {
    "scene": "path of the scene file, relative to the sweep file (required)",
    "name": "name of the sweep (default: the file name without .toml)",
    "title": "title of charts",
    "timeout_s": "wall-clock limit of each run in seconds (default 600)",
    "grace_s": "seconds between SIGINT and SIGKILL when a run overruns (default 10)",
    "threads_per_run": "OMP_NUM_THREADS given to each run (default: cores // jobs, at least 1)",
    "jobs": "runs at a time (default: the cores this process may use; --jobs overrides)",
    "description": "free text",
}
CASE_KEYS = {"name", "set", "reference", "expect", "timeout_s", "description"}
CHART_KEYS = {"series", "x", "y", "annotate", "title"}
CHECK_KEYS = {"tolerance", "atol"}
BISECT_KEYS = {"key", "low", "high", "rel_tol", "max_runs", "scale", "integer", "fail_if", "confirm"}
COST_COLUMNS = ("wall_s", "cpu_s", "particle_steps", "element_steps", "record_wall_s")


class SweepError(ValueError):
    """A mistake in a sweep file: nothing is run."""


class Axis:
    def __init__(self, name, values, bundles):
        self.name = name          # column name: a scene key, or the bundle axis name
        self.values = values      # candidate values; for bundles: list of (label, {scene key: value})
        self.bundles = bundles


class Run:
    def __init__(self, overrides, settings, case="", reference=False, expect=None, timeout_s=None, slug_items=None):
        self.overrides = overrides  # scene key -> value, in application order (fixed, grid, case)
        self.settings = settings    # column -> value (varied keys, bundle labels)
        self.case = case
        self.reference = reference
        self.expect = dict(expect or {})
        self.timeout_s = timeout_s
        self.slug_items = list(slug_items if slug_items is not None else settings.items())
        self.id = run_id(overrides, self.slug_items, case)

    def set_args(self):
        """The --set arguments of this run."""
        return [f"{k}={toml_value(v)}" for k, v in self.overrides.items()]

    def label(self):
        return self.case or ", ".join(f"{short_key(k)}={display(v)}" for k, v in self.slug_items)


class Sweep:
    pass


def load(path):
    """Reads and checks the sweep file at `path`; returns a Sweep with its runs expanded."""
    path = os.path.abspath(path)
    try:
        with open(path, "rb") as f:
            data = tomllib.load(f)
    except FileNotFoundError:
        raise SweepError(f"{path}: no such file") from None
    except tomllib.TOMLDecodeError as err:
        raise SweepError(f"{path}: not valid TOML: {err}") from None
    where = os.path.relpath(path)

    def fail(msg):
        raise SweepError(f"{where}: {msg}")

    unknown = sorted(set(data) - set(TOP_LEVEL))
    if unknown:
        fail(f"unknown table(s) {', '.join(repr(u) for u in unknown)}; allowed: "
             + "; ".join(f"[{k}] {v}" for k, v in TOP_LEVEL.items()))
    s = Sweep()
    s.path = path
    s.dir = os.path.dirname(path)
    head = _table(data, "sweep", fail, required=True)
    _only(head, SWEEP_KEYS, "[sweep]", fail)
    if "scene" not in head:
        fail("missing [sweep] scene = \"path/to/scene.toml\" (relative to this file)")
    s.scene = os.path.normpath(os.path.join(s.dir, _str(head["scene"], "[sweep] scene", fail)))
    if not os.path.isfile(s.scene):
        fail(f"[sweep] scene: no such file {s.scene}")
    with open(s.scene, "rb") as f:
        s.scene_bytes = f.read()
    s.scene_sha = hashlib.sha1(s.scene_bytes).hexdigest()
    s.name = _str(head.get("name", os.path.splitext(os.path.basename(path))[0]), "[sweep] name", fail)
    s.title = _str(head.get("title", s.name), "[sweep] title", fail)
    s.description = head.get("description", "")
    s.timeout_s = _positive(head.get("timeout_s", 600.0), "[sweep] timeout_s", fail)
    s.grace_s = _positive(head.get("grace_s", 10.0), "[sweep] grace_s", fail)
    s.threads_per_run = head.get("threads_per_run")
    if s.threads_per_run is not None and (not isinstance(s.threads_per_run, int) or isinstance(s.threads_per_run, bool)
                                          or s.threads_per_run < 1):
        fail(f"[sweep] threads_per_run: got {s.threads_per_run!r}; allowed: an integer >= 1")
    s.jobs = head.get("jobs")
    if s.jobs is not None and (not isinstance(s.jobs, int) or isinstance(s.jobs, bool) or s.jobs < 1):
        fail(f"[sweep] jobs: got {s.jobs!r}; allowed: an integer >= 1")

    s.fixed = _flatten(_table(data, "fixed", fail), "[fixed]", fail)
    for k, v in s.fixed.items():
        _check_scene_value(k, v, "[fixed]", fail)

    s.axes = []
    for name, values in _flatten(_table(data, "grid", fail), "[grid]", fail).items():
        if not isinstance(values, list) or not values:
            fail(f"[grid] {name}: expected a non-empty array of values to sweep, got {values!r}")
        tables = [isinstance(v, dict) for v in values]
        if any(tables) and not all(tables):
            fail(f"[grid] {name}: mixes plain values and tables; an axis is either values of one scene key or "
                 "named bundles (tables with a label and scene keys)")
        if all(tables):
            bundles = []
            for i, b in enumerate(values):
                if "label" not in b:
                    fail(f"[grid] {name}[{i}]: a bundle needs label = \"...\" (its name in the results and charts)")
                label = _str(b["label"], f"[grid] {name}[{i}].label", fail)
                keys = _flatten({k: v for k, v in b.items() if k != "label"}, f"[grid] {name}[{i}]", fail)
                for k, v in keys.items():
                    _check_scene_value(k, v, f"[grid] {name}[{i}]", fail)
                if label in [l for l, _ in bundles]:
                    fail(f"[grid] {name}: two bundles are labelled {label!r}")
                bundles.append((label, keys))
            s.axes.append(Axis(name, bundles, True))
        else:
            for v in values:
                _check_scene_value(name, v, f"[grid] {name}", fail)
            if len({json.dumps(v, sort_keys=True) for v in values}) != len(values):
                fail(f"[grid] {name}: repeated values {values!r}")
            s.axes.append(Axis(name, values, False))

    raw_cases = data.get("case", [])
    if not isinstance(raw_cases, list) or not all(isinstance(c, dict) for c in raw_cases):
        fail("case: write each extra run as a [[case]] table")
    bundle_axes = {a.name: dict(a.values) for a in s.axes if a.bundles}
    cases = []
    for i, c in enumerate(raw_cases):
        what = f"[[case]] #{i + 1}" + (f" ({c['name']!r})" if "name" in c else "")
        _only(c, CASE_KEYS, what, fail)
        name = _str(c.get("name", ""), f"{what} name", fail)
        sets = c.get("set", {})
        if not isinstance(sets, dict):
            fail(f"{what}: set must be a table of scene key = value")
        overrides, labels, explicit = {}, {}, {}
        for k, v in _flatten(sets, f"{what} set", fail).items():
            if k in bundle_axes:
                if v not in bundle_axes[k]:
                    fail(f"{what} set: {k} = {v!r}; allowed: {', '.join(repr(l) for l in bundle_axes[k])}")
                labels[k] = v
                overrides.update(bundle_axes[k][v])
            else:
                _check_scene_value(k, v, f"{what} set", fail)
                explicit[k] = v
        # A case's own keys win over its bundles' whatever order the table lists them in (a bundle named after
        # a key used to overwrite it, and the case could then merge silently into a grid run).
        overrides.update(explicit)
        timeout = c.get("timeout_s")
        if timeout is not None:
            timeout = _positive(timeout, f"{what} timeout_s", fail)
        reference = c.get("reference", False)
        if not isinstance(reference, bool):
            fail(f"{what} reference: expected true or false")
        expect = c.get("expect", {})
        if not isinstance(expect, dict):
            fail(f"{what} expect: expected a table, e.g. expect = {{ status = \"completed\", \"tip.rel_error\" = 1e-3 }}")
        cases.append(dict(name=name, overrides=overrides, labels=labels, timeout_s=timeout, reference=reference,
                          expect=_check_expect(expect, f"{what} expect", fail)))
    names = [c["name"] for c in cases if c["name"]]
    if len(set(names)) != len(names):
        fail("two [[case]] tables have the same name")
    if sum(c["reference"] for c in cases) > 1:
        fail("more than one [[case]] has reference = true")

    s.metrics = []
    raw_metrics = data.get("metric", [])
    if isinstance(raw_metrics, dict):
        raw_metrics = [raw_metrics]
    labels_seen = set()
    for i, m in enumerate(raw_metrics):
        if not isinstance(m, dict) or "name" not in m:
            fail(f"[[metric]] #{i + 1}: needs name = \"...\" (one of the metrics in tools/metrics.py)")
        label = _str(m.get("label", m["name"]), f"[[metric]] #{i + 1} label", fail)
        if label in labels_seen:
            fail(f"[[metric]]: two metrics are labelled {label!r}; give each a distinct label")
        if "." in label or "," in label:
            fail(f"[[metric]] label {label!r}: no dots or commas (columns are named LABEL.QUANTITY)")
        labels_seen.add(label)
        where_ = m.get("where", {})
        if not isinstance(where_, dict):
            fail(f"[[metric]] {label}: where must be a table of column = value (or = [values])")
        s.metrics.append(dict(name=m["name"], label=label, where=_flatten(where_, f"[[metric]] {label} where", fail),
                              params={k: v for k, v in m.items() if k not in ("name", "label", "where")}))

    chart = _table(data, "chart", fail)
    _only(chart, {k: "" for k in CHART_KEYS}, "[chart]", fail)
    s.chart = {
        "series": _str_list(chart.get("series", []), "[chart] series", fail),
        "x": _str_list(chart.get("x", ["cpu_s"]), "[chart] x", fail),
        "y": _str_list(chart.get("y", []), "[chart] y", fail),
        "annotate": chart.get("annotate"),
        "title": chart.get("title", s.title),
    }
    check = _table(data, "check", fail)
    _only(check, {k: "" for k in CHECK_KEYS}, "[check]", fail)
    s.check = {"tolerance": _nonneg(check.get("tolerance", 0.2), "[check] tolerance", fail),
               "atol": _nonneg(check.get("atol", 0.0), "[check] atol", fail)}
    s.expects = []
    raw_expects = data.get("expect", [])
    if isinstance(raw_expects, dict):
        raw_expects = [raw_expects]
    for i, e in enumerate(raw_expects):
        if not isinstance(e, dict) or not isinstance(e.get("where", None), dict):
            fail(f"[[expect]] #{i + 1}: needs where = {{ column = value, ... }} selecting the run(s)")
        s.expects.append((_flatten(e["where"], f"[[expect]] #{i + 1} where", fail),
                          _check_expect({k: v for k, v in e.items() if k != "where"}, f"[[expect]] #{i + 1}", fail)))

    s.bisect = None
    if "bisect" in data:
        s.bisect = _check_bisect(_table(data, "bisect", fail), fail)

    s.runs = _expand(s, cases, fail)
    for i, (where_, values) in enumerate(s.expects):
        matched = [r for r in s.runs if matches(r, where_)]
        if not matched:
            fail(f"[[expect]] #{i + 1}: where = {where_!r} selects no run of this sweep")
        for r in matched:
            r.expect.update(values)
    s.setting_columns = []
    for r in s.runs:
        for k in r.settings:
            if k not in s.setting_columns:
                s.setting_columns.append(k)
    for r in s.runs:  # a varied key that [fixed] sets has the fixed value where nothing else sets it
        for k in s.setting_columns:
            if k not in r.settings and k in r.overrides:
                r.settings[k] = r.overrides[k]
    known = set(s.setting_columns) | {"case"} | {k for r in s.runs for k in r.overrides}
    if s.bisect is not None:
        known.add(s.bisect["key"])
    for k in s.chart["series"]:
        if k not in known:
            fail(f"[chart] series: {k!r} is not a setting of this sweep; settings: {', '.join(s.setting_columns)}")
    for m in s.metrics:
        for k in m["where"]:
            if k not in known:
                fail(f"[[metric]] {m['label']} where: {k!r} is not a setting of this sweep")
        if m["where"] and not any(matches(r, m["where"]) for r in s.runs) and s.bisect is None:
            fail(f"[[metric]] {m['label']} where = {m['where']!r} selects no run of this sweep")
    return s


def _expand(s, cases, fail):
    runs, by_id = [], {}

    def add(run, what):
        key = run.id.rsplit("-", 1)[1]  # the hash of the override set
        if key in by_id:
            old = by_id[key]
            if not run.case and not old.case:
                fail(f"two grid runs have the same settings ({old.label()}; {run.label()}): "
                     "two bundles of an axis set the same keys to the same values")
            if run.case and old.case and run.case != old.case:
                fail(f"{what} has exactly the settings of case {old.case!r}")
            # A case with a grid point's settings names that run (e.g. the finest grid run as reference).
            old.case = old.case or run.case
            old.reference = old.reference or run.reference
            old.expect.update(run.expect)
            old.timeout_s = run.timeout_s if run.timeout_s is not None else old.timeout_s
            return
        by_id[key] = run
        runs.append(run)

    # A scene key set by two axes would take whichever comes last, and the run would be labelled with a value
    # it did not run with: refused.
    setter = {}
    for a in s.axes:
        for k in sorted({k for _, keys in a.values for k in keys} if a.bundles else {a.name}):
            if k in setter:
                fail(f"[grid] {k!r} is set by both {setter[k]!r} and {a.name!r}: one axis per scene key")
            setter[k] = a.name
    axis_values = [[(a, v) for v in a.values] for a in s.axes]
    for combo in (itertools.product(*axis_values) if s.axes else []):
        overrides, settings, slug = dict(s.fixed), {}, []
        for axis, v in combo:
            if axis.bundles:
                label, keys = v
                settings[axis.name] = label
                slug.append((axis.name, label))
                overrides.update(keys)
                for k, kv in keys.items():
                    settings[k] = kv
            else:
                overrides[axis.name] = v
                settings[axis.name] = v
                slug.append((axis.name, v))
        add(Run(overrides, settings, slug_items=slug), "a grid run")
    grid_columns = []
    for r in runs:
        grid_columns += [k for k in r.settings if k not in grid_columns]
    for c in cases:
        overrides = dict(s.fixed)
        overrides.update(c["overrides"])
        settings = {}
        for k in grid_columns:  # a case's value for each varied column (blank: the scene's own value)
            if k in c["labels"]:
                settings[k] = c["labels"][k]
            elif k in overrides:
                settings[k] = overrides[k]
        for k, v in c["labels"].items():
            settings.setdefault(k, v)
        for k, v in c["overrides"].items():
            settings.setdefault(k, v)
        add(Run(overrides, settings, c["name"], c["reference"], c["expect"], c["timeout_s"]),
            f"[[case]] {c['name']!r}")
    if not runs and s.bisect is None:
        fail("nothing to run: give a [grid] and/or [[case]] tables")
    if not runs:
        runs.append(Run(dict(s.fixed), {}))  # a bisection of the scene as it is
    return runs


def _check_bisect(b, fail):
    _only(b, {k: "" for k in BISECT_KEYS}, "[bisect]", fail)
    for k in ("key", "low", "high"):
        if k not in b:
            fail(f"[bisect] needs {k}")
    key = _str(b["key"], "[bisect] key", fail)
    integer = b.get("integer", isinstance(b["low"], int) and isinstance(b["high"], int))
    if not isinstance(integer, bool):
        fail("[bisect] integer: expected true or false")
    low, high = b["low"], b["high"]
    for name, v in (("low", low), ("high", high)):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            fail(f"[bisect] {name}: expected a number, got {v!r}")
        if integer and v != int(v):
            fail(f"[bisect] {name}: integer = true but {v!r} is not an integer")
    if low >= high:
        fail(f"[bisect] low ({low}) must be below high ({high}); which end completes is found by running both")
    scale = b.get("scale", "linear" if integer else "log")
    if scale not in ("log", "linear"):
        fail(f"[bisect] scale: got {scale!r}; allowed: \"log\", \"linear\"")
    if scale == "log" and low <= 0:
        fail("[bisect] scale = \"log\" needs low > 0")
    rel_tol = b.get("rel_tol", 0.05)
    if isinstance(rel_tol, bool) or not isinstance(rel_tol, (int, float)) or not 0 < rel_tol < 1:
        fail(f"[bisect] rel_tol: got {rel_tol!r}; allowed: a number > 0 and < 1")
    max_runs = b.get("max_runs", 20)
    if isinstance(max_runs, bool) or not isinstance(max_runs, int) or max_runs < 3:
        fail(f"[bisect] max_runs: got {max_runs!r}; allowed: an integer >= 3 (two ends and one probe)")
    confirm = b.get("confirm", 2)
    if isinstance(confirm, bool) or not isinstance(confirm, int) or confirm < 0:
        fail(f"[bisect] confirm: got {confirm!r}; allowed: an integer >= 0")
    fail_if = b.get("fail_if", {})
    if not isinstance(fail_if, dict) or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                for v in fail_if.values()):
        fail("[bisect] fail_if: expected a table of metric column = largest acceptable value")
    return dict(key=key, low=int(low) if integer else float(low), high=int(high) if integer else float(high),
                integer=integer, scale=scale, rel_tol=float(rel_tol), max_runs=max_runs, confirm=confirm,
                fail_if=dict(fail_if))


def _check_expect(e, what, fail):
    out = {}
    for k, v in e.items():
        if k == "status":
            if not isinstance(v, str):
                fail(f"{what} status: expected a string such as \"completed\"")
            out[k] = v
        elif isinstance(v, dict):
            extra = set(v) - {"value", "tolerance", "atol", "two_sided"}
            if extra or "value" not in v:
                fail(f"{what} {k}: expected a number or {{ value = ..., tolerance = ..., atol = ..., two_sided = ... }}")
            for kk, vv in v.items():
                if kk == "two_sided":
                    if not isinstance(vv, bool):
                        fail(f"{what} {k}.two_sided: expected true or false")
                elif isinstance(vv, bool) or not isinstance(vv, (int, float)):
                    fail(f"{what} {k}.{kk}: expected a number")
            out[k] = dict(v)
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            out[k] = {"value": float(v)}
        else:
            fail(f"{what} {k}: expected a number (the recorded value) or status = \"...\"")
    return out


def matches(run, where):
    """True if the run's settings (or overrides, or case name) equal every `where` entry; an entry whose
    value is an array matches any of its values (an array-valued scene key is compared as a whole too)."""
    for k, want in where.items():
        if k == "case":
            have = run.case
        elif k in run.settings:
            have = run.settings[k]
        elif k in run.overrides:
            have = run.overrides[k]
        else:
            return False
        if not (same_value(have, want) or (isinstance(want, list) and any(same_value(have, w) for w in want))):
            return False
    return True


def same_value(a, b):
    num = (int, float)
    if isinstance(a, num) and isinstance(b, num) and not isinstance(a, bool) and not isinstance(b, bool):
        return a == b or abs(a - b) <= 1e-12 * max(abs(a), abs(b))
    return a == b


def toml_value(v):
    """A Python value (from tomllib) written back as a TOML value for --set."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        r = repr(v)
        return r if any(c in r for c in ".en") else r + ".0"
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)  # a JSON string is a valid TOML basic string
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"cannot write {v!r} as TOML")


def display(v):
    """Compact text of a setting value for labels and folder names."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, (list, dict)):
        return toml_value(v)
    return str(v)


def short_key(k):
    """`structure.members[0].n_elements` -> `n_elements`."""
    last = k.split(".")[-1]
    return re.sub(r"\[\d+\]$", "", last) or k


def run_id(overrides, slug_items, case=""):
    """Folder name: a readable slug, then 8 hex digits of the SHA-1 of the complete, sorted override set
    (1 and 1.0 differ, as they do for the scene)."""
    canon = json.dumps(sorted(overrides.items()), separators=(",", ":"), sort_keys=True)
    digest = hashlib.sha1(canon.encode()).hexdigest()[:8]
    if case:
        slug = case
    elif slug_items:
        slug = "_".join(f"{short_key(k)}={display(v)}" for k, v in slug_items)
    else:
        slug = "scene"
    slug = re.sub(r"[^A-Za-z0-9._=+-]+", "-", slug).strip("-")[:72] or "run"
    return f"{slug}-{digest}"


def _flatten(table, what, fail, prefix=""):
    """Nested TOML tables -> dotted keys: [fixed] run.end_time = 1 and "run.end_time" = 1 are the same.
    Arrays (of values, or of bundle tables) end the path."""
    out = {}
    for k, v in table.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(_flatten(v, what, fail, key + "."))
        else:
            if key in out:
                fail(f"{what}: {key} given twice")
            out[key] = v
    return out


def _check_scene_value(key, v, what, fail):
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_-]*(\[\d+\])?(\.[A-Za-z_][A-Za-z0-9_-]*(\[\d+\])?)*", key):
        fail(f"{what}: {key!r} is not a scene key path such as fluid.time.cfl or structure.members[0].n_elements")
    if isinstance(v, dict):
        fail(f"{what}: {key} = {v!r}: a table is not a value here (write dotted keys)")


def _table(data, name, fail, required=False):
    v = data.get(name, {} if not required else None)
    if v is None:
        fail(f"missing [{name}] table")
    if not isinstance(v, dict):
        fail(f"[{name}] must be a table")
    return v


def _only(table, allowed, what, fail):
    extra = sorted(set(table) - set(allowed))
    if extra:
        fail(f"{what}: unknown key(s) {', '.join(repr(e) for e in extra)}; allowed: {', '.join(sorted(allowed))}")


def _str(v, what, fail):
    if not isinstance(v, str):
        fail(f"{what}: expected a string, got {v!r}")
    return v


def _str_list(v, what, fail):
    if isinstance(v, str):
        return [v]
    if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
        fail(f"{what}: expected a string or an array of strings")
    return list(v)


def _positive(v, what, fail):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0 or not math.isfinite(v):
        fail(f"{what}: got {v!r}; allowed: a number > 0")
    return float(v)


def _nonneg(v, what, fail):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not v >= 0 or not math.isfinite(v):
        fail(f"{what}: got {v!r}; allowed: a number >= 0")
    return float(v)
