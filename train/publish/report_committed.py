"""Evaluate the committed policies (3 training seeds per task) beside the thesis PID and ``pid_formation``
on 100 held-out test episodes, attach the results to their metadata and draw the README figures.

    formation-env publish committed --out DIR [--episodes 100] [--tasks ...]   # all under DIR
    formation-env publish committed --overwrite [--episodes 100]   # into the tracked files

For each task: ``formation-env evaluate`` with the three seeds, ``pid`` and ``pid_formation`` (frozen
Dryden turbulence sigma 1 m/s, wake on, seeds 20000000000..), written to ``OUT/<task>/``; the slim record
(per-episode metrics, summaries, paired comparisons, seed groups) ``<task>_ppo_setpoints_evaluation.json``;
each policy's ``NAME.json`` with its summary and comparisons; the rliable aggregates over the three seeds x
episodes (in the record and ``OUT/<task>/results.md``) and ``OUT/<task>/marl_eval.json``. Figures:
``eval_<task>_slot_error.png``, ``eval_<task>_performance_profile.png`` (rliable) and ``training_curves.png``
(validation curves with the baselines' RMS on the same validation episodes).

Without ``--overwrite`` the records, metadata and figures go to ``OUT/policies/`` and ``OUT/figures/``
(nothing tracked is touched; OUT must be new or empty); with ``--overwrite`` they replace
``train/policies/`` and ``docs/figures/`` (the evaluation directories still go to OUT). Every input and
every file to be written is checked before the first episode flies, so a run never stops half way on a
file it may not write.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
from pathlib import Path

from formation_env.io import atomic_write, atomic_write_json
from formation_env.tasks import TASKS as _TASKS

from ..config import VALIDATION_SEED_BASE
from ..evaluation.evaluate import MAX_EPISODES, evaluate
from . import publish
from .publish import attach_evaluation, plot_validation_curves

#: the tasks whose committed PPO evaluation this command writes: those with such a record
#: (``EvaluationProtocol.ppo_record_score``) and the generic evaluation (a task with its own, wake_surfing, writes
#: its record with ``formation-env publish records``)
TASKS = tuple(name for name, task in _TASKS.items()
              if task.evaluation.ppo_record_score is not None and task.evaluator is None)
FIGURES = Path(__file__).resolve().parents[2] / "docs" / "figures"
DEFAULT_OUT = "results/committed-eval"


def policy_names(task: str) -> list[str]:
    return [f"{task}_ppo_setpoints_seed{k}" for k in range(3)]


def plan(out: Path, tasks, *, overwrite: bool) -> dict:
    """Where every output goes: {"policies": dir of records and NAME.json, "figures": dir, "eval": {task:
    dir}, "files": [every file written]}."""
    policies = publish.POLICIES if overwrite else out / "policies"
    figures = FIGURES if overwrite else out / "figures"
    files = [out / "validation_baselines.json", figures / "training_curves.png"]
    for task in tasks:
        files += [out / task / "results.json", out / task / "results.md", policies / f"{task}_ppo_setpoints_evaluation.json",
                  figures / f"eval_{task}_slot_error.png", figures / f"eval_{task}_performance_profile.png"] + \
            [policies / f"{n}.json" for n in policy_names(task)]
    return {"policies": policies, "figures": figures, "eval": {t: out / t for t in tasks}, "files": files}


def _writable_dir(d: Path) -> str | None:
    """None if files can be created in ``d`` (it exists writable, or its nearest existing parent is)."""
    p = d
    while not p.exists() and p != p.parent:
        p = p.parent
    if not p.is_dir():
        return f"{str(p)!r} is not a directory"
    if not os.access(p, os.W_OK | os.X_OK):
        return f"{str(p)!r} is not writable"
    return None


def check_plan(out: Path, tasks, *, overwrite: bool) -> dict:
    """Raise ValueError (one line) unless every input exists and every output may be written."""
    p = plan(out, tasks, overwrite=overwrite)
    for task in tasks:
        for n in policy_names(task):
            for suffix in (".zip", ".json", "_evaluations.json"):
                src = publish.POLICIES / f"{n}{suffix}"
                if not src.is_file():
                    raise ValueError(f"missing committed file {str(src)!r} (run train/committed_runs.sh first)")
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {str(out)!r} exists and is not a directory")
    if not overwrite and out.is_dir() and any(out.iterdir()):
        raise ValueError(f"--out {str(out)!r} exists and is not empty (choose a new or empty directory)")
    for f in p["files"]:
        if f.exists() and not overwrite:
            raise ValueError(f"refusing to overwrite {str(f)!r} (choose a new or empty --out)")
        if f.exists() and (not f.is_file() or not os.access(f, os.W_OK)):
            raise ValueError(f"cannot overwrite {str(f)!r}: not a writable file")
        why = _writable_dir(f.parent)
        if why:
            raise ValueError(f"cannot write {str(f)!r}: {why}")
    return p


def _validation_baselines(task: str, episodes: int) -> dict:
    """The thesis PID's and pid_formation's RMS slot error on the validation episodes (the lines beside the curves)."""
    val = evaluate(["pid", "pid_formation"], scenario=task, episodes=episodes, seeds=[VALIDATION_SEED_BASE], plots=False)
    return {f"{n} (validation)": val["policies"][n]["summary"]["rms_slot_error_m"] for n in ("pid", "pid_formation")}


def report_committed(out: str | Path = DEFAULT_OUT, *, overwrite: bool = False, episodes: int = 100,
                     validation_episodes: int = 32, tasks=TASKS) -> int:
    """``formation-env publish committed``: evaluate the committed policies of ``tasks`` on ``episodes`` held-out
    episodes and write the records, metadata and figures (see the module docstring); ``validation_episodes``: the
    baselines' lines in training_curves.png. Every input and output is checked (a ValueError naming it) before
    the first episode flies."""
    unknown = [t for t in tasks if t not in TASKS]
    if unknown:
        raise ValueError(f"--tasks: unknown task(s) {unknown}; the committed ones are {list(TASKS)}")
    if not (1 <= episodes <= MAX_EPISODES and 1 <= validation_episodes <= MAX_EPISODES):
        raise ValueError(f"episodes must be integers in [1, {MAX_EPISODES}], got {episodes} and {validation_episodes}")
    out = Path(out)
    p = check_plan(out, tasks, overwrite=overwrite)
    print(f"writing the evaluations to {out}/, records and metadata to {p['policies']}/, figures to {p['figures']}/",
          file=sys.stderr)
    baselines = {}
    for task in tasks:
        names = policy_names(task)
        rep = evaluate([str(publish.POLICIES / f"{n}.zip") for n in names] + ["pid", "pid_formation"], scenario=task,
                       episodes=episodes, out_dir=p["eval"][task], overwrite=overwrite, log=print)
        print(rep["table_markdown"])
        print(rep.get("comparison_markdown", ""))
        print(rep.get("groups_markdown", ""))
        attach_evaluation(names, p["eval"][task] / "results.json",
                          p["policies"] / f"{task}_ppo_setpoints_evaluation.json", overwrite=overwrite,
                          meta_dir=p["policies"])
        print(rep.get("aggregates_markdown", ""))
        for fig in ("slot_error", "performance_profile"):  # the profile needs rliable (the evaluation extra)
            if fig == "performance_profile" and not (p["eval"][task] / f"{fig}.png").is_file():
                continue
            atomic_write(p["figures"] / f"eval_{task}_{fig}.png",
                         lambda tmp, src=p["eval"][task] / f"{fig}.png": shutil.copyfile(src, tmp), overwrite=overwrite)
        baselines[task] = _validation_baselines(task, validation_episodes)
    for task in TASKS:  # the figure shows every task: the baselines of those not re-evaluated are measured too
        if task not in baselines:
            baselines[task] = _validation_baselines(task, validation_episodes)
    atomic_write_json(out / "validation_baselines.json", baselines, overwrite=overwrite)
    plot_validation_curves({t: policy_names(t) for t in TASKS}, p["figures"] / "training_curves.png",
                           baselines=baselines)
    print(f"done: evaluations in {out}/<task>/, records and metadata in {p['policies']}/, figures in {p['figures']}/")
    return 0


