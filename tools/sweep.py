#!/usr/bin/env -S /usr/bin/python3
"""Runs a scene over a grid of overrides and tabulates cost and error per run (sphfsi itself only runs and
checks single scenes).

usage: /usr/bin/python3 tools/sweep.py SWEEP.toml [--jobs N] [--out DIR] [--only PATTERN] [--resume]
                                       [--check] [--print-expect] [--list] [--bin BUILD/bin] [--no-charts]

  SWEEP.toml      the sweep file (format: docs/sweeps.md); a file with a [bisect] table runs a
                  stability bisection instead of a grid
  --jobs N        runs at a time (default: [sweep] jobs, else the cores this process may use); each run
                  gets OMP_NUM_THREADS = [sweep] threads_per_run, else max(1, cores // N)
  --out DIR       output folder (default: out/sweeps/NAME under the current folder); each run in
                  DIR/runs/SLUG-HASH, the table in DIR/results.csv, its description in DIR/sweep.json
  --only PATTERN  run only the runs whose folder name or case name matches the shell pattern (a pattern
                  without * ? [ matches as a substring); repeatable. The table and charts still hold every
                  run of the sweep with a result in DIR: the others are kept, as --resume would keep them
  --resume        keep the results of runs already in DIR (same overrides, same scene text; not interrupted
                  runs, nor timeouts under a shorter limit than today's); metrics are recomputed from their records
  --check         regression guard: exit 1 if a run's status or a recorded value is off (docs/sweeps.md)
  --print-expect  print the measured values as [[expect]] tables, to record them in the sweep file
  --list          print the runs and their --set arguments; run nothing
  --bin DIR       folder holding sphfsi (default: $SPHFSI_BIN, else $SPHFSI_BUILD_DIR/bin, else build/bin)
  --no-charts     skip the charts named in [chart]

Exit status: 0 done (failed runs are results, not errors), 1 --check found a regression, 2 a mistake in
the sweep file or the command line, 3 a bisection's reference run did not complete (nothing to bisect
against), 130 interrupted (the runs in progress are stopped with SIGINT).
"""
import argparse
import concurrent.futures
import datetime
import fnmatch
import json
import math
import os
import shutil
import sys
import threading

TOOLS = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(TOOLS)
sys.path.insert(0, TOOLS)

import metrics  # noqa: E402
from sweeplib import bisect as bisection  # noqa: E402
from sweeplib import expect as guard  # noqa: E402
from sweeplib import record, results, runner  # noqa: E402
from sweeplib import spec as specs  # noqa: E402


class Interrupted(Exception):
    pass


def cores():
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def find_sphfsi(bin_dir):
    candidates = []
    if bin_dir:
        candidates.append(bin_dir)
    if os.environ.get("SPHFSI_BIN"):
        candidates.append(os.environ["SPHFSI_BIN"])
    if os.environ.get("SPHFSI_BUILD_DIR"):
        candidates.append(os.path.join(os.environ["SPHFSI_BUILD_DIR"], "bin"))
    candidates.append(os.path.join(ROOT, "build", "bin"))
    for c in candidates:
        path = c if os.path.basename(c) == "sphfsi" and os.path.isfile(c) else os.path.join(c, "sphfsi")
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return os.path.abspath(path)
        if bin_dir and c == bin_dir:
            break  # an explicit --bin that has no sphfsi is a mistake, not a hint
    print(f"sweep: no sphfsi executable in {candidates[0]} (build it, or pass --bin BUILD/bin)", file=sys.stderr)
    return None


