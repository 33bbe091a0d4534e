"""What a task is and the registry of tasks.

A :class:`Task` is one self-contained unit: its scenario (flight path, slots, safe box), its benchmark
configuration (the observation, action interface, reward weights and training randomisation every result on
it is reported with: ``gym.make(task.gym_id)``, :func:`formation_env.parallel_env`, the vector envs and
``formation-env train`` all start from it), its evaluation protocol (held-out seeds, turbulence levels, episodes,
headline metric), where it has one its reference optimum and its metrics, the names of the baselines it is
judged against and of the safety guard its published policies fly with (the agents themselves live in the
top-level ``agents`` package: ``formation_env`` never imports it), and its version. Adding a task means adding
one unit under :mod:`formation_env.tasks` and calling :func:`register_task`; its Gymnasium id follows.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass, field

from ..scenarios import Scenario, get_scenario, register_scenario
from ..sim.config import EnvConfig, Randomisation, RewardWeights
from .terms import TaskTerms

__all__ = ["Task", "EvaluationProtocol", "RecordFile", "levels_record", "ALGORITHM_LABELS", "versus_records", "register_task", "get_task", "task_names", "TASKS", "task_options",
           "task_for_scenario", "make_config", "gym_ids", "task_learning", "TEST_SEED_BASE", "VALIDATION_SEED_BASE",
           "HEADLINE_METRICS"]

# Held-out seeds. Training episodes use the seeds ``seed + f`` (small ints) and then 32-bit draws of numpy's
# SeedSequence, so any seed >= 2**32 is provably never a training episode's seed.
VALIDATION_SEED_BASE = 10_000_000_000  # the training's validation (model selection) episodes
TEST_SEED_BASE = 20_000_000_000        # the test episodes every result is reported on

#: headline metric -> (label, higher is better): the per-episode quantities a task can be judged by
HEADLINE_METRICS = {
    "harvest_ratio": ("harvest ratio (induced-drag saving / the task's optimum)", True),
    "formation_saving": ("formation saving (every UAV's mean induced-drag saving)", True),
    "reconfig_success": ("success (in the 1-span window at the end)", True),
    "rms_slot_error_m": ("RMS slot error, m", False),
}
#: training algorithm (``formation-env train --algo``, a published policy's ``<task>_<algo>_<mode>`` name) -> label
ALGORITHM_LABELS = {"ppo": "PPO", "mappo": "MAPPO", "sac": "SAC", "td3": "TD3", "recurrent_ppo": "recurrent PPO"}


def versus_records(folder, task_name: str) -> list:
    """The task's recipe-against-PPO records in ``folder`` (``formation-env publish versus``:
    ``<task>_<algo>_setpoints_versus_ppo.json``), as (path, record) pairs in name order; a file whose record names
    another task is not the task's."""
    import json
    from pathlib import Path

    pairs = [(f, json.loads(f.read_text(encoding="utf-8")))
             for f in sorted(Path(folder).glob(f"{task_name}_*_versus_ppo.json"))]
    return [(f, r) for f, r in pairs if r.get("task") == task_name]


@dataclass(frozen=True)
class RecordFile:
    """One committed record of a task's results (``file`` in ``train/policies/``): the ``path`` of keys inside it to
    a mapping policy -> its episodes at each turbulence level of ``levels`` (m/s); a key's ``{sigma}`` is the level
    written as ``f"{sigma:g}"``. The results page and the absolute metric read a task's episodes from its records."""

    file: str
    path: tuple
    levels: tuple = (1.0,)

    def keys_at(self, sigma: float) -> tuple:
        """The path of keys to the episodes at level ``sigma``."""
        return tuple(k.format(sigma=f"{sigma:g}") if isinstance(k, str) else k for k in self.path)


def levels_record(file: str, levels: tuple, task: str | None = None, index: int = 0) -> RecordFile:
    """A record written by ``formation-env publish levels``: a one-task record (``task`` None), or record ``index``
    of ``task`` in a record of several."""
    by_level = ("by_level", "sigma_{sigma}", "episodes")
    return RecordFile(file, by_level if task is None else ("records", task, index) + by_level, levels)


