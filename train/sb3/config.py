"""The SB3 training configuration: a validated dataclass built from RL-Zoo-style YAML files.

``train/hyperparams/{ppo,recurrent_ppo,sac,td3}.yml`` hold one section per scenario (and a ``default`` section
used for scenarios without their own), in the style of the RL Baselines3 Zoo::

    formation_keeping:
      n_timesteps: 1000000          # total environment steps (one step = one agent decision)
      n_formations: 32              # formations per FormationVecEnv (num_envs = formations x agents)
      policy: MlpPolicy
      learning_rate: 3.0e-4         # any keyword of the SB3 algorithm's constructor ("lin_3.0e-4": a
                                    # linear decay from 3e-4 to 0 over the run, as in the RL Zoo)
      policy_kwargs: {net_arch: [64, 64], log_std_init: -1.0, activation_fn: tanh}
      env_kwargs:                   # EnvConfig options; randomisation / reward are sub-dicts
        randomisation: {turbulence_sigma_mps: 1.0, initial_offset_m: 1.0}
      eval_freq: 50000              # evaluate every this many env steps (0: never)
      eval_episodes: 32             # held-out validation episodes per evaluation (>= 32; drawn like
                                    # the test set of `formation-env evaluate`, on their own seeds)
      checkpoint_freq: 100000       # checkpoint every this many env steps (0: never)
      reward_scale: 0.05            # rewards seen by the learner are multiplied by this (the curves
                                    # and evaluations report the unscaled env reward)
      selection_collision_cost: 2.0 # model selection: each validation episode with a collision adds this
                                    # / eval_episodes to the score (null, the default: any collision
                                    # disqualifies the model)

A ``--config FILE`` is the same format (a section keyed by the scenario, or a flat section) and is
merged over the defaults key by key (``env_kwargs``, ``policy_kwargs`` and their sub-dicts merged
too). Unknown keys raise ValueError naming them; every value is checked (type and range,
:data:`HYPERPARAMETER_RANGES`, :data:`POLICY_KWARGS_RANGES`) when the TrainConfig is built, before the run
directory or its ``config.yaml`` is written, into a one-line ValueError (never SB3's own assertion or a
failure after training).
"""

from __future__ import annotations

import copy
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

from ..config import (ACTION_MODES, ENV_KEYS, HYPERPARAMS_DIR, MIN_VALIDATION_EPISODES, config_section, env_config_for,
                      load_yaml, merge_config, with_task_env)

__all__ = ["ALGOS", "TrainConfig", "load_hyperparams", "make_env_config"]

# recurrent_ppo: sb3-contrib's RecurrentPPO (an LSTM before the actor's and the critic's MLPs), on the same VecEnv
ALGOS = ("ppo", "recurrent_ppo", "sac", "td3")

_TRAIN_KEYS = {"n_timesteps", "n_formations", "policy", "policy_kwargs", "env_kwargs", "eval_freq",
               "eval_episodes", "checkpoint_freq", "torch_threads", "reward_scale", "init_policy", "action_guard",
               "selection_collision_cost", "residual_on"}
_PPO_KEYS = {"learning_rate", "n_steps", "batch_size", "n_epochs", "gamma", "gae_lambda", "clip_range", "clip_range_vf",
             "normalize_advantage", "ent_coef", "vf_coef", "max_grad_norm", "use_sde", "sde_sample_freq", "target_kl"}
_ALGO_KEYS = {
    "ppo": _PPO_KEYS,
    "recurrent_ppo": _PPO_KEYS,
    "sac": {"learning_rate", "buffer_size", "learning_starts", "batch_size", "tau", "gamma", "train_freq",
            "gradient_steps", "ent_coef", "target_update_interval", "target_entropy", "use_sde",
            "sde_sample_freq", "use_sde_at_warmup", "action_noise"},
    "td3": {"learning_rate", "buffer_size", "learning_starts", "batch_size", "tau", "gamma", "train_freq",
            "gradient_steps", "policy_delay", "target_policy_noise", "target_noise_clip", "action_noise"},
}
_LSTM_KWARGS = {"lstm_hidden_size", "n_lstm_layers", "shared_lstm", "enable_critic_lstm"}  # recurrent_ppo's only
_POLICY_KWARGS = {"net_arch", "log_std_init", "activation_fn", "ortho_init", "squash_output", "n_critics",
                  "use_expln", "full_std", "share_features_extractor", *_LSTM_KWARGS}

