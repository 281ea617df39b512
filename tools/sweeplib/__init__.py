"""Sweep machinery behind tools/sweep.py, tools/chart.py and tools/metrics.py (docs/sweeps.md).

spec     -- reads and checks a sweep file, expands it into runs with deterministic folder names
runner   -- runs one coordinator with a wall-clock limit, measures wall and CPU seconds, classifies the end
record   -- reads what a run left (record.h5, watchpoints.csv) into cost columns
results  -- the results CSV and its description (sweep.json)
expect   -- the regression guard (--check)
bisect   -- stability thresholds by bisection on one numeric override
formula  -- a small, safe arithmetic evaluator for analytic reference values
"""