@dataclass(frozen=True)
class EvaluationProtocol:
    """How a task's results are made: ``episodes`` held-out episodes per turbulence level (``levels``, the
    frozen von Karman field's sigma in m/s) on the seeds ``seed_base``, ``seed_base + 1``, ...; ``metric`` the
    headline per-episode metric (:data:`HEADLINE_METRICS`), reported at ``headline_level``. ``preset``: the
    EnvConfig options of the test episodes where they are not the generic test distribution (the benchmark
    task's reward, its randomisation at the level, the saving computed): a task whose episodes draw more than
    the turbulence (wake_surfing's crosswind and leader manoeuvre). None: the generic distribution, the
    scenario with the task's ``test_randomisation``. ``records``: the committed records its results page reads
    (:class:`RecordFile`, in the order a later one's runs replace an earlier one's of the same name);
    ``absolute``: whether its learned methods are also flown on the absolute metric's 1,000 further episodes
    (``formation-env results --absolute``). ``ppo_record_score``: the task's committed PPO evaluation at sigma 1
    (``<task>_ppo_setpoints_evaluation.json``: ``formation-env publish committed``, or the task's own evaluation)
    and the per-episode score it enters the table across tasks of ``formation-env publish recompute`` with (a key
    of ``train.evaluation.aggregates.SCORES``); None: the task has no such record."""

    levels: tuple = (0.0, 1.0, 1.5)
    headline_level: float = 1.0
    episodes: int = 100
    seed_base: int = TEST_SEED_BASE
    metric: str = "rms_slot_error_m"
    preset: dict | None = None
    records: tuple = ()
    absolute: bool = False
    ppo_record_score: str | None = None

    def __post_init__(self) -> None:
        if self.metric not in HEADLINE_METRICS:
            raise ValueError(f"EvaluationProtocol.metric must be one of {sorted(HEADLINE_METRICS)}, got {self.metric!r}")
        if self.headline_level not in self.levels:
            raise ValueError(f"EvaluationProtocol.headline_level {self.headline_level!r} is not one of its levels "
                             f"{self.levels!r}")
        if not 1 <= self.episodes <= 100_000:
            raise ValueError(f"EvaluationProtocol.episodes must be in [1, 100000], got {self.episodes!r}")
        if self.ppo_record_score is not None and not (isinstance(self.ppo_record_score, str) and self.ppo_record_score):
            raise ValueError(f"EvaluationProtocol.ppo_record_score must be a score name or None, got "
                             f"{self.ppo_record_score!r}")
        for r in self.records:
            if not isinstance(r, RecordFile):
                raise ValueError(f"EvaluationProtocol.records must hold RecordFile objects, got {r!r}")
        if not 2**32 <= self.seed_base <= 2**62:
            raise ValueError(f"EvaluationProtocol.seed_base must be in [2**32, 2**62] (never a training seed), "
                             f"got {self.seed_base!r}")

    @property
    def higher_is_better(self) -> bool:
        return HEADLINE_METRICS[self.metric][1]


_ID = re.compile(r"^[A-Za-z0-9_]+/[A-Za-z0-9]+$")


