"""The SB3 training configuration: a validated dataclass built from RL-Zoo-style YAML files.

``train/hyperparams/{ppo,sac,td3}.yml`` hold one section per scenario (and a ``default`` section
used for scenarios without their own), in the style of the RL Baselines3 Zoo::

    formation_keeping:
      n_timesteps: 1000000          # total environment steps (one step = one agent decision)
      n_formations: 32              # formations per FormationVecEnv (num_envs = formations x agents)
      policy: MlpPolicy
      learning_rate: 3.0e-4         # any keyword of the SB3 algorithm's constructor
      policy_kwargs: {net_arch: [64, 64], log_std_init: -1.0, activation_fn: tanh}
      env_kwargs:                   # EnvConfig options; randomisation / reward are sub-dicts
        randomisation: {turbulence_sigma_mps: 1.0, initial_offset_m: 1.0}
      eval_freq: 50000              # evaluate every this many env steps (0: never)
      eval_episodes: 32             # held-out validation episodes per evaluation (>= 32; drawn like
                                    # the test set of `formation-env evaluate`, on their own seeds)
      checkpoint_freq: 100000       # checkpoint every this many env steps (0: never)
      reward_scale: 0.05            # rewards seen by the learner are multiplied by this (the curves
                                    # and evaluations report the unscaled env reward)

A ``--config FILE`` is the same format (a section keyed by the scenario, or a flat section) and is
merged over the defaults key by key (``env_kwargs``, ``policy_kwargs`` and their sub-dicts merged
too). Unknown keys raise ValueError naming them.
"""

from __future__ import annotations

import copy
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

from ..config import (ACTION_MODES, ENV_KEYS, HYPERPARAMS_DIR, MIN_VALIDATION_EPISODES, config_section, env_config_for,
                      load_yaml, merge_config)

__all__ = ["ALGOS", "TrainConfig", "load_hyperparams", "make_env_config"]

ALGOS = ("ppo", "sac", "td3")

_TRAIN_KEYS = {"n_timesteps", "n_formations", "policy", "policy_kwargs", "env_kwargs", "eval_freq",
               "eval_episodes", "checkpoint_freq", "torch_threads", "reward_scale"}
_ALGO_KEYS = {
    "ppo": {"learning_rate", "n_steps", "batch_size", "n_epochs", "gamma", "gae_lambda", "clip_range",
            "clip_range_vf", "normalize_advantage", "ent_coef", "vf_coef", "max_grad_norm", "use_sde",
            "sde_sample_freq", "target_kl"},
    "sac": {"learning_rate", "buffer_size", "learning_starts", "batch_size", "tau", "gamma", "train_freq",
            "gradient_steps", "ent_coef", "target_update_interval", "target_entropy", "use_sde",
            "sde_sample_freq", "use_sde_at_warmup", "action_noise"},
    "td3": {"learning_rate", "buffer_size", "learning_starts", "batch_size", "tau", "gamma", "train_freq",
            "gradient_steps", "policy_delay", "target_policy_noise", "target_noise_clip", "action_noise"},
}
_POLICY_KWARGS = {"net_arch", "log_std_init", "activation_fn", "ortho_init", "squash_output", "n_critics",
                  "use_expln", "full_std", "share_features_extractor"}


def load_hyperparams(algo: str, scenario: str, config_file: str | Path | None = None) -> dict:
    """The merged hyperparameters of ``algo`` on ``scenario`` (defaults, then ``config_file``)."""
    if algo not in ALGOS:
        raise ValueError(f"unknown algo {algo!r}; choose one of {ALGOS}")
    params = config_section(load_yaml(HYPERPARAMS_DIR / f"{algo}.yml"), scenario)
    if config_file is not None:
        params = merge_config(params, config_section(load_yaml(config_file), scenario))
    return params


