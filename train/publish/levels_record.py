"""The committed record of a multi-level evaluation (``formation-env evaluate --turbulence 0 0.5 1 1.5``, whose
output directory holds ``levels.json`` and one ``sigma_<level>/results.json`` per level; one level's directory, its
``results.json``): per level the
summaries of every policy (ablated copies included), the paired comparisons, and per-episode columns of the
quantities close formation is judged by for the controllers themselves (harvest ratio, slot-frame RMS errors,
smallest separation, collision, episode length, and a moving-slot task's success and settling time: enough to recompute their intervals and paired differences).
The per-decision series and the ablated copies' episodes stay out (the full results are ~30 MB).

    python -m train.publish.levels_record RESULTS_DIR OUT.json [--command "..."] [--overwrite]

The N-UAV records hold several such records, one list per task flown (``{"_about": text, "records": {task:
[record, ...]}}``: a formation's policies flown on their own task and, without retraining, on others):

    python -m train.publish.levels_record RESULTS_DIR OUT.json --task TASK [--about TEXT] [--command "..."]

adds this record to ``records[TASK]`` of OUT.json (a new file needs ``--about``, what the record holds; an existing
one keeps its own, unless ``--about`` with ``--overwrite`` replaces it). Adding never drops a record already there.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

__all__ = ["EPISODE_KEYS", "add_to_task_record", "levels_record", "main"]

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


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m train.publish.levels_record", description=__doc__.split("\n\n")[0])
    p.add_argument("results_dir")
    p.add_argument("out")
    p.add_argument("--command", help="the evaluate command that made the results (stored in the record)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace OUT.json (with --task: replace its '_about' by --about; its records are kept)")
    p.add_argument("--task", help="add the record to OUT.json's records[TASK] (a multi-task record, e.g. the "
                                  "N-UAV ones) instead of writing a one-record file")
    p.add_argument("--about", help="with --task: what the multi-task record holds (required for a new file)")
    a = p.parse_args(argv)
    if a.about is not None and a.task is None:
        print("error: --about belongs to a multi-task record: give --task as well", file=sys.stderr)
        return 2
    from formation_env.io import atomic_write_text

    src = Path(a.results_dir)
    if not ((src / "levels.json").is_file() or (src / "results.json").is_file()):
        print(f"error: {src} has no levels.json or results.json (is it the --out of 'formation-env evaluate'?)",
              file=sys.stderr)
        return 2
    try:
        rec = levels_record(src, command=a.command)
        if a.task is not None:
            whole = add_to_task_record(rec, a.out, a.task, about=a.about, overwrite_about=a.overwrite)
            print(f"added to {a.out}: records {({k: len(v) for k, v in whole['records'].items()})}")
            return 0
        atomic_write_text(a.out, json.dumps(rec, separators=(",", ":")) + "\n", overwrite=a.overwrite)
    except (FileExistsError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