@dataclass(frozen=True)
class Task:
    """One task. ``scenario``: a registered scenario name or a Scenario (registered by :func:`register_task`);
    ``options``: the EnvConfig options the task is posed with (``parallel_env``, the Gymnasium id and
    ``make_config`` start from them; given options override them); ``gym_id``/``gym_learner``: its
    single-agent Gymnasium id and learner index; ``baselines``: names of the agents it is judged against;
    ``reference``: the reference optimum (an object with ``optimum_saving()``, e.g. a module; None where the task
    has none); ``metrics``: the task's own per-episode metrics, an object with ``recorder()`` (a
    :class:`formation_env.rollout.Recorder`) and ``episodes(recorder, result, keep_series=False)`` (one dict per
    episode; None: the :class:`~formation_env.tasks.terms.MetricTerm` s of ``terms``, if any);
    ``terms``: the task's Python reward, observation, termination and metric terms
    (:class:`~formation_env.tasks.terms.TaskTerms`), composed after the compiled step; ``evaluator``: the task's
    own evaluation hooks (:class:`~formation_env.tasks.evaluation.TaskEvaluation`; None: the generic evaluation);
    ``test_randomisation``: :class:`~formation_env.sim.config.Randomisation` fields the held-out test set (and
    the training's validation) draws besides the turbulence level, so that even calm-air episodes differ;
    ``learning``: the UAVs that are agents when the task is trained and evaluated (an EnvConfig ``learning``:
    "followers", vehicle 0 flying the thesis PID on its track, or "all" where vehicle 0 must be flown like the
    others, e.g. in another UAV's wake).

    ``options`` is the task's benchmark configuration: the EnvConfig options (action interface, reward
    weights, the training randomisation, the saving computed) that every result on the task is trained with
    and that ``gym.make(gym_id)`` gives (:meth:`default_config`). ``gym_name`` is the id without its version
    (``formation_env/CloseFormation``); ``gym_id`` adds ``-v{version}``. ``version`` changes whenever the task's
    behaviour does (tests/tasks/test_task_versions.py holds a fingerprint of each version). ``guard``: the name
    of the safety filter (``agents``) the task's published policies fly with, None where they fly without one;
    ``guard_options`` its gains. ``evaluation``: the protocol its results are made with."""

    name: str
    scenario: object
    gym_name: str | None = None
    gym_learner: int = 1
    options: dict = field(default_factory=dict)
    baselines: tuple = ("pid", "pid_formation")
    reference: object = None
    metrics: object = None
    description: str = ""
    test_randomisation: dict = field(default_factory=dict)
    learning: str = "followers"
    version: int = 1
    guard: str | None = None
    guard_options: dict = field(default_factory=dict)
    evaluation: EvaluationProtocol = field(default_factory=EvaluationProtocol)
    terms: TaskTerms | None = None
    evaluator: object = None

    def __post_init__(self) -> None:
        for name in ("reference", "metrics", "evaluator"):
            if isinstance(getattr(self, name), str):
                raise ValueError(f"Task.{name} must be an object (a module or instance), not an import string: "
                                 f"got {getattr(self, name)!r}")
        if self.terms is not None and not isinstance(self.terms, TaskTerms):
            raise ValueError(f"Task.terms must be a TaskTerms or None, got {self.terms!r}")
        if self.metrics is None and self.terms is not None and self.terms.metrics:
            object.__setattr__(self, "metrics", self.terms.episode_metrics())
        if self.metrics is not None and not all(callable(getattr(self.metrics, m, None))
                                                for m in ("recorder", "episodes")):
            raise ValueError(f"Task.metrics must have recorder() and episodes(); got {self.metrics!r}")
        if self.learning not in ("followers", "all"):
            raise ValueError(f"Task.learning must be 'followers' or 'all', got {self.learning!r}")
        if isinstance(self.version, bool) or not isinstance(self.version, int) or self.version < 0:
            raise ValueError(f"Task.version must be an integer >= 0, got {self.version!r}")
        if self.gym_name is not None and not _ID.match(self.gym_name):
            raise ValueError(f"Task.gym_name must look like 'namespace/Name' (no version: Task.version adds it), "
                             f"got {self.gym_name!r}")
        if self.guard not in (None, "separation_guard"):
            raise ValueError(f"Task.guard must be None or 'separation_guard', got {self.guard!r}")
        if not isinstance(self.evaluation, EvaluationProtocol):
            raise ValueError(f"Task.evaluation must be an EvaluationProtocol, got {self.evaluation!r}")
        bad = sorted(set(self.options) - set(EnvConfig.__dataclass_fields__) - {"scenario"})
        if bad or "scenario" in self.options:
            raise ValueError(f"Task.options: not EnvConfig options {bad or ['scenario']}")

    @property
    def gym_id(self) -> str | None:
        """The Gymnasium id of this version of the task (None: a task without one)."""
        return None if self.gym_name is None else f"{self.gym_name}-v{self.version}"

    def default_config(self, **overrides) -> EnvConfig:
        """The task's benchmark EnvConfig (its scenario and :attr:`options`, who learns as :attr:`learning`), with
        ``overrides`` (EnvConfig options) replacing any of them: the environment every result on the task is
        trained with."""
        opts = {"learning": self.learning, **self.options, **overrides}
        return make_config(scenario=self.scenario_name, **opts)

    def env_kwargs(self) -> dict:
        """:attr:`options` as plain data in the hyperparameter files' ``env_kwargs`` form (``reward`` and
        ``randomisation`` as mappings of the fields that differ from their defaults; ``action_mode`` left out, a
        run's own setting): what a training run's sidecar records."""
        out = {}
        for k, v in self.options.items():
            if k == "action_mode":
                continue
            if isinstance(v, (RewardWeights, Randomisation)):
                default = type(v)()
                v = {f.name: getattr(v, f.name) for f in dataclasses.fields(v)
                     if getattr(v, f.name) != getattr(default, f.name)}
            out[k] = v
        return out

    @property
    def action_mode(self) -> str:
        """The action interface of the benchmark (its ``options``' ``action_mode``, else EnvConfig's default)."""
        return self.options.get("action_mode", EnvConfig.__dataclass_fields__["action_mode"].default)

    @property
    def scenario_name(self) -> str:
        return self.scenario.name if isinstance(self.scenario, Scenario) else str(self.scenario)

    def get_scenario(self) -> Scenario:
        return get_scenario(self.scenario_name)

    def optimum_saving(self) -> float | None:
        """The follower's induced-drag saving at the reference optimum of the task's allowed region in calm
        air (the denominator of the evaluations' ``harvest_ratio``): the reference's ``optimum_saving()``;
        None for a task without a reference or whose reference has no such optimum."""
        fn = getattr(self.reference, "optimum_saving", None)
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
    """Gymnasium id (with its version) -> (scenario, learner index) of every registered task that has one."""
    return {t.gym_id: (t.scenario_name, t.gym_learner) for t in TASKS.values() if t.gym_name}


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
