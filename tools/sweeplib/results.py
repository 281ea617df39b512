"""The results CSV (one row per run) and its description file sweep.json.

Columns, in order: run, case, one column per varied setting, then RUN_COLUMNS, then the metric columns
LABEL.QUANTITY, then notes. Empty cell: not applicable or not available (docs/sweeps.md says which).
"""
import csv
import json
import math
import os

RUN_COLUMNS = {
    "status": ("how the run ended: completed, failed, timeout, invalid or interrupted", ""),
    "message": ("first line of what went wrong (empty when completed)", ""),
    "exit_code": ("the coordinator's exit status (0, 1, 2, 130; -N: killed by signal N)", ""),
    "wall_s": ("wall-clock time of the run, start of the coordinator to its exit", "s"),
    "cpu_s": ("CPU time of the coordinator and its participants (user + system)", "s"),
    "record_wall_s": ("the coupling windows' wall time summed, recording and snapshots left out (record attribute "
                      "wall_s)", "s"),
    "t_end": ("simulated time reached (end of the last window)", "s"),
    "windows": ("coupling windows taken", ""),
    "coupling_iterations": ("sum over windows of coupling iterations", ""),
    "fluid_particles": ("fluid particles (walls and solids not counted; the total where the record does not tell them apart)", ""),
    "particles_total": ("all SPH particles (fluid, wall, solid)", ""),
    "fluid_substeps": ("sum over windows of fluid sub-steps", ""),
    "particle_steps": ("fluid particles x sum of fluid sub-steps, every coupling iteration's (empty without a fluid)",
                       "particle-steps"),
    "fluid_solver_iterations": ("sum of PCISPH iterations", ""),
    "fluid_threads": ("OpenMP threads the fluid reported", ""),
    "structure_elements": ("beam elements", ""),
    "structure_substeps": ("sum over windows of structure sub-steps", ""),
    "element_steps": ("structure elements x sum of structure sub-steps, every coupling iteration's (empty "
                      "without a structure)", "element-steps"),
    "structure_solver_iterations": ("sum of the structure's Newton iterations", ""),
}
COST_LABELS = {
    "wall_s": "wall-clock time [s]",
    "cpu_s": "CPU time, coordinator + participants [s]",
    "record_wall_s": "wall time of the coupling windows [s]",
    "particle_steps": "particle-steps (fluid particles x fluid sub-steps)",
    "element_steps": "element-steps (beam elements x structure sub-steps)",
    "coupling_iterations": "coupling iterations (sum over windows)",
}


def columns(setting_columns, metric_columns):
    return ["run", "case"] + list(setting_columns) + list(RUN_COLUMNS) + list(metric_columns) + ["notes"]


def cell(v):
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(v)
    if isinstance(v, (list, dict)):
        from .spec import toml_value
        return toml_value(v)
    return str(v)


def write_csv(path, cols, rows):
    """Writes rows (dicts) atomically: a reader never sees half a file."""
    tmp = path + ".tmp"
    with open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for r in rows:
            w.writerow([cell(r.get(c)) for c in cols])
    os.replace(tmp, path)


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def write_json(path, data):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(data, f, indent=1, sort_keys=False, default=str)
        f.write("\n")
    os.replace(tmp, path)


def number(text):
    """A CSV cell as float (nan when empty or not a number)."""
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan
