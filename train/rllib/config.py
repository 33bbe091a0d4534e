"""The configuration of an RLlib run (:class:`RLlibTrainConfig`), its hyperparameter file and the
PPOConfig built from it. Ray is imported only inside :func:`build_algo_config`."""

from __future__ import annotations

import copy
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

from ..config import ENV_KEYS, HYPERPARAMS_DIR, config_section, env_config_for, load_yaml, merge_config, with_task_env

__all__ = ["RLlibTrainConfig", "load_rllib_hyperparams", "env_config_dict", "build_algo_config", "POLICY_MODES",
           "LEARNING_MODES"]

POLICY_MODES = ("shared", "per-role")
LEARNING_MODES = ("followers", "all")
_PPO_KEYS = {"lr", "gamma", "lambda_", "clip_param", "vf_clip_param", "vf_loss_coeff", "entropy_coeff", "kl_coeff",
             "kl_target", "use_kl_loss", "use_gae", "grad_clip", "train_batch_size_per_learner", "minibatch_size",
             "num_epochs", "shuffle_batch_per_epoch"}
_MODEL_KEYS = {"fcnet_hiddens", "fcnet_activation", "vf_share_layers", "free_log_std", "log_std_clip_param",
               "fcnet_use_layernorm"}
_TOP_KEYS = {"n_timesteps", "iterations", "num_env_runners", "num_envs_per_env_runner", "num_cpus_per_env_runner",
             "custom_resources_per_env_runner", "checkpoint_every", "reward_scale", "training", "model", "env_kwargs",
             "learning", "policies"}
# Ray's built-in resources, which Ray refuses as custom ones (num_cpus_per_env_runner sets the CPUs).
_BUILTIN_RESOURCES = ("CPU", "GPU", "memory", "object_store_memory")


@dataclass
class RLlibTrainConfig:
    """Everything that defines an RLlib run (saved as ``config.yaml`` in the run directory)."""

    scenario: str
    action_mode: str = "setpoints"
    seed: int = 0
    learning: str = "followers"
    policies: str = "shared"
    n_timesteps: int | None = 1_000_000
    iterations: int | None = None
    num_env_runners: int = 2
    num_envs_per_env_runner: int = 1
    num_cpus_per_env_runner: int = 1
    # Ray custom resources each env runner requests, e.g. {"sampler": 1}: a runner then goes only to a node
    # started with `ray start --resources '{"sampler": N}'`, and such a node takes at most N runners
    # (docs/distributed.md, "A real multi-node run").
    custom_resources_per_env_runner: dict = field(default_factory=dict)
    checkpoint_every: int = 10
    reward_scale: float = 1.0
    training: dict = field(default_factory=dict)
    model: dict = field(default_factory=dict)
    env_kwargs: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        from formation_env.scenarios import scenario_names

        from ..config import ACTION_MODES

        if self.scenario not in scenario_names():
            raise ValueError(f"unknown scenario {self.scenario!r}; available: {scenario_names()}")
        if self.action_mode not in ACTION_MODES:
            raise ValueError(f"unknown action mode {self.action_mode!r}; choose one of {ACTION_MODES}")
        if self.learning not in LEARNING_MODES:
            raise ValueError(f"learning must be one of {LEARNING_MODES}, got {self.learning!r}")
        if self.policies not in POLICY_MODES:
            raise ValueError(f"policies must be one of {POLICY_MODES}, got {self.policies!r}")
        for name, low in (("seed", 0), ("n_timesteps", 1), ("num_env_runners", 0), ("num_envs_per_env_runner", 1),
                          ("num_cpus_per_env_runner", 0), ("checkpoint_every", 0), ("iterations", 1)):
            v = getattr(self, name)
            if v is None and name in ("iterations", "n_timesteps"):
                continue
            if isinstance(v, float) and math.isfinite(v) and v.is_integer():
                v = int(v)
                setattr(self, name, v)
            if isinstance(v, bool) or not isinstance(v, int) or v < low:
                raise ValueError(f"{name} must be an integer >= {low}, got {v!r}")
        if self.n_timesteps is None and self.iterations is None:
            raise ValueError("give the run an end: steps (n_timesteps) or iterations")
        if isinstance(self.reward_scale, bool) or not isinstance(self.reward_scale, (int, float)) \
                or not math.isfinite(self.reward_scale) or self.reward_scale <= 0:
            raise ValueError(f"reward_scale must be a finite number > 0, got {self.reward_scale!r}")
        for name, valid in (("training", _PPO_KEYS), ("model", _MODEL_KEYS), ("env_kwargs", ENV_KEYS - {"learning"})):
            value = getattr(self, name)
            if not isinstance(value, dict):
                raise ValueError(f"{name} must be a mapping, got {type(value).__name__}")
            bad = sorted(set(value) - valid)
            if bad:
                raise ValueError(f"unknown {name} key(s) {bad}; valid: {sorted(valid)}")
        self._check_custom_resources()
        # Validates the environment options here, without ray (the env itself is built on the runners).
        from formation_env.scenarios import get_scenario

        env_config_for(self.scenario, self.action_mode, self.env_kwargs, learning=self.learning)
        if self.learning == "followers" and not get_scenario(self.scenario).slots:
            raise ValueError(f"scenario {self.scenario!r} flies one UAV: there are no followers to learn "
                             "(use learning='all')")

    def _check_custom_resources(self) -> None:
        res = self.custom_resources_per_env_runner
        if res is None:
            res = self.custom_resources_per_env_runner = {}
        if not isinstance(res, dict):
            raise ValueError("custom_resources_per_env_runner must be a mapping of Ray resource names to amounts "
                             f"> 0, got {type(res).__name__}")
        for name, amount in res.items():
            if not isinstance(name, str) or not name.strip():
                raise ValueError(f"custom_resources_per_env_runner: resource names must be non-empty strings, "
                                 f"got {name!r}")
            if name in _BUILTIN_RESOURCES:
                raise ValueError(f"custom_resources_per_env_runner: {name!r} is one of Ray's built-in resources "
                                 f"{list(_BUILTIN_RESOURCES)}, not a custom one (CPUs per runner: "
                                 "num_cpus_per_env_runner)")
            if isinstance(amount, bool) or not isinstance(amount, (int, float)) or not math.isfinite(amount) \
                    or amount <= 0:
                raise ValueError(f"custom_resources_per_env_runner[{name!r}] must be a finite number > 0, "
                                 f"got {amount!r}")

    @property
    def modules(self) -> list[str]:
        """The RLModule ids this run trains."""
        if self.policies == "shared":
            return ["shared"]
        return (["leader"] if self.learning == "all" else []) + ["follower"]

    @classmethod
    def from_hyperparams(cls, params: dict, **given) -> RLlibTrainConfig:
        p = copy.deepcopy(params)
        bad = sorted(set(p) - _TOP_KEYS)
        if bad:
            raise ValueError(f"unknown RLlib hyperparameter key(s) {bad}; valid: {sorted(_TOP_KEYS)}")
        p.update({k: v for k, v in given.items() if v is not None})
        return cls(**p)

    def to_dict(self) -> dict:
        return asdict(self)


