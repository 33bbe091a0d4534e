"""The generic driver of a task's own evaluation (:attr:`formation_env.tasks.Task.evaluator`, the hooks of
:class:`formation_env.tasks.evaluation.TaskEvaluation`): every controller (the task's baselines, the policies, the
ceilings asked for) flies the same held-out episodes on the batched rollout, measured by the task's own metrics;
the task's hooks summarise and compare them with this package's statistics (:mod:`train.evaluation.stats`); the
rliable aggregates (:mod:`train.evaluation.aggregates`) and marl-eval export are added here.

``formation-env evaluate --scenario S --task-report --policy ZIP [...] --out DIR`` (a new directory) writes
``results.json``, ``results.md``, ``marl_eval.json`` and ``performance_profile.png`` (with several seeds);
``--figure PATH`` the task's figure with the first policy; ``--tune`` runs the task's tuning sweep instead.
"""

from __future__ import annotations

import dataclasses
import json
import time
from collections.abc import Sequence
from functools import partial
from pathlib import Path

from ..config import TEST_SEED_BASE
from . import stats
from .aggregates import aggregates_table, evaluation_aggregates, plot_profiles, profile_panels
from .comparisons import seed_groups
from .marl_eval import marl_eval_data, training_steps, write_marl_eval

__all__ = ["agent_kit", "task_of", "policy_from_zip", "fly", "evaluate_task", "task_report", "task_groups",
           "write_outputs", "rounded"]


def agent_kit():
    """The agents the tasks' baselines are built from (:class:`formation_env.tasks.evaluation.AgentKit`)."""
    from agents.extremum_seeking import ExtremumSeeking, ExtremumSeekingGains
    from agents.pid_formation import PIDFormation
    from agents.station_keeper import StationKeeper, StationKeeperGains
    from formation_env.tasks.evaluation import AgentKit

    return AgentKit(pid_formation=PIDFormation, extremum_seeking=ExtremumSeeking,
                    extremum_seeking_gains=ExtremumSeekingGains, station_keeper=StationKeeper,
                    station_keeper_gains=StationKeeperGains)


def task_of(scenario: str):
    """The task flown on ``scenario`` that has its own evaluation (a ValueError naming the ones that do otherwise)."""
    from formation_env.tasks import TASKS, task_for_scenario

    t = task_for_scenario(scenario)
    if t is None or t.evaluator is None or scenario not in t.evaluator.scenarios:
        own = sorted(s for task in TASKS.values() if task.evaluator is not None for s in task.evaluator.scenarios)
        raise ValueError(f"scenario must be one of {own} (a task with its own evaluation), got {scenario!r}")
    return t


def policy_from_zip(path: str, name: str | None = None):
    """An SB3 PPO zip as a rollout policy named after its file (nothing in the zip unpickled)."""
    import zipfile

    from formation_env.rollout import FunctionPolicy

    from .safe_zip import load_sb3_model

    try:
        model = load_sb3_model(path, "ppo")
    except zipfile.BadZipFile as exc:
        raise ValueError(f"{path}: not a zip file ({exc})") from None
    return FunctionPolicy(lambda obs: model.predict(obs, deterministic=True)[0], name=name or Path(path).stem)


def fly(scenario: str, policy, seeds: Sequence[int], *, config=None, keep_series: bool = False,
        options: dict | None = None, overrides: dict | None = None) -> list[dict]:
    """Fly ``policy`` on the held-out episodes ``seeds`` of ``scenario``'s task (its test distribution:
    :func:`train.evaluation.episodes.eval_env_config`, or ``config``; ``overrides``: EnvConfig fields replaced) and
    measure each with the task's metrics; ``options``: reset options (a steady wind)."""
    from formation_env.tasks.evaluation import fly_task

    from .episodes import eval_env_config

    cfg = config if config is not None else eval_env_config(scenario, "setpoints")
    if overrides:
        cfg = dataclasses.replace(cfg, **overrides)
    return fly_task(task_of(scenario), policy, seeds, cfg, keep_series=keep_series, options=options)


def evaluate_task(policies, *, scenario: str, episodes: int = 100, seeds=None, ceilings=None,
                  turbulence_sigma_mps: float | None = None, n_boot: int = stats.N_BOOT, log=print, kit=None) -> dict:
    """Every policy (SB3 zips), the task's baselines and ``ceilings`` (the task's ceiling specs; None: its default
    ones) on the same held-out episodes (``turbulence_sigma_mps`` None: the task's level); the report."""
    from .episodes import eval_env_config

    task = task_of(scenario)
    ev, kit = task.evaluator, kit or agent_kit()
    config = eval_env_config(scenario, "setpoints", turbulence_sigma_mps=turbulence_sigma_mps)
    seeds = list(seeds) if seeds is not None else [TEST_SEED_BASE + i for i in range(episodes)]
    controllers = ev.baselines(kit)
    names = []
    for p in policies:
        c = policy_from_zip(str(p))
        if c.name in names or c.name in ev.baseline_names:
            raise ValueError(f"two policies named {c.name!r}")
        names.append(c.name)
        controllers.append(c)
    n_base = len(controllers) - len(names)
    controllers += [ev.ceiling(kit, spec) for spec in (ev.default_ceilings if ceilings is None else ceilings)]
    episodes_by = {}
    for c in controllers:
        t0 = time.perf_counter()
        episodes_by[c.name] = fly(scenario, c, seeds, config=config)
        s = ev.summarise(episodes_by[c.name], stats, n_boot=n_boot)
        head = [f"{k} {v:.4g}" for k, v in s.items() if isinstance(v, float)][:4]
        log(f"{c.name}: " + ", ".join(head) + f" ({time.perf_counter() - t0:.0f} s)")
    specs = {c.name: str(p) for c, p in zip(controllers[n_base:], policies)}
    return task_report(task, episodes_by, names, scenario=scenario, seeds=seeds, randomisation=config.randomisation,
                       policy_specs=specs, n_boot=n_boot)


