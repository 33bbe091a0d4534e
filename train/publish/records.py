"""The committed records of a task with its own evaluation (``train/policies/<group>_levels.json`` and the task
group's ``<group>_evaluation.json``): every controller flown once per setting of the task's
:class:`~formation_env.tasks.evaluation.RecordSpec` on the default held-out seeds, its episodes saved as
``EPISODES_DIR/<scenario>_sigma_<s>/<name>.json``, then each policy group's report
(:func:`train.evaluation.task_eval.task_report`, what ``formation-env evaluate --task-report`` runs after flying)
from the same episodes, so that the baselines and ceilings are flown once for every group.

    python -m train.publish.records TASK EPISODES_DIR ZIP [ZIP ...] [--out-dir train/policies] [--overwrite]

Zips are named ``<group>_seed<k>.zip``; flights already saved in EPISODES_DIR are not flown again.
"""

from __future__ import annotations

import argparse
import json
import sys
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


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m train.publish.records", description=__doc__.split("\n\n")[0])
    p.add_argument("task")
    p.add_argument("episodes_dir")
    p.add_argument("zips", nargs="+")
    p.add_argument("--episodes", type=int, default=100)
    p.add_argument("--out-dir", default="train/policies")
    p.add_argument("--overwrite", action="store_true")
    a = p.parse_args(argv)
    if a.episodes < 1:
        print(f"error: --episodes must be >= 1, got {a.episodes}", file=sys.stderr)
        return 2
    missing = [z for z in a.zips if not Path(z).is_file()]
    if missing:
        print(f"error: policy file {missing[0]!r} does not exist", file=sys.stderr)
        return 2
    groups = sorted({Path(z).stem.rsplit("_seed", 1)[0] for z in a.zips})
    try:
        task, spec = record_spec(a.task)
        for scenario, sigma in spec.settings:
            fly_setting(a.task, a.episodes_dir, scenario, sigma, a.zips, episodes=a.episodes)
        out = Path(a.out_dir)
        for group in groups:
            levels, full = group_levels(a.task, a.episodes_dir, group)
            if full is not None:
                full["command"] = _command(task, spec, group, True)
                _write_compact(out / f"{group}_evaluation.json", full, a.overwrite)
            _write_compact(out / f"{group}_levels.json", {"command": _command(task, spec, group, False),
                                                          "levels": levels, "about": spec.about.format(group=group)},
                           a.overwrite)
            print(f"wrote {group}_levels.json")
    except (ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
