"""The absolute metric of the headline tasks (Gorsane et al., NeurIPS 2022): each learned method's best training
seed, flown again on ten times the test episodes.

The seed is chosen by the task's headline metric at its headline turbulence level on the 100 test episodes of the
method's committed record, with the results page's estimator (the IQM; the mean for a 0/1 success). It is then
flown on :data:`ABSOLUTE_EPISODES` further held-out episodes, the seeds ``seed_base + 100`` on (disjoint from the
episodes that chose it, so the choice does not bias the figure), with the task's own evaluation protocol: the
generic evaluation (:func:`train.evaluation.evaluate.evaluate`, the saving computed) or, for a task with its own
evaluation (``Task.evaluator``: each episode measured against its reference optimum), that task's flight
(:func:`train.evaluation.task_eval.fly`). The record,
``train/policies/<task>_absolute.json``, holds one entry per method: the seed chosen and why, the command, and
the per-episode columns; the results page computes every number it shows from them.

    formation-env results --absolute TASK   # fly the best seed of each method of TASK and write its record
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from formation_env.tasks import TASKS

__all__ = ["ABSOLUTE_EPISODES", "ABSOLUTE_SEED_OFFSET", "ABSOLUTE_TASKS", "best_seeds", "absolute_record",
           "write_absolute", "absolute_path", "absolute_markdown", "absolute_episodes"]

ABSOLUTE_EPISODES = 1000   # ten times the test episodes of a record
ABSOLUTE_SEED_OFFSET = 100  # the first seed after the test episodes the best seed is chosen on
#: the tasks whose learned methods are flown on the absolute metric's episodes (their EvaluationProtocol.absolute)
ABSOLUTE_TASKS = tuple(name for name, task in TASKS.items() if task.evaluation.absolute)
#: per-episode columns a record keeps (where the evaluation gives them)
KEEP = ("seed", "duration_s", "harvest_ratio", "saving_ratio", "saving", "formation_saving", "rms_along_track_m",
        "rms_lateral_m", "rms_vertical_m", "min_separation_m", "collision", "reconfig_success", "reconfig_time_s")


def _pages():
    from . import record_data

    return record_data


def _estimator(metric: str) -> str:
    return "mean" if metric == "reconfig_success" else "iqm"


def _point(x: np.ndarray, stat: str) -> float:
    if stat == "mean":
        return float(np.mean(x))
    from scipy import stats

    return float(stats.trim_mean(x, 0.25))


def best_seeds(task_name: str, data: dict | None = None) -> dict[str, dict]:
    """method (record group) -> {"policy": run name, "value": its estimate on the test episodes, "estimator",
    "episodes"}: the best training seed of every learned method with three seeds on the task's own record at
    its headline level (a transfer, a classical baseline or a ceiling is not a method of the task)."""
    from formation_env.tasks import get_task

    rp = _pages()
    task = get_task(task_name)
    ev = task.evaluation
    data = rp.collect() if data is None else data
    level = data.get(task_name, {}).get(ev.headline_level)
    if level is None:
        raise ValueError(f"no committed record of {task_name!r} at its headline level {ev.headline_level:g} m/s")
    stat = _estimator(ev.metric)
    out = {}
    for group, runs in sorted(level["runs"].items()):
        if group in rp.CLASSICAL or group in rp.CEILINGS or "transfer" in rp._label(group, task_name):
            continue
        scored = []
        for name, cols in sorted(runs.items()):
            key = rp._metric_key(cols, ev.metric)
            if key is not None:
                scored.append((_point(cols[key], stat), name, len(cols[key])))
        if not scored:
            continue
        pick = (max if ev.higher_is_better else min)(scored, key=lambda s: s[0])
        out[group] = {"policy": pick[1], "value": round(pick[0], 6), "estimator": stat, "episodes": pick[2]}
    return out


def _columns(episodes: list[dict]) -> dict[str, list]:
    cols = {}
    for k in KEEP:
        vals = [e.get(k) for e in episodes]
        if all(isinstance(v, (int, float, bool, np.floating, np.integer)) for v in vals):
            # a quantity an episode does not reach (a failed reconfiguration's settling time) is null, not NaN
            cols[k] = [int(v) if k == "seed" else (None if np.isnan(v) else float(f"{float(v):.6g}")) for v in vals]
    return cols


def _dump(rec: dict) -> str:
    """One line per column: the record stays readable and small."""
    return json.dumps(rec, separators=(",", ":")).replace(',"', ',\n"') + "\n"


def absolute_record(task_name: str, group: str, *, episodes: int = ABSOLUTE_EPISODES, log=print) -> dict:
    """Fly ``group``'s best seed (:func:`best_seeds`) on ``episodes`` held-out episodes of the task's headline
    level; the record entry (see the module docstring)."""
    from formation_env.tasks import get_task

    task = get_task(task_name)
    ev = task.evaluation
    choice = best_seeds(task_name).get(group)
    if choice is None:
        raise ValueError(f"{group!r} is not a learned method with a committed record of {task_name!r}; "
                         f"methods: {sorted(best_seeds(task_name))}")
    rp = _pages()
    zip_path = rp.POLICIES / f"{choice['policy']}.zip"
    first = ev.seed_base + ABSOLUTE_SEED_OFFSET
    seeds = [first + i for i in range(episodes)]
    rel = zip_path.relative_to(rp.REPO)
    if task.evaluator is not None:  # the task's own evaluation: each episode against its reference optimum
        from train.evaluation.task_eval import fly, policy_from_zip

        eps = fly(task_name, policy_from_zip(str(zip_path)), seeds)  # the task's preset, at its own level
        command = f"formation-env results --absolute {task_name}"
    else:
        from train.evaluation.evaluate import evaluate

        rep = evaluate([str(zip_path)], scenario=task_name, episodes=episodes, seeds=[first],
                       turbulence_sigma_mps=ev.headline_level, compute_benefit=True, plots=False, log=log)
        eps = next(iter(rep["policies"].values()))["episodes"]
        command = (f"formation-env evaluate --scenario {task_name} --policy {rel} --turbulence "
                   f"{ev.headline_level:g} --episodes {episodes} --seeds {first} --benefit --no-plots --out DIR")
    return {"task": task_name, "task_version": task.version, "method": group, "policy": choice["policy"],
            "selection": {k: choice[k] for k in ("estimator", "value", "episodes")}, "metric": ev.metric,
            "turbulence_sigma_mps": ev.headline_level, "seeds": [seeds[0], seeds[-1]], "n_episodes": len(seeds),
            "command": command, "episodes": _columns(eps)}


def absolute_path(task_name: str) -> Path:
    return _pages().POLICIES / f"{task_name}_absolute.json"


def write_absolute(task_name: str, *, overwrite: bool = False, episodes: int = ABSOLUTE_EPISODES, log=print) -> Path:
    """Fly every learned method of ``task_name`` (:func:`absolute_record`) and write the task's record
    atomically; an existing method's entry is replaced only with ``overwrite``."""
    if task_name not in ABSOLUTE_TASKS:
        raise ValueError(f"the absolute metric is kept for {list(ABSOLUTE_TASKS)}, got {task_name!r}")
    path = absolute_path(task_name)
    rec = json.loads(path.read_text()) if path.is_file() else {"records": {}}
    for group in best_seeds(task_name):
        if group in rec["records"] and not overwrite:
            log(f"{path.name}: {group} already recorded (overwrite to replace it)")
            continue
        rec["records"][group] = absolute_record(task_name, group, episodes=episodes, log=log)
        tmp = path.with_suffix(".json.tmp")
        tmp.write_text(_dump(rec))
        tmp.replace(path)
    return path