MAX_TIMESTEPS = 10**9  # as the CLI's --steps (formation_env.cli._args.MAX_TRAIN_STEPS; a test holds them equal)
ACTIVATIONS = ("tanh", "relu", "elu", "leaky_relu")  # policy_kwargs.activation_fn (train/sb3/train.py maps them)
# the vector envs' observations are flat Boxes; CentralCriticPolicy (PPO only): MAPPO's centralised critic on the
# agent-specific global state, the actor on the agent's own observation (train/sb3/central_critic.py);
# MlpLstmPolicy (recurrent_ppo only): sb3-contrib's LSTM policy
POLICIES = ("MlpPolicy", "CentralCriticPolicy", "MlpLstmPolicy")

#: hyperparameter -> (kind, min, max, what): kind "int", "float", "bool", "float?" (None allowed); min and
#: max inclusive, except a float min marked exclusive by being in _EXCLUSIVE_MIN. "ent_coef", "target_entropy"
#: and "gradient_steps" take extra forms (see _check_special).
HYPERPARAMETER_RANGES: dict[str, tuple[str, float, float, str]] = {
    "learning_rate": ("float", 0.0, 1.0, "Adam step size"),
    "n_steps": ("int", 1, 1_000_000, "rollout length per env index"),
    "batch_size": ("int", 2, 10_000_000, "minibatch size (SB3 needs > 1)"),
    "n_epochs": ("int", 1, 1000, "passes over each rollout"),
    "gamma": ("float", 0.0, 1.0, "discount factor"),
    "gae_lambda": ("float", 0.0, 1.0, "GAE lambda"),
    "clip_range": ("float", 0.0, 10.0, "PPO ratio clip"),
    "clip_range_vf": ("float?", 0.0, 1e6, "value clip (None: off)"),
    "normalize_advantage": ("bool", 0, 1, ""),
    "ent_coef": ("float", 0.0, 10.0, "entropy bonus"),
    "vf_coef": ("float", 0.0, 100.0, "value-loss weight"),
    "max_grad_norm": ("float", 0.0, 1e6, "gradient clip"),
    "use_sde": ("bool", 0, 1, ""),
    "sde_sample_freq": ("int", -1, 1_000_000, "-1: once per rollout"),
    "target_kl": ("float?", 0.0, 10.0, "early-stop KL (None: off)"),
    "buffer_size": ("int", 1, 100_000_000, "replay buffer transitions"),
    "learning_starts": ("int", 0, MAX_TIMESTEPS, "env steps before learning"),
    "tau": ("float", 0.0, 1.0, "target network soft-update rate"),
    "train_freq": ("int", 1, 1_000_000, "vector steps between updates"),
    "gradient_steps": ("int", -1, 10_000, "gradient steps per update (-1: as many as env steps)"),
    "target_update_interval": ("int", 1, 1_000_000, "gradient steps between target updates"),
    "use_sde_at_warmup": ("bool", 0, 1, ""),
    "action_noise": ("float?", 0.0, 10.0, "Gaussian exploration noise std, normalised actions (None/0: off)"),
    "policy_delay": ("int", 1, 1000, "critic updates per actor update"),
    "target_policy_noise": ("float", 0.0, 10.0, "target smoothing noise std"),
    "target_noise_clip": ("float", 0.0, 10.0, "target smoothing noise clip"),
}
_EXCLUSIVE_MIN = {"learning_rate", "clip_range", "clip_range_vf", "max_grad_norm", "target_kl", "tau"}

#: policy_kwargs key -> (kind, min, max, what); net_arch and activation_fn are checked by _check_policy_kwargs
POLICY_KWARGS_RANGES: dict[str, tuple[str, float, float, str]] = {
    "log_std_init": ("float", -20.0, 2.0, "initial log std of the Gaussian policy"),
    "ortho_init": ("bool", 0, 1, ""),
    "squash_output": ("bool", 0, 1, ""),
    "n_critics": ("int", 1, 10, "Q networks"),
    "use_expln": ("bool", 0, 1, ""),
    "full_std": ("bool", 0, 1, ""),
    "share_features_extractor": ("bool", 0, 1, ""),
    "lstm_hidden_size": ("int", 1, 4096, "LSTM units (recurrent_ppo)"),
    "n_lstm_layers": ("int", 1, 8, "stacked LSTM layers (recurrent_ppo)"),
    "shared_lstm": ("bool", 0, 1, "the critic reads the actor's LSTM (recurrent_ppo)"),
    "enable_critic_lstm": ("bool", 0, 1, "the critic has its own LSTM (recurrent_ppo)"),
}
MAX_LAYER_WIDTH = 65_536