@dataclass
class TrainConfig:
    """Everything that defines a training run (saved as ``config.yaml`` in the run directory)."""

    scenario: str
    algo: str
    action_mode: str
    seed: int
    n_timesteps: int
    n_formations: int = 32
    policy: str = "MlpPolicy"
    algo_kwargs: dict = field(default_factory=dict)
    policy_kwargs: dict = field(default_factory=dict)
    env_kwargs: dict = field(default_factory=dict)
    eval_freq: int = 50_000
    eval_episodes: int = MIN_VALIDATION_EPISODES
    checkpoint_freq: int = 100_000
    torch_threads: int = 1
    reward_scale: float = 1.0

    def __post_init__(self) -> None:
        from formation_env.scenarios import scenario_names

        if self.algo not in ALGOS:
            raise ValueError(f"unknown algo {self.algo!r}; choose one of {ALGOS}")
        if self.action_mode not in ACTION_MODES:
            raise ValueError(f"unknown action mode {self.action_mode!r}; choose one of {ACTION_MODES}")
        if self.scenario not in scenario_names():
            raise ValueError(f"unknown scenario {self.scenario!r}; available: {scenario_names()}")
        for name in ("seed", "n_timesteps", "n_formations", "eval_freq", "eval_episodes", "checkpoint_freq",
                     "torch_threads"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int):
                if isinstance(v, float) and v.is_integer() and math.isfinite(v):
                    v = int(v)
                    setattr(self, name, v)
                else:
                    raise ValueError(f"{name} must be an integer, got {v!r}")
        if self.seed < 0:
            raise ValueError(f"seed must be >= 0, got {self.seed}")
        if self.n_timesteps <= 0:
            raise ValueError(f"steps (n_timesteps) must be a positive integer, got {self.n_timesteps}")
        if self.n_formations < 1:
            raise ValueError(f"n_formations must be >= 1, got {self.n_formations}")
        for name in ("eval_freq", "checkpoint_freq"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0 (0: off), got {getattr(self, name)}")
        if self.eval_episodes < 1:
            raise ValueError(f"eval_episodes must be >= 1, got {self.eval_episodes}")
        if isinstance(self.reward_scale, bool) or not isinstance(self.reward_scale, (int, float)) \
                or not math.isfinite(self.reward_scale) or self.reward_scale <= 0:
            raise ValueError(f"reward_scale must be a finite number > 0, got {self.reward_scale!r}")
        if self.torch_threads < 1:
            raise ValueError(f"torch_threads must be >= 1, got {self.torch_threads}")
        bad = sorted(set(self.algo_kwargs) - _ALGO_KEYS[self.algo])
        if bad:
            raise ValueError(f"unknown {self.algo} hyperparameter(s) {bad}; valid: {sorted(_ALGO_KEYS[self.algo] | _TRAIN_KEYS)}")
        bad = sorted(set(self.policy_kwargs) - _POLICY_KWARGS)
        if bad:
            raise ValueError(f"unknown policy_kwargs key(s) {bad}; valid: {sorted(_POLICY_KWARGS)}")
        bad = sorted(set(self.env_kwargs) - ENV_KEYS)
        if bad:
            raise ValueError(f"unknown env_kwargs key(s) {bad}; valid: {sorted(ENV_KEYS)}")
        make_env_config(self)  # validates the environment options

    @classmethod
    def from_hyperparams(cls, params: dict, *, scenario: str, algo: str, action_mode: str, seed: int,
                         n_timesteps: int | None = None) -> TrainConfig:
        p = copy.deepcopy(params)
        kw = {k: p.pop(k) for k in list(p) if k in _TRAIN_KEYS}
        steps = kw.pop("n_timesteps", None) if n_timesteps is None else n_timesteps
        kw.pop("n_timesteps", None)
        if steps is None:
            raise ValueError("steps: give --steps or n_timesteps in the hyperparameter file")
        if isinstance(steps, float) and steps.is_integer():
            steps = int(steps)
        return cls(scenario=scenario, algo=algo, action_mode=action_mode, seed=seed, n_timesteps=steps,
                   algo_kwargs=p, **kw)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> TrainConfig:
        return cls(**data)


def make_env_config(cfg: TrainConfig, **overrides):
    """The EnvConfig a run trains on (followers learn; flat observations)."""
    return env_config_for(cfg.scenario, cfg.action_mode, cfg.env_kwargs, **overrides)