class Sweeper:
    """Runs the runs of one sweep, keeps their rows, computes their metrics."""

    def __init__(self, sw, out, sphfsi, jobs, threads, resume):
        self.sw, self.out, self.sphfsi, self.jobs, self.resume = sw, out, sphfsi, jobs, resume
        self.threads = threads
        self.env = dict(os.environ)
        if threads is not None:
            self.env["OMP_NUM_THREADS"] = str(threads)
        self.stop = threading.Event()
        self.lock = threading.Lock()
        self.metric_lock = threading.Lock()  # h5py: one reader at a time
        # Every program a run may start (the coordinator starts the participants from its own folder): a
        # rebuilt fluid or structure changes results as much as a rebuilt coordinator.
        parts = []
        for program in ("sphfsi", "sphfsi-fluid", "sphfsi-structure"):
            path = os.path.join(os.path.dirname(sphfsi), program)
            try:
                st = os.stat(path)
                parts.append(f"{path} {int(st.st_mtime)} {st.st_size}")
            except OSError:
                parts.append(path)
        self.build_stamp = "; ".join(parts)
        self.reused_other_build = []  # ids of kept runs made by another build, or with another thread count
        self.reused_other_threads = []
        self.metric_columns = []
        self.metric_errors = []
        for m in sw.metrics:
            f = metrics.METRICS[m["name"]]
            self.metric_columns += [f"{m['label']}.{k}" for k in f.columns]
            self.metric_errors += [f"{m['label']}.{k}" for k in f.errors]

    def run_dir(self, run):
        return os.path.join(self.out, "runs", run.id)

    def previous(self, run):
        """The row of an earlier identical run in the output folder (read again from its record), or None."""
        try:
            with open(os.path.join(self.run_dir(run), "result.json")) as f:
                data = json.load(f)
        except (OSError, ValueError):
            return None
        if data.get("id") != run.id or data.get("scene_sha") != self.sw.scene_sha \
                or data.get("set_args") != run.set_args() or data.get("row", {}).get("status") == "interrupted":
            return None
        # A run that timed out under a shorter limit than today's may complete now (a missing limit: older file).
        if data["row"].get("status") == "timeout" and self.timeout_of(run) > data.get("timeout_s", math.inf):
            return None
        row = self.resummarize(run, data)
        # Said in the row too: results.csv and its charts outlive the warning on stderr.
        notes = []
        if data.get("build") != self.build_stamp:
            self.reused_other_build.append(run.id)
            notes.append("kept: made by another build of sphfsi")
        if data.get("threads") != self.threads:  # its wall and CPU times are of another thread count
            self.reused_other_threads.append(run.id)
            notes.append(f"kept: ran with {data.get('threads')} threads per run, not {self.threads}")
        if notes:
            row["notes"] = "; ".join([n for n in (row.get("notes") or "").split("; ") if n] + notes)
        return row

    def resummarize(self, run, data):
        """A kept run's row, its columns read again from its record.h5 with today's tools: only what the
        record cannot say (exit status, times, how the sweep stopped it) comes from result.json. A row kept
        whole would carry the counting of the tools that first read it (particle_steps once over-counted)."""
        kept = data["row"]
        rr = runner.RunResult()
        saved = data.get("run_result")
        if saved is None:  # written before the run's own result was saved: rebuild it from the row
            saved = {"exit_code": kept.get("exit_code"), "wall_s": kept.get("wall_s"), "cpu_s": kept.get("cpu_s"),
                     "timed_out": kept.get("status") == "timeout",
                     "killed": "SIGKILL" in (kept.get("message") or "")}
        for k, v in saved.items():
            setattr(rr, k, v)
        d = self.run_dir(run)
        rr.stderr_path = os.path.join(d, runner.STDERR_FILE)
        with self.metric_lock:
            return record.summarize(d, rr, data.get("timeout_s", self.timeout_of(run)))

    def timeout_of(self, run):
        return run.timeout_s if run.timeout_s is not None else self.sw.timeout_s

    def execute(self, run):
        """Runs one coordinator (or reuses its earlier result under --resume); returns its row."""
        if self.resume:
            row = self.previous(run)
            if row is not None:
                row = dict(row)
                row["reused"] = True
                return row
        if self.stop.is_set():
            raise Interrupted()
        d = self.run_dir(run)
        if os.path.isdir(d):
            shutil.rmtree(d)
        timeout = self.timeout_of(run)
        rr = runner.run_coordinator(self.sphfsi, self.sw.scene, d, run.set_args(), timeout, self.sw.grace_s,
                                    self.env, self.stop)
        with self.metric_lock:
            row = record.summarize(d, rr, timeout)
        results.write_json(os.path.join(d, "result.json"), {
            "id": run.id, "scene": self.sw.scene, "scene_sha": self.sw.scene_sha, "set_args": run.set_args(),
            "build": self.build_stamp, "threads": self.threads, "timeout_s": timeout,
            "finished": datetime.datetime.now().isoformat(timespec="seconds"), "row": row,
            "run_result": {k: getattr(rr, k) for k in ("exit_code", "timed_out", "stopped", "killed", "wall_s", "cpu_s")}})
        return row

    def infos(self, rows_by_id, runs=None):
        """metrics.RunInfo for every run of the sweep; one without a row (unselected runs that were kept have
        theirs: run_grid) is "not run"."""
        out = []
        for r in (runs if runs is not None else self.sw.runs):
            row = rows_by_id.get(r.id)
            status = row.get("status", "") if row is not None else "not run"
            out.append(metrics.RunInfo(r.id, self.run_dir(r), status, r.settings, r.overrides, r.case,
                                       r.reference))
        return out

    def compute_metrics(self, run, row, infos, which):
        """Fills the row's metric columns; which: 'plain', 'reference' (uses_reference) or 'all'."""
        if row.get("status") != "completed":
            return
        me = next(i for i in infos if i.id == run.id)
        ctx = metrics.Context(me, infos, self.sw.dir)
        notes = [n for n in (row.get("notes") or "").split("; ") if n]
        for m in self.sw.metrics:
            f = metrics.METRICS[m["name"]]
            if which != "all" and f.uses_reference != (which == "reference"):
                continue
            if m["where"] and not specs.matches(run, m["where"]):
                continue
            notes = [n for n in notes if not n.startswith(m["label"] + ": ")]
            try:
                with self.metric_lock:
                    vals = metrics.compute(m["name"], self.run_dir(run), m["params"], ctx)
            except metrics.MetricError as err:
                notes.append(f"{m['label']}: {err}")
                continue
            except Exception as err:  # a broken record must not end the sweep: say what happened
                notes.append(f"{m['label']}: {type(err).__name__}: {err}")
                continue
            for k, v in vals.items():
                row[f"{m['label']}.{k}"] = v
            # A NaN becomes an empty cell: say why, as for a metric that failed (e.g. rel_error with exact = 0).
            nan = [k for k, v in vals.items() if isinstance(v, float) and math.isnan(v)]
            if nan:
                notes.append(f"{m['label']}: {', '.join(nan)} not a number")
        row["notes"] = "; ".join(notes)

    def columns(self):
        return results.columns(self.sw.setting_columns, self.metric_columns)

    def full_row(self, run, row):
        out = {"run": run.id, "case": run.case}
        out.update(run.settings)
        out.update(row)
        return out


