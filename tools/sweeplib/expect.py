"""The regression guard: recorded values per run, checked by `tools/sweep.py --check`.

A run's expectations come from its [[case]] `expect` table and from every [[expect]] table whose `where`
selects it. A check fails when
  * the run's status differs from `status` (numeric expectations imply status = "completed"), or
  * a recorded quantity has no value now, or
  * |measured| > |recorded| * (1 + tolerance) + atol   (defaults: [check] tolerance = 0.2, atol = 0),
so an error may not rise more than 20 % above its recorded value. A value that fell below
|recorded| / (1 + tolerance) passes, with a note to record the improvement. A quantity that is not an
error (a signed error, a fraction of windows that converged) sets `two_sided = true`: it fails when
|measured - recorded| > tolerance * |recorded| + atol, whichever way it moved.
"""
import math

from .spec import toml_value


def check(runs, rows_by_id, defaults):
    """Returns (failures, notes): lists of text lines. `runs` are the spec's runs that were selected."""
    failures, notes = [], []
    for run in runs:
        if not run.expect:
            continue
        row = rows_by_id.get(run.id)
        who = run.case or run.label()
        if row is None:
            notes.append(f"{who}: not run (not selected)")
            continue
        numeric = {k: v for k, v in run.expect.items() if k != "status"}
        want_status = run.expect.get("status", "completed" if numeric else None)
        if want_status is not None and row.get("status") != want_status:
            msg = row.get("message") or ""
            failures.append(f"{who}: status {row.get('status')!r}, expected {want_status!r}"
                            + (f" ({msg})" if msg else ""))
        for key, e in numeric.items():
            recorded = float(e["value"])
            tol = float(e.get("tolerance", defaults["tolerance"]))
            atol = float(e.get("atol", defaults["atol"]))
            measured = row.get(key)
            if measured is None or (isinstance(measured, float) and math.isnan(measured)):
                failures.append(f"{who}: {key} has no value (recorded {recorded:.4g})")
                continue
            if e.get("two_sided", False):
                if abs(measured - recorded) > tol * abs(recorded) + atol:
                    failures.append(f"{who}: {key} = {measured:.4g}, recorded {recorded:.4g}: moved by more than "
                                    f"{tol:g} of it + {atol:g} (two-sided)")
                continue
            limit = abs(recorded) * (1 + tol) + atol
            if abs(measured) > limit:
                failures.append(f"{who}: {key} = {measured:.4g}, recorded {recorded:.4g}: "
                                f"{_change(measured, recorded)} (allowed up to {limit:.4g})")
            elif abs(measured) < abs(recorded) / (1 + tol) - atol:
                notes.append(f"{who}: {key} = {measured:.4g} improved on the recorded {recorded:.4g} "
                             f"({_change(measured, recorded)}); consider recording the new value")
    return failures, notes


def _change(measured, recorded):
    if recorded == 0:
        return "was 0"
    return f"{100 * (abs(measured) / abs(recorded) - 1):+.1f} %"


def expect_toml(runs, rows_by_id, error_columns, when):
    """[[expect]] tables holding the measured values, to paste into the sweep file."""
    out = [f"# Measured {when}. Paste into the sweep file; --check then fails on a rise above "
           "recorded * (1 + tolerance) + atol."]
    for run in runs:
        row = rows_by_id.get(run.id)
        if row is None:
            continue
        if run.case:
            where = f'{{ case = "{run.case}" }}'
        else:  # case = "": a [[case]] with the same settings is not this run (it failed --check when pasted)
            where = "{ " + ", ".join(['case = ""'] + [f'"{k}" = {toml_value(v)}' for k, v in run.settings.items()]) + " }"
        out.append("")
        out.append("[[expect]]")
        out.append(f"where = {where}")
        out.append(f'status = "{row.get("status")}"')
        keys = [k for k in run.expect if k != "status"] or error_columns
        for k in keys:
            v = row.get(k)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or math.isnan(v):
                continue
            value = f"{v:.4g}" if isinstance(v, float) else str(v)
            # A recorded expectation's own tolerance, atol and two_sided stay with its new value.
            extra = {kk: vv for kk, vv in run.expect.get(k, {}).items() if kk != "value"}
            if extra:
                value = "{ value = " + value + "".join(f", {kk} = {toml_value(vv)}" for kk, vv in extra.items()) + " }"
            out.append(f'"{k}" = {value}')
    return "\n".join(out) + "\n"