def absolute_episodes(task_name: str) -> dict[tuple[str, str], np.ndarray]:
    """(method, policy) -> the headline metric of its absolute flight, per episode (empty without a record)."""
    from formation_env.tasks import get_task

    path = absolute_path(task_name)
    if not path.is_file():
        return {}
    metric = get_task(task_name).evaluation.metric
    out = {}
    for group, r in json.loads(path.read_text())["records"].items():
        cols = {k: np.asarray(v, dtype=float) for k, v in r["episodes"].items()}
        out[(group, r["policy"])] = cols[_pages()._metric_key(cols, metric)]
    return out


def absolute_markdown(task, data: dict) -> list[str]:
    """The page's "absolute metric" subsection of ``task`` (empty without a record). That each record flew the seed
    :func:`best_seeds` chooses from the committed records is a test's to hold (tests/train/test_results_page.py)."""
    from train.evaluation.aggregates import aggregate

    rp = _pages()
    path = absolute_path(task.name)
    if not path.is_file():
        return []
    rec = json.loads(path.read_text())["records"]
    ev = task.evaluation
    stat = _estimator(ev.metric)
    name = "mean" if stat == "mean" else "IQM"
    lines = ["### Absolute metric", "",
             f"Each method's best training seed (by the {name} of the headline metric on the 100 test episodes "
             f"above) flown on {ABSOLUTE_EPISODES:,} further held-out episodes at sigma {ev.headline_level:g} m/s. "
             f"Record: `{path.name}` (sha256 {rp._digest(path)}).", "",
             f"| method | seed chosen ({name} on its 100 episodes) | episodes | {name} [95 % CI] | mean | "
             "lateral RMS, b | vertical RMS, b | collisions |", "|---|---|---|---|---|---|---|---|"]
    for group, r in sorted(rec.items()):
        cols = {k: np.asarray(v, dtype=float) for k, v in r["episodes"].items()}
        key = rp._metric_key(cols, ev.metric)
        agg = aggregate(cols[key][None, :], statistics=("iqm", "mean"), n_boot=rp.N_BOOT, seed=0)
        lat, ver = cols.get("rms_lateral_m"), cols.get("rms_vertical_m")
        col = cols.get("collision")
        rms = (lambda x: "-" if x is None else rp._fmt(float(np.sqrt(np.mean(x ** 2)) / rp.SPAN_M)))
        seed = r["policy"].rsplit("_seed", 1)[-1]
        lines.append(f"| {rp._label(group, task.name)} | seed {seed} ({r['selection']['value']:.3f}) | "
                     f"{r['n_episodes']:,} | {rp._fmt(agg[stat]['value'], agg[stat]['ci'])} | "
                     f"{rp._fmt(agg['mean']['value'])} | {rms(lat)} | {rms(ver)} | "
                     f"{'-' if col is None else f'{int(col.sum())} / {col.size}'} |")
    return lines + [""]
