"""The committed records of a task with its own evaluation (``train/policies/<group>_levels.json`` and the task
group's ``<group>_evaluation.json``): every controller flown once per setting of the task's
:class:`~formation_env.tasks.evaluation.RecordSpec` on the default held-out seeds, its episodes saved as
``EPISODES_DIR/<scenario>_sigma_<s>/<name>.json``, then each policy group's report
(:func:`train.evaluation.task_eval.task_report`, what ``formation-env evaluate --task-report`` runs after flying)
from the same episodes, so that the baselines and ceilings are flown once for every group.

    formation-env publish records TASK EPISODES_DIR ZIP [ZIP ...] [--out-dir train/policies] [--overwrite]

Zips are named ``<group>_seed<k>.zip``; flights already saved in EPISODES_DIR are not flown again.
"""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["fly_setting", "group_levels", "record_spec", "main"]


def record_spec(task_name: str):
    """(task, its RecordSpec); a ValueError for a task without committed records of its own."""
    from formation_env.tasks import get_task

    task = get_task(task_name)
    if task.evaluator is None or task.evaluator.records is None:
        raise ValueError(f"task {task_name!r} has no records of its own evaluation")
    return task, task.evaluator.records


def _setting_dir(episodes_dir: Path, scenario: str, sigma: float) -> Path:
    return Path(episodes_dir) / f"{scenario}_sigma_{sigma:g}"


def fly_setting(task_name: str, episodes_dir, scenario: str, sigma: float, zips, *, episodes: int = 100,
                log=print) -> list[str]:
    """Fly the baselines, the ceilings and every policy in ``zips`` on ``episodes`` held-out episodes of one setting,
    each saved once (an existing file is kept); the names flown."""
    from formation_env.io import atomic_write_text

    from ..config import TEST_SEED_BASE
    from ..evaluation.episodes import eval_env_config
    from ..evaluation.task_eval import agent_kit, fly, policy_from_zip

    task, spec = record_spec(task_name)
    kit = agent_kit()
    out = _setting_dir(episodes_dir, scenario, sigma)
    out.mkdir(parents=True, exist_ok=True)
    cfg = eval_env_config(scenario, "setpoints", turbulence_sigma_mps=sigma)
    seeds = [TEST_SEED_BASE + i for i in range(episodes)]
    controllers = [*task.evaluator.baselines(kit), *(task.evaluator.ceiling(kit, c) for c in spec.ceilings),
                   *(policy_from_zip(str(z)) for z in zips)]
    for c in controllers:
        f = out / f"{c.name}.json"
        if not f.exists():
            eps = fly(scenario, c, seeds, config=cfg)
            atomic_write_text(f, json.dumps(eps, default=float))
            log(f"{scenario} sigma {sigma:g} {c.name}: {len(eps)} episodes")
    return [c.name for c in controllers]


def _group_report(task, spec, episodes_dir, scenario: str, sigma: float, group: str) -> tuple[dict, list[str]]:
    from ..evaluation.episodes import eval_env_config
    from ..evaluation.task_eval import agent_kit, rounded, task_report

    d = _setting_dir(episodes_dir, scenario, sigma)
    names = sorted(p.stem for p in d.glob(f"{group}_seed*.json"))
    if not names:
        raise ValueError(f"no episodes of policy group {group!r} in {d}")
    kit = agent_kit()
    ceilings = [task.evaluator.ceiling(kit, c).name for c in spec.ceilings]
    eps = {n: json.loads((d / f"{n}.json").read_text()) for n in [*task.evaluator.baseline_names, *names, *ceilings]}
    cfg = eval_env_config(scenario, "setpoints", turbulence_sigma_mps=sigma)
    first = task.evaluator.baseline_names[0]
    r = task_report(task, eps, names, scenario=scenario, seeds=[e["seed"] for e in eps[first]],
                    randomisation=cfg.randomisation, policy_specs={n: f"train/policies/{n}.zip" for n in names})
    return rounded(json.loads(json.dumps(r, default=float))), names


