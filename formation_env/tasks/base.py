"""What a task is and the registry of tasks.

A :class:`Task` is one self-contained unit: its scenario (flight path, slots, safe box), the preset that
poses it for learning (reward weights, action interface, randomisation), where it has one its reference
optimum and its metrics, and the names of the baselines it is judged against (the agents themselves live in
the top-level ``agents`` package: ``formation_env`` never imports it). Adding a task means adding one unit
under :mod:`formation_env.tasks` and calling :func:`register_task`; its Gymnasium id follows.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass, field

from ..scenarios import Scenario, get_scenario, register_scenario
from ..sim.config import EnvConfig

__all__ = ["Task", "register_task", "get_task", "task_names", "TASKS", "task_options", "task_for_scenario", "make_config",
           "gym_ids", "task_learning"]


@dataclass(frozen=True)
class Task:
    """One task. ``scenario``: a registered scenario name or a Scenario (registered by :func:`register_task`);
    ``options``: the EnvConfig options the task is posed with (``parallel_env``, the Gymnasium id and
    ``make_config`` start from them; given options override them); ``gym_id``/``gym_learner``: its
    single-agent Gymnasium id and learner index; ``baselines``: names of the agents it is judged against;
    ``reference``: the reference optimum (a module or object, None where the task has none); ``metrics``:
    a callable making the task's own per-episode metrics (None: the generic evaluation table);
    ``test_randomisation``: :class:`~formation_env.sim.config.Randomisation` fields the held-out test set (and
    the training's validation) draws besides the turbulence level, so that even calm-air episodes differ;
    ``learning``: the UAVs that are agents when the task is trained and evaluated (an EnvConfig ``learning``:
    "followers", vehicle 0 flying the thesis PID on its track, or "all" where vehicle 0 must be flown like the
    others, e.g. in another UAV's wake)."""

    name: str
    scenario: object
    gym_id: str | None = None
    gym_learner: int = 1
    options: dict = field(default_factory=dict)
    baselines: tuple = ("pid", "pid_formation")
    reference: object = None
    metrics: Callable | None = None
    description: str = ""
    test_randomisation: dict = field(default_factory=dict)
    learning: str = "followers"

    def __post_init__(self) -> None:
        if self.learning not in ("followers", "all"):
            raise ValueError(f"Task.learning must be 'followers' or 'all', got {self.learning!r}")

    @property
    def scenario_name(self) -> str:
        return self.scenario.name if isinstance(self.scenario, Scenario) else str(self.scenario)

    def get_scenario(self) -> Scenario:
        return get_scenario(self.scenario_name)

    def optimum_saving(self) -> float | None:
        """The follower's induced-drag saving at the reference optimum of the task's allowed region in calm
        air (the denominator of the evaluations' ``harvest_ratio``): the reference's ``optimum_saving()``;
        None for a task without a reference or whose reference has no such optimum."""
        if self.reference is None:
            return None
        ref = importlib.import_module(self.reference) if isinstance(self.reference, str) else self.reference
        fn = getattr(ref, "optimum_saving", None)
        return None if fn is None else float(fn())


TASKS: dict[str, Task] = {}


def register_task(task: Task) -> Task:
    """Register ``task`` (and its scenario, when it brings its own)."""
    if not isinstance(task, Task):
        raise ValueError(f"register_task: expected a Task, got {type(task).__name__}")
    if task.name in TASKS:
        raise ValueError(f"register_task: a task named {task.name!r} is already registered")
    if isinstance(task.scenario, Scenario):
        register_scenario(task.scenario)
    TASKS[task.name] = task
    return task


def task_names() -> list[str]:
    return list(TASKS)


def get_task(name: str) -> Task:
    if name not in TASKS:
        raise ValueError(f"unknown task {name!r}; available: {task_names()}")
    return TASKS[name]


def task_options(scenario) -> dict:
    """The preset options of the task flown on ``scenario`` (a name; {} for a Scenario object or a
    scenario no task poses differently from the EnvConfig defaults)."""
    if not isinstance(scenario, str):
        return {}
    for t in TASKS.values():
        if t.scenario_name == scenario:
            return dict(t.options)
    return {}


def task_for_scenario(scenario) -> Task | None:
    """The registered task flown on ``scenario`` (a name), None if no task poses it."""
    for t in TASKS.values():
        if isinstance(scenario, str) and t.scenario_name == scenario:
            return t
    return None


def task_learning(scenario) -> str:
    """Who learns when the task flown on ``scenario`` (a name) is trained or evaluated: its
    :attr:`Task.learning`; "followers" for a scenario no task poses."""
    t = task_for_scenario(scenario)
    return t.learning if t is not None else "followers"


def gym_ids() -> dict[str, tuple[str, int]]:
    """Gymnasium id -> (scenario, learner index) of every registered task that has one."""
    return {t.gym_id: (t.scenario_name, t.gym_learner) for t in TASKS.values() if t.gym_id}


def make_config(config: EnvConfig | None = None, **options) -> EnvConfig:
    """An EnvConfig from keyword options, starting from the scenario's task preset.

    An unknown option raises ``TypeError`` naming it (as Python does for an unexpected keyword argument;
    wrappers such as TorchRL's ``GymEnv`` probe constructors with optional keywords and expect
    ``TypeError``); a bad value of a known option raises ``ValueError`` (from :class:`EnvConfig`)."""
    valid = set(EnvConfig.__dataclass_fields__)
    unknown = sorted(set(options) - valid)
    if unknown:
        more = f" (and {unknown[1:]})" if len(unknown) > 1 else ""
        raise TypeError(f"unknown option: got an unexpected keyword argument {unknown[0]!r}{more}; "
                        f"valid options: {sorted(valid)}")
    if config is not None and not isinstance(config, EnvConfig):
        raise ValueError(f"config must be an EnvConfig, got {type(config).__name__}")
    if config is None:
        return EnvConfig(**{**task_options(options.get("scenario", "formation_keeping")), **options})
    if options:
        raise ValueError("give either config or keyword options, not both")
    return config
