"""Stability threshold by bisection on one numeric override.

Both ends of [low, high] are run first: exactly one must pass (complete, and satisfy fail_if), which also
tells the direction (stable below a threshold, like a CFL number, or above one, like an iteration cap).
Then the bracket [good, bad] is halved -- geometrically for scale = "log", arithmetically for "linear",
on integers for integer keys -- until |bad - good| <= rel_tol * |good| (integers: until they are
neighbours) or max_runs probes have run. The threshold reported is `good`, the last passing value, and
`bad` the nearest failing one: the true boundary lies between them, assuming one boundary (a method that
fails, passes and fails again inside the bracket is reported at one of its boundaries; the probes CSV
shows every probe so such cases can be seen).

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


def bound_on_runs(low, high, scale, integer, rel_tol):
    """Probes needed to converge from the two ends (the ends included)."""
    if integer:
        span = max(high - low, 1)
        return 2 + max(0, math.ceil(math.log2(span)))
    if scale == "log":
        ratio = math.log(high / low) / math.log1p(rel_tol)
    else:
        ratio = (high - low) / (rel_tol * low) if low > 0 else (high - low) / (rel_tol * high)
    return 2 + max(0, math.ceil(math.log2(max(ratio, 1.0))))


def bisect(cfg, probe):
    """Runs the bisection; `probe(value)` runs one case and returns (passed: bool, row: dict).
    Returns a summary dict."""
    low, high = cfg["low"], cfg["high"]
    runs = 0
    ok_low, _ = probe(low)
    runs += 1
    ok_high, _ = probe(high)
    runs += 1
    summary = dict(low=low, high=high, runs=runs, threshold=None, first_failing=None, rel_width=None,
                   converged=False, passes="", note="")
    if ok_low and ok_high:
        summary.update(note=f"both ends pass: no failure up to {high} nor down to {low}; widen the bracket",
                       passes="both")
        return summary
    if not ok_low and not ok_high:
        summary.update(note=f"neither end passes: no stable value in [{low}, {high}]", passes="neither")
        return summary
    good, bad = (low, high) if ok_low else (high, low)
    summary["passes"] = "below" if ok_low else "above"
    while not converged(good, bad, cfg["integer"], cfg["rel_tol"]) and runs < cfg["max_runs"]:
        mid = midpoint(good, bad, cfg["scale"], cfg["integer"], cfg["rel_tol"])
        if mid is None:
            break
        ok, _ = probe(mid)
        runs += 1
        if ok:
            good = mid
        else:
            bad = mid
    done = converged(good, bad, cfg["integer"], cfg["rel_tol"])
    summary.update(runs=runs, threshold=good, first_failing=bad,
                   rel_width=abs(bad - good) / abs(good) if good else math.inf, converged=done,
                   note="" if done else f"stopped at max_runs = {cfg['max_runs']} before reaching rel_tol")
    return summary