def group_levels(task_name: str, episodes_dir, group: str, settings=None) -> tuple[dict, dict | None]:
    """``(levels, full)``: the group's levels (``<scenario>_sigma_<s>`` -> summaries of every controller, paired
    comparisons, rliable aggregates and per-episode columns: every controller's for the task group, the policies'
    only for another group) and, for the task group, the full report of its task level (None otherwise).
    ``settings``: (scenario, sigma) pairs (None: the task's)."""
    from formation_env.scenarios import get_scenario

    task, spec = record_spec(task_name)
    levels, full = {}, None
    for scenario, sigma in (spec.settings if settings is None else settings):
        r, names = _group_report(task, spec, episodes_dir, scenario, sigma, group)
        key = f"{scenario}_sigma_{sigma:g}"
        is_full = (group, key) == tuple(spec.full)
        if is_full:
            full = r
        keep = list(r["controllers"]) if group == spec.full[0] else names
        levels[key] = {
            "scenario": scenario, "wake_fidelity": get_scenario(scenario).wake_fidelity, "turbulence_sigma_mps": sigma,
            "seeds": [r["seeds"][0], r["seeds"][-1]],
            "summaries": {n: c["summary"] for n, c in r["controllers"].items()},
            "comparisons": r["comparisons"], "seed_spread": r.get("seed_spread"), "aggregates": r.get("aggregates"),
            "episodes": (f"in train/policies/{group}_evaluation.json (every episode in full)" if is_full else
                         {n: {k: [e[k] for e in r["controllers"][n]["episodes"]] for k in spec.episode_columns}
                          for n in keep}),
            "episode_seeds": [r["seeds"][0], r["seeds"][-1]]}
    return levels, full


def _command(task, spec, group: str, full: bool) -> str:
    ceilings = " ".join(f"--ceiling {c}" for c in spec.ceilings)
    return (f"formation-env evaluate --scenario {task.scenario_name} --task-report --policy "
            f"train/policies/{group}_seed{{0,1,2}}.zip {ceilings}" + ("" if full else " [--turbulence S] [--scenario "
            "VARIANT]") + " --out DIR")


def _write_compact(path: Path, data, overwrite: bool) -> None:
    from formation_env.io import atomic_write_text

    atomic_write_text(path, json.dumps(data, separators=(",", ":")) + "\n", overwrite=overwrite)


def write_records(task_name: str, episodes_dir, zips, *, episodes: int = 100, out_dir="train/policies",
                  overwrite: bool = False) -> list[Path]:
    """Fly ``zips`` in every setting of ``task_name``'s record spec (episodes kept in ``episodes_dir``) and write each
    seed group's records into ``out_dir`` (``formation-env publish records``); the paths written."""
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes must be an integer >= 1, got {episodes!r}")
    missing = [z for z in zips if not Path(z).is_file()]
    if missing:
        raise ValueError(f"policy file {missing[0]!r} does not exist")
    groups = sorted({Path(z).stem.rsplit("_seed", 1)[0] for z in zips})
    task, spec = record_spec(task_name)
    for scenario, sigma in spec.settings:
        fly_setting(task_name, episodes_dir, scenario, sigma, zips, episodes=episodes)
    out, written = Path(out_dir), []
    for group in groups:
        levels, full = group_levels(task_name, episodes_dir, group)
        if full is not None:
            full["command"] = _command(task, spec, group, True)
            _write_compact(out / f"{group}_evaluation.json", full, overwrite)
            written.append(out / f"{group}_evaluation.json")
        _write_compact(out / f"{group}_levels.json", {"command": _command(task, spec, group, False),
                                                      "levels": levels, "about": spec.about.format(group=group)},
                       overwrite)
        written.append(out / f"{group}_levels.json")
    return written
