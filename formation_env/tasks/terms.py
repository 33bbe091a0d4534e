"""Task terms in Python: reward terms, observation groups, termination conditions and per-episode metrics as
vectorised numpy functions of the batched simulation (every formation at once), composed after the compiled
decision step.

A term's function takes the :class:`~formation_env.sim.Simulation` after the step (its public arrays:
``sim.aircraft`` (B, V, 16), ``sim.info`` (every info quantity with the batch axis), ``sim.position_demand``,
``sim.time_s``, ...) and returns

* :class:`RewardTerm`: (B, V) or (B,) per UAV, added to the compiled reward times ``weight`` (its value is
  ``info["reward_<name>"]``, weighted);
* :class:`ObservationTerm`: (B, V, size), appended after the compiled observation (clipped to +-OBS_CLIP; in
  ``obs_mode="dict"`` a group of its own name);
* :class:`TerminationTerm`: (B,) bool, ending those formations' episodes as terminated;
* :class:`MetricTerm`: (B,) or (B, V) per decision, reduced over each episode to one column of the task's
  per-episode metrics (``reduce``: mean, min, max, sum or last; (B, V) values are averaged over the agents).

A function that keeps state between decisions (a previous value) is an object with ``__call__(sim)`` and
``reset(sim, indices)``, called after every reset of those formations. The compiled terms are untouched: a
task without Python terms flies the plain :class:`~formation_env.sim.Simulation` (:func:`task_simulation`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..rollout import Recorder, RolloutResult
from ..sim import INFO_REWARD_KEYS

__all__ = ["RewardTerm", "ObservationTerm", "TerminationTerm", "MetricTerm", "TaskTerms", "TermMetrics"]

_REDUCE = {"mean": np.mean, "min": np.min, "max": np.max, "sum": np.sum, "last": lambda x: x[-1]}


def _check_name(kind: str, name) -> None:
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"{kind}.name must be an identifier, got {name!r}")


@dataclass(frozen=True)
class RewardTerm:
    """``weight * fn(sim)`` added to each UAV's reward after the compiled step."""

    name: str
    fn: Callable
    weight: float = 1.0

    def __post_init__(self) -> None:
        _check_name("RewardTerm", self.name)
        if not np.isfinite(self.weight):
            raise ValueError(f"RewardTerm.weight must be finite, got {self.weight!r}")


@dataclass(frozen=True)
class ObservationTerm:
    """``fn(sim)`` (B, V, size) appended to every UAV's observation."""

    name: str
    fn: Callable
    size: int

    def __post_init__(self) -> None:
        _check_name("ObservationTerm", self.name)
        if isinstance(self.size, bool) or not isinstance(self.size, int) or self.size < 1:
            raise ValueError(f"ObservationTerm.size must be an integer >= 1, got {self.size!r}")


@dataclass(frozen=True)
class TerminationTerm:
    """``fn(sim)`` (B,) bool: the formations whose episodes end (terminated) at this decision."""

    name: str
    fn: Callable

    def __post_init__(self) -> None:
        _check_name("TerminationTerm", self.name)


@dataclass(frozen=True)
class MetricTerm:
    """``fn(sim)`` per decision, ``reduce``-d over each episode into the metric column ``name``."""

    name: str
    fn: Callable
    reduce: str = "mean"

    def __post_init__(self) -> None:
        _check_name("MetricTerm", self.name)
        if self.reduce not in _REDUCE:
            raise ValueError(f"MetricTerm.reduce must be one of {sorted(_REDUCE)}, got {self.reduce!r}")


@dataclass(frozen=True)
class TaskTerms:
    """A task's Python terms (each a tuple; empty: none of that kind)."""

    rewards: tuple = ()
    observations: tuple = ()
    terminations: tuple = ()
    metrics: tuple = ()

    def __post_init__(self) -> None:
        for field_name, kind in (("rewards", RewardTerm), ("observations", ObservationTerm),
                                 ("terminations", TerminationTerm), ("metrics", MetricTerm)):
            terms = tuple(getattr(self, field_name))
            object.__setattr__(self, field_name, terms)
            bad = [t for t in terms if not isinstance(t, kind)]
            if bad:
                raise ValueError(f"TaskTerms.{field_name} takes {kind.__name__}s, got {bad[0]!r}")
            names = [t.name for t in terms]
            if len(set(names)) != len(names):
                raise ValueError(f"TaskTerms.{field_name}: duplicate names {names}")
        taken = sorted(f"reward_{t.name}" for t in self.rewards if f"reward_{t.name}" in INFO_REWARD_KEYS)
        if taken:
            raise ValueError(f"TaskTerms.rewards: {taken} are the compiled reward's info keys; name the terms otherwise")

    @property
    def observation_size(self) -> int:
        return sum(t.size for t in self.observations)

    @property
    def stepped(self) -> bool:
        """Whether any term acts on the step (a task with metrics alone flies the plain Simulation)."""
        return bool(self.rewards or self.observations or self.terminations)

    def functions(self):
        """Every term's function, once each (their ``reset`` hooks are called after each reset)."""
        seen = {}
        for t in (*self.rewards, *self.observations, *self.terminations, *self.metrics):
            seen.setdefault(id(t.fn), t.fn)
        return list(seen.values())

    def episode_metrics(self) -> "TermMetrics | None":
        return TermMetrics(self.metrics) if self.metrics else None


class _MetricRecorder(Recorder):
    """Records every metric term of the formations still flown, per decision."""

    def __init__(self, metrics: tuple) -> None:
        self.metrics = metrics

    def start(self, sim, out) -> None:
        self.rows = {m.name: [] for m in self.metrics}
        for fn in {id(m.fn): m.fn for m in self.metrics}.values():
            if callable(getattr(fn, "reset", None)):
                fn.reset(sim, np.arange(sim.batch_size))
        self.agents = list(sim.agent_indices)

    def after_step(self, sim, out, actions, alive, k) -> None:
        for m in self.metrics:
            v = np.asarray(m.fn(sim), dtype=float)
            if v.ndim == 2:  # per UAV: the agents' mean
                v = v[:, self.agents].mean(axis=1)
            self.rows[m.name].append(np.where(alive, v, np.nan))


class TermMetrics:
    """The per-episode metrics of a task's :class:`MetricTerm` s: ``recorder()`` for
    :func:`formation_env.rollout.rollout`, then ``episodes(recorder, result)``: one dict per episode (its seed and
    each metric)."""

    def __init__(self, metrics: tuple) -> None:
        self.metrics = tuple(metrics)

    def recorder(self) -> Recorder:
        return _MetricRecorder(self.metrics)

    def episodes(self, recorder, result: RolloutResult, keep_series: bool = False) -> list[dict]:
        arr = {k: np.stack(v) for k, v in recorder.rows.items()}  # (T, B)
        out = []
        for i, seed in enumerate(result.seeds):
            n = int(result.decisions[i])
            row = {"seed": seed}
            for m in self.metrics:
                row[m.name] = float(_REDUCE[m.reduce](arr[m.name][:n, i])) if n else float("nan")
            out.append(row)
        return out