def progress(i, n, run, row, extra=""):
    status = row.get("status", "?")
    cost = ""
    if row.get("wall_s") is not None:
        cost = f"{row['wall_s']:7.2f} s wall {row.get('cpu_s') or 0:7.2f} s CPU"
    msg = f"  {row.get('message')}" if row.get("message") else ""
    reused = " (kept)" if row.get("reused") else ""
    print(f"[{i}/{n}] {status:<11} {run.label()}  {cost}{reused}{extra}{msg}", flush=True)


def keep_unselected(sweeper, selected):
    """Under --only, the rows of the runs not selected whose folders hold a result usable today (as --resume
    would keep it), their metrics computed: results.csv and the charts stay those of the whole sweep instead of
    the subset's (which overwrote them), and a reference run that is not selected is compared (build, threads)
    like any kept run. Returns (rows by id, ids of unselected runs without such a result)."""
    chosen = {r.id for r in selected}
    kept, missing = {}, []
    for r in sweeper.sw.runs:
        if r.id in chosen:
            continue
        row = sweeper.previous(r)
        if row is None:
            missing.append(r.id)
        else:
            kept[r.id] = dict(row, reused=True)
    infos = sweeper.infos(kept)
    for r in sweeper.sw.runs:
        if r.id in kept:
            sweeper.compute_metrics(r, kept[r.id], infos, "plain")
    return kept, missing