def _check_value(where: str, name: str, value, spec, *, exclusive: bool | None = None) -> object:
    """``value`` checked against ``spec`` = (kind, min, max, what); returns it (ints from integral floats)."""
    kind, lo, hi, what = spec
    about = f" ({what})" if what else ""
    if kind == "bool":
        if not isinstance(value, bool):
            raise ValueError(f"{where}{name} must be true or false, got {value!r}")
        return value
    if kind == "float?" and value is None:
        return None
    if kind == "int":
        if isinstance(value, float) and math.isfinite(value) and value.is_integer():
            value = int(value)
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            raise ValueError(f"{where}{name} must be an integer in [{lo}, {hi}]{about}, got {value!r}")
        return value
    exclusive = name in _EXCLUSIVE_MIN if exclusive is None else exclusive
    span = f"{'(' if exclusive else '['}{lo:g}, {hi:g}]"
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
            or not (lo < value if exclusive else lo <= value) or value > hi:
        none = " or null" if kind == "float?" else ""
        raise ValueError(f"{where}{name} must be a number in {span}{none}{about}, got {value!r}")
    return value


def _check_special(algo: str, name: str, value):
    """The hyperparameters with more than one form; None where the generic table applies."""
    where = f"{algo} hyperparameter "
    if name == "ent_coef" and algo == "sac":  # "auto", "auto_<init>" or a number > 0
        if isinstance(value, str):
            init = value[5:] if value.startswith("auto_") else None
            try:
                ok = value == "auto" or (init is not None and math.isfinite(float(init)) and float(init) > 0)
            except ValueError:
                ok = False
            if not ok:
                raise ValueError(f"{where}ent_coef must be 'auto', 'auto_<initial value > 0>' or a number in (0, 10], "
                                 f"got {value!r}")
            return value
        return _check_value(where, name, value, ("float", 0.0, 10.0, "SAC: 'auto' or a number"), exclusive=True)
    if name == "learning_rate" and isinstance(value, str):  # RL Zoo's "lin_<initial>": linear decay to 0 at the end
        try:
            ok = value.startswith("lin_") and 0.0 < float(value[4:]) <= 1.0
        except ValueError:
            ok = False
        if not ok:
            raise ValueError(f"{where}learning_rate must be a number in (0, 1] or 'lin_<initial value in (0, 1]>' "
                             f"(linear decay to 0 over the run), got {value!r}")
        return value
    if name == "target_entropy":  # "auto" or a number
        if value == "auto":
            return value
        return _check_value(where, name, value, ("float", -1000.0, 1000.0, "'auto' or the target entropy"))
    if name == "gradient_steps" and value == 0:
        raise ValueError(f"{where}gradient_steps must be -1 or an integer in [1, 10000] (0 never trains), got 0")
    return None


def _check_hyperparameters(algo: str, kwargs: dict) -> dict:
    out = {}
    for name, value in kwargs.items():
        special = _check_special(algo, name, value)
        out[name] = special if special is not None else _check_value(f"{algo} hyperparameter ", name, value,
                                                                      HYPERPARAMETER_RANGES[name])
    return out


def _check_net_arch(value) -> None:
    def layers(v, what: str) -> None:
        if not isinstance(v, list) or any(isinstance(w, bool) or not isinstance(w, int) or not 1 <= w <= MAX_LAYER_WIDTH
                                          for w in v):
            raise ValueError(f"policy_kwargs.{what} must be a list of layer widths (integers in [1, {MAX_LAYER_WIDTH}]), "
                             f"got {v!r}")

    if isinstance(value, dict):
        bad = sorted(set(value) - {"pi", "vf", "qf"})
        if bad:
            raise ValueError(f"policy_kwargs.net_arch: unknown key(s) {bad}; a dict takes 'pi' and 'vf' (PPO) or 'qf' "
                             f"(SAC, TD3), got {value!r}")
        for k, v in value.items():
            layers(v, f"net_arch.{k}")
    else:
        layers(value, "net_arch")


def _check_policy_kwargs(kwargs: dict) -> None:
    for name, value in kwargs.items():
        if name == "net_arch":
            _check_net_arch(value)
        elif name == "activation_fn":
            if not isinstance(value, str) or value.lower() not in ACTIVATIONS:
                raise ValueError(f"policy_kwargs.activation_fn must be one of {ACTIVATIONS}, got {value!r}")
        else:
            _check_value("policy_kwargs.", name, value, POLICY_KWARGS_RANGES[name])


