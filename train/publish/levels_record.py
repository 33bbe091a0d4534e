"""The committed record of a multi-level evaluation (``formation-env evaluate --turbulence 0 0.5 1 1.5``, whose
output directory holds ``levels.json`` and one ``sigma_<level>/results.json`` per level; one level's directory, its
``results.json``): per level the
summaries of every policy (ablated copies included), the paired comparisons, and per-episode columns of the
quantities close formation is judged by for the controllers themselves (harvest ratio, slot-frame RMS errors,
smallest separation, collision, episode length, and a moving-slot task's success and settling time: enough to recompute their intervals and paired differences).
The per-decision series and the ablated copies' episodes stay out (the full results are ~30 MB).

    formation-env publish levels RESULTS_DIR OUT.json [--command "..."] [--overwrite]

The N-UAV records hold several such records, one list per task flown (``{"_about": text, "records": {task:
[record, ...]}}``: a formation's policies flown on their own task and, without retraining, on others):

    formation-env publish levels RESULTS_DIR OUT.json --task TASK [--about TEXT] [--command "..."]

adds this record to ``records[TASK]`` of OUT.json (a new file needs ``--about``, what the record holds; an existing
one keeps its own, unless ``--about`` with ``--overwrite`` replaces it). Adding never drops a record already there.
"""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["EPISODE_KEYS", "add_to_task_record", "levels_record", "write_levels_record"]

EPISODE_KEYS = ("seed", "duration_s", "harvest_ratio", "rms_along_track_m", "rms_lateral_m", "rms_vertical_m",
                "min_separation_m", "collision", "formation_saving")
# kept where the task has them (a moving-slot task: reconfiguration, vee_rotation)
OPTIONAL_EPISODE_KEYS = ("reconfig_success", "reconfig_time_s")


def _round(v):
    return float(f"{v:.6g}") if isinstance(v, float) else v


def levels_record(results_dir: str | Path, *, command: str | None = None) -> dict:
    """The compact record of ``results_dir`` (see the module docstring)."""
    src = Path(results_dir)
    if (src / "levels.json").is_file():
        levels = json.loads((src / "levels.json").read_text())
        files = {f"sigma_{lv:g}": src / f"sigma_{lv:g}" / "results.json" for lv in levels["levels"]}
    else:  # one level (``--turbulence L``): the directory's own results.json
        rep = json.loads((src / "results.json").read_text())
        levels = {"scenario": rep["scenario"], "levels": [rep["turbulence_sigma_mps"]]}
        files = {f"sigma_{rep['turbulence_sigma_mps']:g}": src / "results.json"}
    out = {"scenario": levels["scenario"], "levels": levels["levels"], "command": command, "by_level": {}}
    for name, path in files.items():
        rep = json.loads(path.read_text())
        out["by_level"][name] = {
            "turbulence_sigma_mps": rep["turbulence_sigma_mps"], "turbulence_field": rep.get("turbulence_field"),
            "wake_coupling": rep.get("wake_coupling"),
            "wake_fidelity": rep.get("wake_fidelity", "lattice"), "seeds": [rep["seeds"][0], rep["seeds"][-1]],
            "n_episodes": len(rep["seeds"]),
            "summaries": {p: {k: v for k, v in x["summary"].items() if k != "wall_s"} for p, x in rep["policies"].items()},
            "comparisons": rep.get("comparisons", {}),
            "episodes": {p: {k: [_round(e.get(k)) for e in x["episodes"]]
                             for k in EPISODE_KEYS + tuple(k for k in OPTIONAL_EPISODE_KEYS
                                                           if any(k in e for e in x["episodes"]))}
                         for p, x in rep["policies"].items() if "-without-" not in p},
        }
    md = src / "levels.md"
    out["table_markdown"] = md.read_text() if md.is_file() else None
    return out


def add_to_task_record(record: dict, path: str | Path, task: str, *, about: str | None = None,
                       overwrite_about: bool = False) -> dict:
    """``path``'s multi-task record (a new one when absent: ``about`` required) with ``record`` appended to
    ``records[task]``; written atomically. Returns the whole record."""
    from formation_env.io import atomic_write_text

    if not isinstance(task, str) or not task.strip():
        raise ValueError(f"task must be a non-empty name (the record's key), got {task!r}")
    path = Path(path)
    if path.is_file():
        whole = json.loads(path.read_text())
        if not (isinstance(whole, dict) and isinstance(whole.get("records"), dict) and "_about" in whole):
            raise ValueError(f"{path} is not a multi-task record (a JSON object with '_about' and 'records'); "
                             f"a one-record file is written without --task")
        if about is not None:
            if not overwrite_about and about != whole["_about"]:
                raise FileExistsError(f"{path} has its own '_about'; pass --overwrite to replace it with --about")
            whole["_about"] = about
    else:
        if not about:
            raise ValueError(f"{path} does not exist: a new multi-task record needs --about (what it holds)")
        whole = {"_about": about, "records": {}}
    whole["records"].setdefault(task, []).append(record)
    atomic_write_text(path, json.dumps(whole, separators=(",", ":")) + "\n", overwrite=True)
    return whole


def write_levels_record(results_dir: str | Path, out: str | Path, *, command: str | None = None,
                        overwrite: bool = False, task: str | None = None, about: str | None = None) -> str:
    """Write the record of ``results_dir`` to ``out`` (``formation-env publish levels``; see the module docstring):
    one record, or with ``task`` added to a multi-task record. Returns what was done, in one line; a ValueError or
    FileExistsError names what is wrong before anything is written."""
    from formation_env.io import atomic_write_text

    if about is not None and task is None:
        raise ValueError("--about belongs to a multi-task record: give --task as well")
    src = Path(results_dir)
    if not ((src / "levels.json").is_file() or (src / "results.json").is_file()):
        raise ValueError(f"{src} has no levels.json or results.json (is it the --out of 'formation-env evaluate'?)")
    rec = levels_record(src, command=command)
    if task is not None:
        whole = add_to_task_record(rec, out, task, about=about, overwrite_about=overwrite)
        return f"added to {out}: records {({k: len(v) for k, v in whole['records'].items()})}"
    atomic_write_text(out, json.dumps(rec, separators=(",", ":")) + "\n", overwrite=overwrite)
    return f"wrote {out}"