def run_grid(sweeper, selected):
    rows_by_id, missing = keep_unselected(sweeper, selected)
    kept = len(rows_by_id)
    if kept or missing:
        print(f"sweep: {kept} run(s) not selected kept in the table from their earlier results"
              + (f"; {len(missing)} not selected have none usable (not in the table)" if missing else ""), flush=True)
    csv_path = os.path.join(sweeper.out, "results.csv")
    n = len(selected)
    done = 0

    def snapshot():
        rows = [sweeper.full_row(r, rows_by_id[r.id]) for r in sweeper.sw.runs if r.id in rows_by_id]
        results.write_csv(csv_path, sweeper.columns(), rows)

    interrupted = False
    with concurrent.futures.ThreadPoolExecutor(max_workers=sweeper.jobs) as pool:
        futures = {pool.submit(sweeper.execute, r): r for r in selected}
        try:
            for fut in concurrent.futures.as_completed(futures):
                run = futures[fut]
                try:
                    row = fut.result()
                except Interrupted:
                    continue
                done += 1
                rows_by_id[run.id] = row
                sweeper.compute_metrics(run, row, sweeper.infos(rows_by_id), "plain")
                shown = [c for c in sweeper.metric_errors if row.get(c) is not None][:2]
                extra = "".join(f"  {c}={row[c]:.3g}" for c in shown)
                progress(done, n, run, row, extra)
                snapshot()
        except KeyboardInterrupt:
            interrupted = True
            print("sweep: interrupted; stopping the runs in progress (SIGINT)", file=sys.stderr, flush=True)
            sweeper.stop.set()
            for fut, run in futures.items():
                try:
                    row = fut.result()
                except (Interrupted, KeyboardInterrupt):
                    continue
                if run.id not in rows_by_id:  # finished before the stop but not yet taken: its metrics too
                    rows_by_id[run.id] = row
                    sweeper.compute_metrics(run, row, sweeper.infos(rows_by_id), "plain")
    infos = sweeper.infos(rows_by_id)
    for r in sweeper.sw.runs:
        if r.id in rows_by_id:
            sweeper.compute_metrics(r, rows_by_id[r.id], infos, "reference")
    snapshot()
    return rows_by_id, interrupted


def describe_columns(sweeper):
    cols = {c: {"meaning": m, "unit": u} for c, (m, u) in results.RUN_COLUMNS.items()}
    for m in sweeper.sw.metrics:
        f = metrics.METRICS[m["name"]]
        for k, (meaning, unit) in f.columns.items():
            cols[f"{m['label']}.{k}"] = {"meaning": f"{m['name']}: {meaning}", "unit": unit,
                                         "error": k in f.errors}
    return cols


def write_description(sweeper, started, extra=None):
    sw = sweeper.sw
    data = {
        "name": sw.name, "title": sw.title, "description": sw.description,
        "sweep_file": sw.path, "scene": sw.scene, "scene_sha": sw.scene_sha,
        "fixed": {k: specs.toml_value(v) for k, v in sw.fixed.items()},
        "axes": [{"name": a.name, "values": [lbl for lbl, _ in a.values] if a.bundles
                  else [specs.toml_value(v) for v in a.values]} for a in sw.axes],
        "setting_columns": sw.setting_columns,
        "reference_run": next((r.id for r in sw.runs if r.reference), None),
        "metrics": sw.metrics,
        "columns": describe_columns(sweeper),
        "chart": sw.chart,
        "sphfsi": sweeper.sphfsi, "jobs": sweeper.jobs, "threads_per_run": sweeper.threads, "cores": cores(),
        "started": started, "finished": datetime.datetime.now().isoformat(timespec="seconds"),
        "command": sys.argv,
    }
    data.update(extra or {})
    results.write_json(os.path.join(sweeper.out, "sweep.json"), data)


def draw_charts(sweeper, csv_path):
    sw = sweeper.sw
    import chart
    ys = sw.chart["y"] or sweeper.metric_errors[:1]
    made = []
    for y in ys:
        for x in sw.chart["x"]:
            prefix = os.path.join(sweeper.out, f"chart-{y}-vs-{x}")
            try:
                summary = chart.chart_file(csv_path, x, y, sw.chart["series"] or None, prefix,
                                           title=sw.chart["title"], annotate=sw.chart["annotate"])
            except chart.ChartError as err:
                print(f"sweep: chart {y} vs {x}: {err}", file=sys.stderr)
                continue
            made.append(prefix)
            print(f"chart: {prefix}.png/.svg ({summary})")
    return made


