"""What both training backends (SB3: :mod:`train.sb3`, RLlib: :mod:`train.rllib`) and the evaluation
share: the action modes, the held-out seed bases, the hyperparameter files' directory
(``train/hyperparams/``), YAML loading and merging, and the EnvConfig built from a hyperparameter
file's ``env_kwargs``. The SB3 run configuration is :mod:`train.sb3.config`, the RLlib one
:mod:`train.rllib.config`.
"""

from __future__ import annotations

import copy
from pathlib import Path

__all__ = ["ACTION_MODES", "ENV_KEYS", "HYPERPARAMS_DIR", "load_yaml", "merge_config", "config_section",
           "task_env_kwargs", "with_task_env", "env_departures", "task_stamp", "default_action_mode",
           "env_config_for", "VALIDATION_SEED_BASE", "TEST_SEED_BASE", "MIN_VALIDATION_EPISODES"]

ACTION_MODES = ("surfaces", "residual", "setpoints")
HYPERPARAMS_DIR = Path(__file__).resolve().parent / "hyperparams"

# Held-out seeds (the tasks' own: formation_env.tasks): training episodes use the seeds ``seed + f`` (small ints)
# and then 32-bit draws of numpy's SeedSequence, so any seed >= 2**32 is provably never a training episode's seed.
from formation_env.tasks.base import TEST_SEED_BASE, VALIDATION_SEED_BASE  # noqa: E402
# Validation episodes per evaluation recommended for model selection (the default; fewer are allowed,
# for tests, with a note in the log).
MIN_VALIDATION_EPISODES = 32

# The EnvConfig options a hyperparameter file's ``env_kwargs`` may set (both backends): these, and every optional
# observation group's switch (formation_env.sim.layout.OPTIONS, so a new group needs no entry here).
from formation_env.sim.layout import OPTIONS as OBSERVATION_OPTIONS  # noqa: E402

ENV_KEYS = {"control_hz", "wake", "collision_separation_b", "duration_s", "compute_benefit", "reward", "turbulence_field",
            "wake_coupling", "wake_fidelity", "randomisation", "learning", "leader_reference", *OBSERVATION_OPTIONS}


def load_yaml(path: str | Path) -> dict:
    import yaml

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"config file {str(path)!r} does not exist")
    with path.open() as fh:
        data = yaml.safe_load(fh)
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ValueError(f"config file {str(path)!r} must hold a mapping, got {type(data).__name__}")
    return data