def load_rllib_hyperparams(scenario: str, config_file: str | Path | None = None) -> dict:
    """``train/hyperparams/rllib_ppo.yml`` for ``scenario``, with ``config_file`` merged over it, its ``env_kwargs``
    merged over the task's benchmark configuration."""
    params = config_section(load_yaml(HYPERPARAMS_DIR / "rllib_ppo.yml"), scenario)
    if config_file is not None:
        params = merge_config(params, config_section(load_yaml(config_file), scenario))
    return with_task_env(params, scenario)


def env_config_dict(cfg: RLlibTrainConfig, episode_stream: int = 0) -> dict:
    """The ``env_config`` RLlib hands to ``FormationMultiAgentEnv`` on every env runner
    (``episode_stream``: 0, or the iteration a resumed run restarts from, so it sees new episodes)."""
    return {"scenario": cfg.scenario, "action_mode": cfg.action_mode, "learning": cfg.learning,
            "env_kwargs": copy.deepcopy(cfg.env_kwargs), "reward_scale": cfg.reward_scale,
            "episode_stream": int(episode_stream)}


def build_algo_config(cfg: RLlibTrainConfig, episode_stream: int = 0):
    """The PPOConfig of a run: the PettingZoo env through RLlib, shared or per-role policies."""
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig
    from ray.rllib.core.rl_module.multi_rl_module import MultiRLModuleSpec
    from ray.rllib.core.rl_module.rl_module import RLModuleSpec

    from .env import FormationMultiAgentEnv, role_policy, shared_policy

    mapping = shared_policy if cfg.policies == "shared" else role_policy
    return (
        PPOConfig()
        .environment(FormationMultiAgentEnv, env_config=env_config_dict(cfg, episode_stream))
        .env_runners(num_env_runners=cfg.num_env_runners, num_envs_per_env_runner=cfg.num_envs_per_env_runner,
                     num_cpus_per_env_runner=cfg.num_cpus_per_env_runner,
                     custom_resources_per_env_runner=dict(cfg.custom_resources_per_env_runner),
                     rollout_fragment_length="auto")
        .multi_agent(policies=set(cfg.modules), policy_mapping_fn=mapping)
        .rl_module(rl_module_spec=MultiRLModuleSpec(rl_module_specs={m: RLModuleSpec() for m in cfg.modules}),
                   model_config=DefaultModelConfig(**cfg.model))
        .training(**cfg.training)
        .debugging(seed=cfg.seed, log_level="ERROR")
    )
