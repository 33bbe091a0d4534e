"""A task's simulation: the compiled :class:`~formation_env.sim.Simulation` with the task's Python terms
(:mod:`formation_env.tasks.terms`) composed after the decision step where it has any. Kept apart from the term
types so that a Task (:mod:`formation_env.tasks.base`) can hold terms without the terms knowing the registry."""

from __future__ import annotations

from .base import task_for_scenario
from .terms import TaskTerms

__all__ = ["task_terms", "task_simulation"]


def task_terms(scenario) -> TaskTerms | None:
    """The Python terms of the task flown on ``scenario`` (a name or Scenario), None where it has none."""
    task = task_for_scenario(getattr(scenario, "name", scenario))
    return None if task is None else task.terms


def task_simulation(config, batch_size: int = 1, **kwargs):
    """The Simulation of ``config``: with the Python terms of its scenario's task composed after the compiled step
    (:class:`~formation_env.sim.composed.ComposedSimulation`), or the plain Simulation for a task without any."""
    from ..sim import Simulation

    terms = task_terms(config.scenario)
    if terms is None or not terms.stepped:
        return Simulation(config, batch_size, **kwargs)
    from ..sim.composed import ComposedSimulation

    return ComposedSimulation(config, batch_size, terms=terms, **kwargs)
