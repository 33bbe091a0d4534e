"""The interface of a task's own evaluation (:attr:`formation_env.tasks.Task.evaluator`): the hooks the generic
driver (``train.evaluation.task_eval``, run by ``formation-env evaluate --task-report``) and the records writer
(``train.publish.records``) call, so that no task name is written outside the task's unit and the registry.

A task whose results are the generic table (:mod:`train.evaluation.evaluate`) needs none of this. One that is
judged differently (wake_surfing: each episode against its own reference optimum, baselines and oracle ceilings
of its own) subclasses :class:`TaskEvaluation`. ``formation_env`` never imports ``agents`` or ``train``: what the
hooks need from them is passed in, the agents' classes as an :class:`AgentKit` and the statistics as the
driver's statistics module (:class:`Statistics`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

__all__ = ["AgentKit", "Statistics", "RecordSpec", "TaskEvaluation", "fly_task", "longest_run"]


@dataclass(frozen=True)
class AgentKit:
    """The controller classes of the top-level ``agents`` package a task's baselines and ceilings are built from
    (the driver fills it in)."""

    pid_formation: type
    extremum_seeking: type
    extremum_seeking_gains: type
    station_keeper: type
    station_keeper_gains: type


class Statistics(Protocol):
    """What the hooks use of the driver's statistics (``train.evaluation.stats``)."""

    N_BOOT: int

    def bootstrap_ci(self, values, statistic: str = "mean", *, n_boot: int = ..., seed: int = ...): ...

    def paired_comparison(self, baseline, candidate, **kwargs) -> dict: ...

    def wilson_interval(self, k: int, n: int): ...


@dataclass(frozen=True)
class RecordSpec:
    """How the records writer makes a task's committed records: every controller flown once per setting
    (``settings``: (scenario, turbulence sigma), the task's level first) on the held-out seeds; ``ceilings`` the
    ceilings flown beside the baselines; ``episode_columns`` the per-episode columns a levels record keeps;
    ``full``: (policy group, level key) kept in full in the group's evaluation record."""

    settings: tuple
    ceilings: tuple
    episode_columns: tuple
    full: tuple
    about: str = ""


class TaskEvaluation:
    """A task's own evaluation. Subclasses set the attributes and override the hooks they need.

    ``scenarios``: the scenarios it evaluates (the task's and its variants'); ``baseline_names``: the baselines
    every policy is compared with, in order; ``default_ceilings``: ceiling specs flown unless others are asked for;
    ``records``: its :class:`RecordSpec` (None: no committed records)."""

    scenarios: tuple = ()
    baseline_names: tuple = ()
    default_ceilings: tuple = ()
    records: RecordSpec | None = None

    def baselines(self, kit: AgentKit) -> list:
        """The baselines as :class:`formation_env.rollout.Policy` objects with a ``name``, in ``baseline_names``
        order."""
        raise NotImplementedError

    def ceiling(self, kit: AgentKit, spec: str):
        """The ceiling named by ``spec`` (e.g. ``oracle_keeper:0.05``): a policy told what no controller knows,
        reported beside the controllers and compared with none. A bad spec is a ValueError."""
        raise ValueError(f"{type(self).__name__} has no ceilings; got {spec!r}")

    def summarise(self, episodes: list[dict], stats: Statistics, *, n_boot: int, seed: int = 0) -> dict:
        """One controller's summary over its episodes."""
        raise NotImplementedError

    def comparisons(self, episodes_by: dict, names: Sequence[str], stats: Statistics, *, n_boot: int,
                    seed: int = 0) -> dict:
        """Paired by episode: each policy in ``names`` against the baselines (name -> baseline -> comparison)."""
        raise NotImplementedError

    def spread_metrics(self) -> tuple:
        """The summary metrics whose spread over the training seeds the report gives."""
        return ()

    def markdown(self, report: dict, aggregates_markdown: str = "") -> str:
        """The report's tables."""
        raise NotImplementedError

    def heading(self, report: dict) -> str:
        """What ``results.md`` starts with (the episodes' distribution, how the statistics were made)."""
        return ""

    def tune(self, kit: AgentKit, fly: Callable, log: Callable = print) -> list[dict]:
        """A sweep of a baseline's gains on training seeds (None where the task has none), best first; ``fly``:
        :func:`fly_task` bound to the task."""
        raise ValueError(f"{type(self).__name__} has no tuning sweep")

    def figure(self, path, policy, kit: AgentKit, fly: Callable, *, overwrite: bool = False):
        """The task's figure with ``policy`` flying (a Policy with a ``name``); the path written."""
        raise ValueError(f"{type(self).__name__} has no figure")


def fly_task(task, policy, seeds: Sequence[int], config, *, keep_series: bool = False,
             options: dict | None = None) -> list[dict]:
    """Fly ``policy`` on the episodes ``seeds`` of ``config`` (one batch) and measure each with the task's own
    metrics (:attr:`formation_env.tasks.Task.metrics`); ``options``: reset options (e.g. a steady wind)."""
    from ..rollout import rollout
    from .compose import task_simulation

    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("seeds must not be empty")
    if task.metrics is None:
        raise ValueError(f"task {task.name!r} has no metrics of its own")
    sim = task_simulation(config, batch_size=len(seeds))
    rec = task.metrics.recorder()
    res = rollout(sim, policy, seeds, recorders=[rec], options=options)
    return task.metrics.episodes(rec, res, keep_series=keep_series)


def longest_run(flags) -> int:
    """Length of the longest run of True in a 1-D bool array."""
    best = run = 0
    for f in flags:
        run = run + 1 if f else 0
        best = max(best, run)
    return best
