"""The policy interface of the evaluation: :class:`EvalPolicy`, an ``act`` function and its action mode.

Its own module so that the policy loaders (:mod:`train.policy_loader`, :mod:`train.rllib_policy`) and
the evaluation (:mod:`train.evaluation.evaluate`) share it without importing one another."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from formation_env.sim.layout import ObservationLayout

__all__ = ["EvalPolicy"]


@dataclass
class EvalPolicy:
    """A policy to evaluate: ``act(obs (N, D) float32) -> actions (N, 4)`` in ``action_mode``."""

    name: str
    action_mode: str
    act: Callable[[np.ndarray], np.ndarray]
    control_hz: float = 10.0
    path: str | None = None
    reset: Callable[[int], None] | None = None
    """Called once by :func:`run_episodes` with the number of rows (formations x learning UAVs)
    before the first decision (stateful policies: a PID's integrators)."""
    observation: ObservationLayout = field(default_factory=ObservationLayout)
    """The observation layout it was trained on (its sidecar's): flown with its optional groups. The default: no
    optional group, any formation (a classical agent, or a policy recorded before layouts were)."""