class BisectionNotRun(Exception):
    """Nothing could be bisected; carries the exit status (2: the command line, 3: the reference run)."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status


def run_bisection(sweeper, selected):
    """One bisection per selected run (grid point or case), the bisections in parallel."""
    sw = sweeper.sw
    cfg = sw.bisect
    key = cfg["key"]
    fail_if = cfg["fail_if"]
    # A metric against the reference run needs that run: it is run (or reused) first, is not itself a target,
    # and every probe's metrics see it (before 2026-11-27 each probe saw only itself, so such a fail_if
    # failed every probe with "no reference run").
    reference = next((r for r in sw.runs if r.reference), None)
    reference_rows = {}
    if reference is not None and any(metrics.METRICS[m["name"]].uses_reference for m in sw.metrics):
        selected = [t for t in selected if t is not reference]
        if not selected:
            raise BisectionNotRun(2, "sweep: the only run selected is the reference run; nothing to bisect "
                                     "(select the runs to bisect with --only)")
        print(f"bisection: the reference run {reference.label() or reference.id} first", flush=True)
        try:
            reference_rows[reference.id] = sweeper.execute(reference)
        except KeyboardInterrupt:
            print("sweep: interrupted during the reference run", file=sys.stderr, flush=True)
            return True
        status = reference_rows[reference.id].get("status")
        print(f"[{reference.label() or 'reference'}] {status}", flush=True)
        if status != "completed":  # every probe would fail for want of it, which reads as 'neither end passes'
            raise BisectionNotRun(3, f"sweep: the reference run did not complete ({status}: "
                                     f"{reference_rows[reference.id].get('message') or ''}); nothing to bisect against")
    probes = {r.id: [] for r in selected}
    summaries = {}
    print(f"bisection on {key} in [{cfg['low']}, {cfg['high']}] ({cfg['scale']}"
          f"{', integer' if cfg['integer'] else ''}), rel_tol {cfg['rel_tol']}, at most {cfg['max_runs']} runs "
          f"each ({bisection.bound_on_runs(cfg['low'], cfg['high'], cfg['scale'], cfg['integer'], cfg['rel_tol'], cfg['confirm'])}"
          f" for one clean boundary, {cfg['confirm']} confirming probes included)", flush=True)

    def target_job(target):
        def probe(value):
            overrides = dict(target.overrides)
            overrides[key] = value
            settings = dict(target.settings)
            settings[key] = value
            slug = ([("case", target.case)] if target.case else list(target.slug_items)) + [(key, value)]
            prun = specs.Run(overrides, settings, slug_items=slug, timeout_s=target.timeout_s)
            prun.case = target.case
            row = sweeper.execute(prun)
            infos = sweeper.infos({prun.id: row, **reference_rows}, [prun] + ([reference] if reference_rows else []))
            sweeper.compute_metrics(prun, row, infos, "all")
            passed = row.get("status") == "completed"
            why = row.get("message") or ""
            for col, limit in (fail_if.items() if passed else ()):  # a failed run keeps its own reason
                v = row.get(col)
                if v is None or (isinstance(v, float) and math.isnan(v)):
                    passed, why = False, f"fail_if: {col} has no value"
                elif v > limit:
                    passed, why = False, f"fail_if: {col} = {v:.4g} > {limit:g}"
            full = sweeper.full_row(prun, row)
            full.update({"target": target.label(), "probe": len(probes[target.id]) + 1, "value": value,
                         "passed": passed, "reason": why})
            with sweeper.lock:
                probes[target.id].append(full)
                print(f"[{target.label() or 'scene'}] {key} = {value!r}: "
                      f"{'passes' if passed else 'fails'} ({row.get('status')}"
                      f"{', ' + why if why else ''}){' (kept)' if row.get('reused') else ''}", flush=True)
            if row.get("status") == "interrupted" and sweeper.stop.is_set():
                raise Interrupted()
            return passed, full

        summaries[target.id] = bisection.bisect(cfg, probe)
        return target

    interrupted = False
    with concurrent.futures.ThreadPoolExecutor(max_workers=sweeper.jobs) as pool:
        futures = [pool.submit(target_job, t) for t in selected]
        try:
            for fut in concurrent.futures.as_completed(futures):
                try:
                    fut.result()
                except Interrupted:
                    pass
        except KeyboardInterrupt:
            interrupted = True
            print("sweep: interrupted; stopping the runs in progress (SIGINT)", file=sys.stderr, flush=True)
            sweeper.stop.set()
            concurrent.futures.wait(futures)

    probe_cols = ["target", "probe", "value", "passed", "reason"] + sweeper.columns()
    probe_cols = list(dict.fromkeys(probe_cols))
    results.write_csv(os.path.join(sweeper.out, "probes.csv"), probe_cols,
                      [p for t in selected for p in probes[t.id]])
    rows = []
    for t in selected:
        s = summaries.get(t.id)
        if s is None:
            continue
        row = {"target": t.label(), "case": t.case}
        row.update(t.settings)
        row.update({"key": key, "passes": s["passes"], "threshold": s["threshold"],
                    "first_failing": s["first_failing"], "rel_width": s["rel_width"], "runs": s["runs"],
                    "converged": s["converged"], "non_monotonic": s["non_monotonic"],
                    "passes_beyond": " ".join(f"{v!r}" for v in s["passes_beyond"]), "note": s["note"]})
        rows.append(row)
        if s["threshold"] is not None:
            side = "largest passing" if s["passes"] == "below" else "smallest passing"
            print(f"[{t.label() or 'scene'}] {key}: {side} {s['threshold']!r}, first failing {s['first_failing']!r} "
                  f"(width {100 * s['rel_width']:.2g} %, {s['runs']} runs){'; ' + s['note'] if s['note'] else ''}")
        else:
            print(f"[{t.label() or 'scene'}] {key}: {s['note']}")
    cols = ["target", "case"] + sw.setting_columns + ["key", "passes", "threshold", "first_failing", "rel_width",
                                                      "runs", "converged", "non_monotonic", "passes_beyond", "note"]
    path = os.path.join(sweeper.out, "thresholds.csv")
    results.write_csv(path, cols, rows)
    print(f"probes: {os.path.join(sweeper.out, 'probes.csv')}\nthresholds: {path}")
    if rows and not interrupted:
        import chart
        try:
            prefix = os.path.join(sweeper.out, "thresholds")
            by_target = {}
            for t in selected:
                by_target[t.label()] = probes[t.id]
            chart.threshold_chart(rows, key, prefix, title=f"{sw.title}: stability limit of {key}",
                                  log=cfg["scale"] == "log", probes=by_target, bracket=(cfg["low"], cfg["high"]))
            print(f"chart: {prefix}.png/.svg")
        except chart.ChartError as err:
            print(f"sweep: threshold chart: {err}", file=sys.stderr)
    return interrupted


def select(runs, patterns):
    if not patterns:
        return list(runs)
    out = []
    for r in runs:
        for p in patterns:
            pat = p if any(c in p for c in "*?[") else f"*{p}*"
            if fnmatch.fnmatchcase(r.id, pat) or (r.case and fnmatch.fnmatchcase(r.case, pat)):
                out.append(r)
                break
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(prog="sweep.py", usage=argparse.SUPPRESS, description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter, add_help=True)
    ap.add_argument("sweep_file")
    ap.add_argument("--jobs", type=int)
    ap.add_argument("--out")
    ap.add_argument("--only", action="append", default=[])
    ap.add_argument("--resume", action="store_true")
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--print-expect", action="store_true")
    ap.add_argument("--list", action="store_true")
    ap.add_argument("--bin")
    ap.add_argument("--no-charts", action="store_true")
    args = ap.parse_args(argv)
    try:
        sw = specs.load(args.sweep_file)
        for m in sw.metrics:
            metrics.check_params(m["name"], m["params"])
        if sw.bisect is not None:  # a misspelt column would fail every probe: "no stable value"
            columns = set(results.RUN_COLUMNS)
            for m in sw.metrics:
                columns |= {f"{m['label']}.{k}" for k in metrics.METRICS[m["name"]].columns}
            for col in sw.bisect["fail_if"]:
                if col not in columns:
                    raise specs.SweepError(f"{args.sweep_file}: [bisect] fail_if: {col!r} is not a column of this "
                                           f"sweep; metric columns: {', '.join(sorted(columns - set(results.RUN_COLUMNS)))}")
    except (specs.SweepError, metrics.MetricError) as err:
        print(f"sweep: {err}", file=sys.stderr)
        return 2
    if args.jobs is not None and args.jobs < 1:
        print("sweep: --jobs must be >= 1", file=sys.stderr)
        return 2
    selected = select(sw.runs, args.only)
    if not selected:
        print(f"sweep: --only {' '.join(args.only)} selects none of the {len(sw.runs)} runs", file=sys.stderr)
        return 2
    if args.list:
        for r in selected:
            flags = (" [reference]" if r.reference else "") + (f" expect {r.expect}" if r.expect else "")
            print(f"{r.id}{flags}\n    " + " ".join(f"--set '{a}'" for a in r.set_args()))
        return 0
    if sw.bisect is not None and (args.check or args.print_expect):
        print("sweep: --check and --print-expect apply to grid sweeps, not to a [bisect] file", file=sys.stderr)
        return 2
    sphfsi = find_sphfsi(args.bin)
    if sphfsi is None:
        return 2
    out = os.path.abspath(args.out or os.path.join("out", "sweeps", sw.name))
    os.makedirs(os.path.join(out, "runs"), exist_ok=True)
    jobs = args.jobs or sw.jobs or cores()
    if sw.bisect is None:
        jobs = max(1, min(jobs, len(selected)))
    threads = sw.threads_per_run
    if threads is None and "OMP_NUM_THREADS" not in os.environ:
        threads = max(1, cores() // jobs)
    sweeper = Sweeper(sw, out, sphfsi, jobs, threads, args.resume)
    started = datetime.datetime.now().isoformat(timespec="seconds")
    scene = os.path.relpath(sw.scene)
    scene = sw.scene if scene.startswith("..") else scene
    print(f"sweep {sw.name}: {len(selected)} of {len(sw.runs)} runs of {scene}, {jobs} at a time, "
          f"OMP_NUM_THREADS={sweeper.env.get('OMP_NUM_THREADS', '(unset)')}, into {out}", flush=True)

    if sw.bisect is not None:
        try:
            interrupted = run_bisection(sweeper, selected)
        except BisectionNotRun as err:
            print(err, file=sys.stderr)
            write_description(sweeper, started, {"bisect": sw.bisect, "not_run": str(err)})
            return err.status
        write_description(sweeper, started, {"bisect": sw.bisect})
        return 130 if interrupted else 0

    rows_by_id, interrupted = run_grid(sweeper, selected)
    csv_path = os.path.join(out, "results.csv")
    write_description(sweeper, started)

    def some(ids):
        return f"{len(ids)} kept result(s) (" + ", ".join(ids[:4]) + (", ..." if len(ids) > 4 else "") + ")"

    if sweeper.reused_other_build:
        print(f"sweep: note: {some(sweeper.reused_other_build)} were made by another build of sphfsi than this one "
              "(their rows' notes say so; a metric against such a reference run compares two builds)", file=sys.stderr)
    if sweeper.reused_other_threads:
        print(f"sweep: note: {some(sweeper.reused_other_threads)} ran with another thread count than this sweep's "
              f"{sweeper.threads}: their wall and CPU times do not compare with the others", file=sys.stderr)
    counts = {}
    for r in sw.runs:  # the table's rows: under --only, the kept ones too
        if r.id in rows_by_id:
            s = rows_by_id[r.id].get("status")
            counts[s] = counts.get(s, 0) + 1
    print(f"results: {csv_path} (" + ", ".join(f"{v} {k}" for k, v in sorted(counts.items())) + ")")
    if interrupted:
        return 130
    if not args.no_charts and sw.metrics:
        draw_charts(sweeper, csv_path)
    if args.print_expect:
        print(guard.expect_toml(selected, rows_by_id, sweeper.metric_errors,
                                datetime.datetime.now().isoformat(timespec="minutes")))
    if args.check:
        failures, notes = guard.check(selected, rows_by_id, sw.check)
        for n in notes:
            print(f"check: note: {n}")
        checked = sum(1 for r in selected if r.expect and r.id in rows_by_id)
        if failures:
            for f in failures:
                print(f"check: FAIL {f}")
            print(f"check: {len(failures)} regression(s) in {checked} guarded run(s)")
            return 1
        print(f"check: {checked} guarded run(s) as recorded")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        sys.exit(130)