def merge_config(base: dict, over: dict) -> dict:
    """``over`` merged over a deep copy of ``base`` key by key (sub-dicts merged too)."""
    out = copy.deepcopy(base)
    for k, v in over.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = merge_config(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out


def task_env_kwargs(scenario: str) -> dict:
    """The benchmark configuration of the task flown on ``scenario`` in the ``env_kwargs`` form
    (:meth:`formation_env.tasks.Task.env_kwargs`; {} for a scenario no task poses): what every run starts from,
    a hyperparameter file's ``env_kwargs`` merging over it as a departure from the task."""
    from formation_env.tasks import task_for_scenario

    task = task_for_scenario(scenario)
    return {} if task is None else task.env_kwargs()


def with_task_env(params: dict, scenario: str) -> dict:
    """``params`` (a hyperparameter section) with its ``env_kwargs`` merged over the task's benchmark configuration
    (:func:`task_env_kwargs`)."""
    out = copy.deepcopy(params)
    given = out.get("env_kwargs") or {}
    if not isinstance(given, dict):
        raise ValueError(f"env_kwargs must be a mapping of EnvConfig options, got {given!r}")
    out["env_kwargs"] = merge_config(task_env_kwargs(scenario), given)
    return out


def env_departures(scenario: str, env_kwargs: dict) -> dict:
    """What ``env_kwargs`` (a run's) sets differently from the task's benchmark configuration ({}: the benchmark
    task itself), as a mapping of the options (and reward / randomisation fields) that differ."""
    from formation_env.sim.config import EnvConfig, Randomisation, RewardWeights

    base = task_env_kwargs(scenario)
    out = {}
    for k in sorted(set(base) | set(env_kwargs)):
        a, b = base.get(k), env_kwargs.get(k)
        if isinstance(a, dict) or isinstance(b, dict):
            a, b = a or {}, b or {}
            cls = {"reward": RewardWeights, "randomisation": Randomisation}.get(k)
            default = (lambda f: getattr(cls(), f, None)) if cls is not None else (lambda f: None)
            diff = {f: b.get(f, default(f)) for f in sorted(set(a) | set(b))
                    if a.get(f, default(f)) != b.get(f, default(f))}
            if diff:
                out[k] = diff
        else:
            field_ = EnvConfig.__dataclass_fields__.get(k)
            d = field_.default if field_ is not None else None
            if (d if a is None else a) != (d if b is None else b):
                out[k] = b
    return out


def default_action_mode(scenario: str) -> str:
    """The action interface of the task flown on ``scenario`` (:attr:`formation_env.tasks.Task.action_mode`), or
    set-points for a scenario no task poses: both backends' default."""
    from formation_env.tasks import task_for_scenario

    task = task_for_scenario(scenario)
    return "setpoints" if task is None else task.action_mode


def task_stamp(scenario: str, env_kwargs: dict, action_mode: str) -> dict:
    """The task and version a run was made on and how its environment departs from the task's benchmark
    configuration ({} for a scenario no task poses): ``{"task": name, "task_version": v, "departures": {...}}``, the
    departures empty when the run trained on the benchmark task itself."""
    from formation_env.tasks import task_for_scenario

    task = task_for_scenario(scenario)
    if task is None:
        return {}
    departures = env_departures(scenario, env_kwargs)
    if action_mode != task.action_mode:
        departures["action_mode"] = action_mode
    return {"task": task.name, "task_version": task.version, "departures": departures}


def config_section(data: dict, scenario: str) -> dict:
    """The part of a hyperparameter mapping that applies to ``scenario``."""
    from formation_env.scenarios import scenario_names

    names = set(scenario_names()) | {"default"}
    if any(k in names for k in data):
        out = copy.deepcopy(data.get("default", {}) or {})
        return merge_config(out, data.get(scenario, {}) or {})
    return copy.deepcopy(data)


def env_config_for(scenario: str, action_mode: str, env_kwargs: dict, **overrides):
    """The EnvConfig of a scenario, action mode and ``env_kwargs`` mapping (the hyperparameter files'
    format; ``learning`` defaults to followers; flat observations). Shared by both backends."""
    from formation_env.sim.config import EnvConfig, Randomisation, RewardWeights

    if not isinstance(env_kwargs, dict):
        raise ValueError(f"env_kwargs must be a mapping of EnvConfig options, got {env_kwargs!r}")
    kw = copy.deepcopy(env_kwargs)
    kw.update(overrides)
    try:
        rnd = kw.pop("randomisation", {}) or {}
        rew = kw.pop("reward", {}) or {}
        for name, value, cls in (("randomisation", rnd, Randomisation), ("reward", rew, RewardWeights)):
            if not isinstance(value, (dict, cls)):
                raise ValueError(f"env_kwargs.{name} must be a mapping of {cls.__name__} fields, got {value!r}")
        from formation_env.sim.validation import nested_options  # an unknown key named, with the valid ones

        rnd = nested_options("env_kwargs", "randomisation", Randomisation, rnd)
        rew = nested_options("env_kwargs", "reward", RewardWeights, rew)
    except TypeError as exc:
        raise ValueError(str(exc) if str(exc).startswith("env_kwargs") else f"env_kwargs: {exc}") from None
    learning = kw.pop("learning", None)
    if learning is None:  # the task's own (vee_rotation: every UAV), else the followers
        from formation_env.tasks import task_learning

        learning = task_learning(scenario)
    if isinstance(learning, list):
        learning = tuple(learning)
    return EnvConfig(scenario=scenario, learning=learning, action_mode=action_mode, obs_mode="flat",
                     reward=rew, randomisation=rnd, **kw)
