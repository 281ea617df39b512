"""Stability threshold by bisection on one numeric override.

Both ends of [low, high] run first: exactly one must pass (complete, and satisfy fail_if), which also
tells the direction: stable below a threshold (a CFL number, a step size: the largest passing value is
sought) or above one (an iteration cap: the smallest passing value).

From all probes so far: `bad` = the failing value nearest the passing end, `good` = the passing value
nearest `bad` on the passing side with no failure between it and the passing end. The bracket
[good, bad] is halved -- geometrically for scale = "log", arithmetically for "linear", on integers for
integer keys -- until |bad - good| <= rel_tol * |good| (integers: neighbours). Then `confirm` more
probes go just inside the threshold, at good / (1 + rel_tol)^k (integers: good -+ k): stability limits
are not always one clean boundary (near it, whether a run survives to end_time can come and go), and a
failure there moves `bad` and the bisection goes on. Everything stops after max_runs probes.

`threshold` = good: every probe on the passing side of it passed. Passing probes beyond `bad` are
reported (non_monotonic) rather than hidden.

Probe values are rounded to a few significant digits (enough for rel_tol) so that they read well and
repeat exactly under --resume.
"""
import math


def midpoint(good, bad, scale, integer, rel_tol):
    """A value strictly between good and bad, or None if there is none (integers)."""
    lo, hi = min(good, bad), max(good, bad)
    if integer:
        m = int(round(math.sqrt(lo * hi))) if scale == "log" and lo > 0 else (lo + hi) // 2
        m = min(max(m, lo + 1), hi - 1)
        return m if lo < m < hi else None
    m = math.sqrt(lo * hi) if scale == "log" else 0.5 * (lo + hi)
    return _round_inside(m, lo, hi, rel_tol)


def _round_inside(m, lo, hi, rel_tol):
    digits = max(3, int(math.ceil(-math.log10(rel_tol))) + 2)
    for d in range(digits, 18):
        r = float(f"{m:.{d}g}")
        if lo < r < hi:
            return r
    return m


def converged(good, bad, integer, rel_tol):
    if integer:
        return abs(bad - good) <= 1
    return abs(bad - good) <= rel_tol * abs(good)


def bound_on_runs(low, high, scale, integer, rel_tol, confirm=0):
    """Probes a clean (single-boundary) bisection needs, the two ends and `confirm` included."""
    if integer:
        span = max(high - low, 1)
        return 2 + max(0, math.ceil(math.log2(span))) + confirm
    if scale == "log":
        ratio = math.log(high / low) / math.log1p(rel_tol)
    else:
        ratio = (high - low) / (rel_tol * low) if low > 0 else (high - low) / (rel_tol * high)
    return 2 + max(0, math.ceil(math.log2(max(ratio, 1.0)))) + confirm


def bisect(cfg, probe):
    """Runs the bisection; `probe(value)` runs one case and returns (passed: bool, row). Returns a summary
    dict: passes ("below", "above", "both", "neither"), threshold, first_failing, rel_width, runs,
    converged, non_monotonic, passes_beyond (passing values beyond first_failing), note."""
    low, high = cfg["low"], cfg["high"]
    integer, tol, scale = cfg["integer"], cfg["rel_tol"], cfg["scale"]
    confirm = cfg.get("confirm", 2)
    history = []

    def run(v):
        ok, _ = probe(v)
        history.append((v, ok))
        return ok

    ok_low, ok_high = run(low), run(high)
    summary = dict(low=low, high=high, runs=2, threshold=None, first_failing=None, rel_width=None,
                   converged=False, passes="", non_monotonic=False, passes_beyond=[], note="")
    if ok_low and ok_high:
        summary.update(passes="both", note=f"both ends pass: no failure in [{low}, {high}]; widen the bracket")
        return summary
    if not ok_low and not ok_high:
        summary.update(passes="neither", note=f"neither end passes: no stable value in [{low}, {high}]")
        return summary
    sign = 1 if ok_low else -1  # sign * value grows from the passing end to the failing one
    start = low if ok_low else high

    def state():
        bad = min((v for v, ok in history if not ok), key=lambda v: sign * v)
        good = max((v for v, ok in history if ok and sign * v < sign * bad), key=lambda v: sign * v)
        return good, bad

    def probed(v):
        return any(abs(v - h) <= (0 if integer else 0.25 * tol * abs(v)) for h, _ in history)

    confirmed = set()
    while len(history) < cfg["max_runs"]:
        good, bad = state()
        if not converged(good, bad, integer, tol):
            mid = midpoint(good, bad, scale, integer, tol)
            if mid is None:
                break
            run(mid)
            continue
        pending = []
        for k in range(1, confirm + 1):
            if integer:
                v = good - sign * k
            else:
                v = _round_inside(good / (1 + tol) ** k if sign > 0 else good * (1 + tol) ** k,
                                  min(start, good), max(start, good), tol)
            if sign * v <= sign * start or probed(v) or (good, k) in confirmed:
                continue
            pending.append((k, v))
        if not pending:
            break
        k, v = pending[0]
        confirmed.add((good, k))
        run(v)
    good, bad = state()
    done = converged(good, bad, integer, tol)
    beyond = sorted((v for v, ok in history if ok and sign * v > sign * bad), key=lambda v: sign * v)
    note = "" if done else f"stopped at max_runs = {cfg['max_runs']} before reaching rel_tol"
    if beyond:
        note = (note + "; " if note else "") + ("passes again beyond the first failing value at "
                                                + ", ".join(f"{v:g}" for v in beyond)
                                                + ": no single boundary; the threshold is the last value "
                                                  "below which every probe passed")
    summary.update(runs=len(history), threshold=good, first_failing=bad,
                   rel_width=abs(bad - good) / abs(good) if good else math.inf, converged=done,
                   passes="below" if sign > 0 else "above", non_monotonic=bool(beyond), passes_beyond=beyond,
                   note=note)
    return summary