def load_hyperparams(algo: str, scenario: str, config_file: str | Path | None = None) -> dict:
    """The merged hyperparameters of ``algo`` on ``scenario`` (defaults, then ``config_file``), their
    ``env_kwargs`` merged over the task's benchmark configuration (a file's ``env_kwargs`` is a departure from the
    task, which the run's sidecar records)."""
    if algo not in ALGOS:
        raise ValueError(f"unknown algo {algo!r}; choose one of {ALGOS}")
    params = config_section(load_yaml(HYPERPARAMS_DIR / f"{algo}.yml"), scenario)
    if config_file is not None:
        params = merge_config(params, config_section(load_yaml(config_file), scenario))
    return with_task_env(params, scenario)


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
    # an SB3 zip of the same algorithm and policy whose parameters start the run (fine-tuning, e.g. vee_rotation
    # from a vee5 policy); "{seed}" in it stands for the run's seed (each training seed from its own policy); None:
    # a fresh initialisation
    init_policy: str | None = None
    # the separation guard (agents.separation_guard) filters the policy's set-point actions in training, in
    # validation and wherever the published policy is evaluated (its sidecar says so): part of the policy
    action_guard: bool | dict = False
    # the model selection's price of a validation episode that ends in a collision or crash, in the selection
    # score's units per episode (train.evaluation.summary.selection_score); None: any collision disqualifies
    selection_collision_cost: float | None = None
    # a residual policy on a classical agent (train.sb3.residual): {agent: station_keeper, scale: s}, the learner's
    # action times s added to the agent's set-points in training, in validation and wherever the published policy
    # flies (its sidecar says so); None: the learner's action is the set-point itself
    residual_on: dict | None = None

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
        if self.n_timesteps > MAX_TIMESTEPS:
            raise ValueError(f"steps (n_timesteps) must be at most {MAX_TIMESTEPS:,}, got {self.n_timesteps}")
        from formation_env.envs.vector import MAX_FORMATIONS

        if not 1 <= self.n_formations <= MAX_FORMATIONS:
            raise ValueError(f"n_formations must be in [1, {MAX_FORMATIONS}], got {self.n_formations}")
        for name in ("eval_freq", "checkpoint_freq"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0 (0: off), got {getattr(self, name)}")
        if not 1 <= self.eval_episodes <= 10_000:
            raise ValueError(f"eval_episodes must be in [1, 10000], got {self.eval_episodes}")
        if isinstance(self.init_policy, str) and "{seed}" in self.init_policy:
            object.__setattr__(self, "init_policy", self.init_policy.replace("{seed}", str(self.seed)))
        if self.init_policy is not None and (not isinstance(self.init_policy, str) or not self.init_policy.endswith(".zip")
                                             or not Path(self.init_policy).is_file()):
            raise ValueError(f"init_policy must be None or the path of an existing SB3 .zip (\"{{seed}}\" for the run's "
                             f"seed), got {self.init_policy!r}")
        if isinstance(self.reward_scale, bool) or not isinstance(self.reward_scale, (int, float)) \
                or not math.isfinite(self.reward_scale) or not 0 < self.reward_scale <= 1e3:
            raise ValueError(f"reward_scale must be a finite number > 0 (and <= 1000), got {self.reward_scale!r}")
        if isinstance(self.action_guard, dict):  # the guard with these GuardGains (e.g. {clip_ramp: 0.25})
            from .guard import guard_gains

            if not self.action_guard:
                raise ValueError("action_guard: an empty mapping; give true for the guard's default gains")
            guard_gains(self.action_guard)
        elif not isinstance(self.action_guard, bool):
            raise ValueError(f"action_guard must be true, false or a mapping of separation-guard gains (e.g. "
                             f"{{clip_ramp: 0.25}}), got {self.action_guard!r}")
        if self.action_guard and self.action_mode != "setpoints":
            raise ValueError(f"action_guard filters set-point actions; action mode {self.action_mode!r} has none "
                             "(use --action-mode setpoints or action_guard: false)")
        if self.action_guard:
            from formation_env.scenarios import get_scenario

            if get_scenario(self.scenario).safe_box_b is not None:
                raise ValueError(f"action_guard: scenario {self.scenario!r} has a safe box, whose set-point ranges are not "
                                 "the guard's +-5 m (use action_guard: false)")
        if self.residual_on is not None:
            from .residual import check_residual_on

            object.__setattr__(self, "residual_on", check_residual_on(self.residual_on))
            if self.action_mode != "setpoints":
                raise ValueError(f"residual_on adds to an agent's set-points; action mode {self.action_mode!r} has none "
                                 "(use --action-mode setpoints)")
            from formation_env.scenarios import get_scenario

            if get_scenario(self.scenario).safe_box_b is not None:
                raise ValueError(f"residual_on: scenario {self.scenario!r} has a safe box, whose set-point ranges are not "
                                 "the station keeper's +-5 m")
        c = self.selection_collision_cost
        if c is not None and (isinstance(c, bool) or not isinstance(c, (int, float)) or not math.isfinite(c)
                              or not 0 <= c <= 1e3):
            raise ValueError(f"selection_collision_cost must be null (a collision disqualifies) or a finite number in "
                             f"[0, 1000], got {c!r}")
        if not 1 <= self.torch_threads <= 1024:
            raise ValueError(f"torch_threads must be in [1, 1024], got {self.torch_threads}")
        if not isinstance(self.policy, str) or self.policy not in POLICIES:
            raise ValueError(f"policy must be one of {POLICIES} (the envs' observations are flat), got {self.policy!r}")
        if self.policy == "CentralCriticPolicy" and self.algo != "ppo":
            raise ValueError(f"policy CentralCriticPolicy (MAPPO's centralised critic) needs algo ppo, got {self.algo!r}")
        if (self.policy == "MlpLstmPolicy") != (self.algo == "recurrent_ppo"):
            raise ValueError(f"policy MlpLstmPolicy goes with algo recurrent_ppo and only with it, got policy "
                             f"{self.policy!r} with algo {self.algo!r}")
        for name in ("algo_kwargs", "policy_kwargs", "env_kwargs"):
            if not isinstance(getattr(self, name), dict):
                label = "hyperparameters" if name == "algo_kwargs" else name
                raise ValueError(f"{label} must be a mapping, got {getattr(self, name)!r}")
        bad = sorted(set(self.algo_kwargs) - _ALGO_KEYS[self.algo])
        if bad:
            raise ValueError(f"unknown {self.algo} hyperparameter(s) {bad}; valid: {sorted(_ALGO_KEYS[self.algo] | _TRAIN_KEYS)}")
        known = _POLICY_KWARGS if self.algo == "recurrent_ppo" else _POLICY_KWARGS - _LSTM_KWARGS
        bad = sorted(set(self.policy_kwargs) - known)
        if bad:
            raise ValueError(f"unknown policy_kwargs key(s) {bad} for {self.algo}; valid: {sorted(known)}")
        bad = sorted(set(self.env_kwargs) - ENV_KEYS)
        if bad:
            raise ValueError(f"unknown env_kwargs key(s) {bad}; valid: {sorted(ENV_KEYS)}")
        self.algo_kwargs = _check_hyperparameters(self.algo, self.algo_kwargs)
        _check_policy_kwargs(self.policy_kwargs)
        _check_batch_fits(self, make_env_config(self))  # validates the environment options too

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


def _check_batch_fits(cfg: TrainConfig, env) -> None:
    """A minibatch fits in what it is drawn from: (recurrent) PPO's rollout (n_steps x env indices), SAC/TD3's replay
    buffer."""
    kw = cfg.algo_kwargs
    on_policy = cfg.algo in ("ppo", "recurrent_ppo")
    batch = kw.get("batch_size", {"ppo": 64, "recurrent_ppo": 128}.get(cfg.algo, 256))  # SB3's / sb3-contrib's defaults
    if on_policy:
        from formation_env.scenarios import get_scenario

        n = get_scenario(cfg.scenario).n_vehicles
        agents = max({"all": n, "followers": n - 1}[env.learning] if isinstance(env.learning, str)
                     else len(env.learning), 1)  # (a one-UAV scenario's env makes its UAV the agent)
        n_steps = kw.get("n_steps", 2048 if cfg.algo == "ppo" else 128)
        rollout = n_steps * cfg.n_formations * agents
        if batch > rollout:
            raise ValueError(f"batch_size {batch} is larger than the rollout it is drawn from: n_steps {n_steps} x "
                             f"n_formations {cfg.n_formations} x {agents} agent(s) = {rollout} samples; give "
                             f"batch_size <= {rollout} (or more n_steps / n_formations)")
    elif batch > kw.get("buffer_size", 1_000_000):
        raise ValueError(f"batch_size {batch} is larger than the replay buffer (buffer_size "
                         f"{kw.get('buffer_size', 1_000_000)}); give batch_size <= buffer_size")


def make_env_config(cfg: TrainConfig, **overrides):
    """The EnvConfig a run trains on (followers learn; flat observations)."""
    return env_config_for(cfg.scenario, cfg.action_mode, cfg.env_kwargs, **overrides)