def task_groups(names: list[str]) -> dict[str, list[str]]:
    """The policies as seed groups: ``<name>_seed<k>`` groups, else all of them as ``policy_seeds`` (two or more)."""
    groups = seed_groups(names)
    grouped = {n for m in groups.values() for n in m}
    rest = [n for n in names if n not in grouped]
    if len(rest) >= 2:
        groups["policy_seeds"] = rest
    return groups


def task_report(task, episodes_by: dict, names, *, scenario: str, seeds, randomisation, policy_specs=None,
                n_boot: int = stats.N_BOOT) -> dict:
    """The report from the episodes every controller flew on ``seeds`` (``episodes_by``: name -> episodes; the
    baselines under their names, the policies under ``names``, any other entry a ceiling, summarised but compared
    with none)."""
    ev = task.evaluator
    seeds = [int(x) for x in seeds]
    for n, e in episodes_by.items():
        if [int(x["seed"]) for x in e] != seeds:
            raise ValueError(f"task_report: {n!r} flew other episodes than the seeds given")
    report = {"scenario": scenario, "seeds": seeds, "turbulence_sigma_mps": randomisation.turbulence_sigma_mps,
              "randomisation": dataclasses.asdict(randomisation),
              "controllers": {n: {"summary": ev.summarise(e, stats, n_boot=n_boot), "episodes": e}
                              for n, e in episodes_by.items()}}
    comps = ev.comparisons(episodes_by, names, stats, n_boot=n_boot)
    if len(names) >= 2:
        import numpy as np

        report["seed_spread"] = {
            k: {"mean": float(np.mean(v)), "std": float(np.std(v, ddof=1)), "min": float(np.min(v)),
                "max": float(np.max(v))}
            for k, v in {m: [report["controllers"][n]["summary"][m] for n in names] for m in ev.spread_metrics()}.items()}
    report["comparisons"] = comps
    report["policy_specs"] = dict(policy_specs or {})
    report["groups"] = task_groups(names)
    report["aggregates"] = evaluation_aggregates(episodes_by, report["groups"], list(ev.baseline_names), n_boot=n_boot)
    report["markdown"] = ev.markdown(report, aggregates_table(report["aggregates"] or {}))
    return report


def write_outputs(out: Path, task, report: dict, *, overwrite: bool = False) -> list[Path]:
    """With several policy seeds: ``marl_eval.json`` (every controller's episodes in marl-eval's format) and
    ``performance_profile.png`` (the rliable profiles)."""
    if not report.get("aggregates"):
        return []
    eps = {n: r["episodes"] for n, r in report["controllers"].items()}
    specs = report.get("policy_specs", {})
    data = marl_eval_data(task.name, eps, report["groups"], list(task.evaluator.baseline_names),
                          step_counts={n: training_steps(p) for n, p in specs.items()})
    return [write_marl_eval(out / "marl_eval.json", data, overwrite=overwrite),
            plot_profiles(out / "performance_profile.png", profile_panels(report["aggregates"]), overwrite=overwrite,
                          title=f"{task.name}: {len(report['seeds'])} held-out episodes")]


def rounded(x, digits: int = 5):
    """Floats rounded to ``digits`` decimals throughout (the committed JSON stays small)."""
    if isinstance(x, float):
        return round(x, digits)
    if isinstance(x, dict):
        return {k: rounded(v, digits) for k, v in x.items()}
    if isinstance(x, list):
        return [rounded(v, digits) for v in x]
    return x


def run(policies, *, scenario: str, episodes: int, seeds=None, turbulence_sigma_mps=None, ceilings=None,
        out=None, overwrite: bool = False, figure=None, tune: bool = False, log=print) -> int:
    """What ``formation-env evaluate --task-report`` runs (arguments checked by the CLI)."""
    from formation_env.io import atomic_write_json, atomic_write_text, prepare_output_dir

    task = task_of(scenario)
    for spec in ceilings or ():  # a bad ceiling fails before anything is flown
        task.evaluator.ceiling(agent_kit(), spec)
    if tune:
        rows = task.evaluator.tune(agent_kit(), partial(fly, scenario), log=log)
        log(json.dumps(rows[:5], indent=1))
        return 0
    out = prepare_output_dir(out, overwrite=overwrite) if out else None
    report = evaluate_task(policies, scenario=scenario, episodes=episodes, seeds=seeds, ceilings=ceilings,
                           turbulence_sigma_mps=turbulence_sigma_mps, log=log)
    if out is not None:
        atomic_write_json(out / "results.json", rounded(json.loads(json.dumps(report, default=float))),
                          overwrite=overwrite)
        atomic_write_text(out / "results.md", task.evaluator.heading(report) + report["markdown"], overwrite=overwrite)
        write_outputs(out, task, report, overwrite=overwrite)
    log(report["markdown"])
    if figure and policies:
        log(str(task.evaluator.figure(figure, policy_from_zip(str(policies[0]), "policy"), agent_kit(),
                                      partial(fly, scenario), overwrite=overwrite)))
    return 0
