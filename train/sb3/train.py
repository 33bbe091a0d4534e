"""Training with Stable-Baselines3 on the native FormationVecEnv.

Run directory layout (a new directory; an existing non-empty one is refused unless ``overwrite``;
``resume`` continues one)::

    config.yaml            the TrainConfig (everything that defines the run) and the command
    checkpoints/           model_<steps>_steps.zip (+ replay buffer for SAC/TD3), written atomically
    best_model.zip/.json   the best model on the held-out validation episodes (eval callback)
    final_model.zip/.json  the model at the end
    curve.csv              learning curve: one row per finished training episode (steps, return, length)
    evaluations.json       validation results at every evaluation
    logs/                  SB3 logger output (progress.csv; TensorBoard events when installed)
    summary.json           wall time, steps, best validation score

Determinism: the env, the model (``seed=``), torch (``torch_threads``, 1 by default) and every
episode seed derive from the run's seed, and the eval callback does not touch any generator the
training uses; on CPU a re-run with the same seed reproduces the curve and the parameters exactly.
A resumed run continues deterministically from its checkpoint (the env is reseeded from the seed and
the checkpoint's step count), but not bit-identically to a run that was never interrupted.
"""

from __future__ import annotations

import csv
import importlib.util
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..config import default_action_mode, merge_config
from .callbacks import build_callbacks
from .config import TrainConfig, load_hyperparams, make_env_config
from .run_files import (latest_checkpoint, run_metadata, save_checkpoint, save_model_atomic, write_curve,
                        write_text_atomic)

__all__ = ["train", "default_run_dir", "latest_checkpoint", "progress_bar_available", "build_model"]


def progress_bar_available() -> bool:
    return all(importlib.util.find_spec(m) is not None for m in ("tqdm", "rich"))


def tensorboard_available() -> bool:
    return importlib.util.find_spec("tensorboard") is not None


def default_run_dir(scenario: str, algo: str, action_mode: str, seed: int, root: str | Path = "runs") -> Path:
    stamp = time.strftime("%Y%m%d-%H%M%S")
    return Path(root) / f"{scenario}-{algo}-{action_mode}-seed{seed}-{stamp}"


def _algo_class(algo: str):
    if algo == "recurrent_ppo":  # sb3-contrib only where asked for: the other algorithms run without it
        from ..recurrent import recurrent_ppo_class

        return recurrent_ppo_class()
    from stable_baselines3 import PPO, SAC, TD3

    return {"ppo": PPO, "sac": SAC, "td3": TD3}[algo]


def _policy_kwargs(cfg: TrainConfig) -> dict:
    import torch.nn as nn

    kw = dict(cfg.policy_kwargs)
    act = kw.get("activation_fn")
    if isinstance(act, str):
        table = {"tanh": nn.Tanh, "relu": nn.ReLU, "elu": nn.ELU, "leaky_relu": nn.LeakyReLU}
        if act.lower() not in table:
            raise ValueError(f"policy_kwargs.activation_fn must be one of {sorted(table)}, got {act!r}")
        kw["activation_fn"] = table[act.lower()]
    if cfg.algo in ("sac", "td3"):
        kw.pop("ortho_init", None)
        if cfg.algo == "td3":
            kw.pop("log_std_init", None)
    return kw


def build_model(cfg: TrainConfig, env):
    cls = _algo_class(cfg.algo)
    kw = dict(cfg.algo_kwargs)
    if isinstance(kw.get("learning_rate"), str):  # "lin_<initial>" (validated): SB3's own schedule class, so a
        from stable_baselines3.common.utils import LinearSchedule  # saved zip unpickles without this package

        kw["learning_rate"] = LinearSchedule(float(kw["learning_rate"][4:]), 0.0, 1.0)
    if cfg.algo in ("sac", "td3"):
        noise = kw.pop("action_noise", None)
        if noise:
            from stable_baselines3.common.noise import NormalActionNoise, VectorizedActionNoise

            base = NormalActionNoise(np.zeros(4), float(noise) * np.ones(4))
            kw["action_noise"] = VectorizedActionNoise(base, env.num_envs) if env.num_envs > 1 else base
    policy, pkw = cfg.policy, _policy_kwargs(cfg)
    if policy == "CentralCriticPolicy":  # MAPPO: the env appends the global state, the actor reads the own part
        from .central_critic import CentralCriticPolicy

        policy, pkw = CentralCriticPolicy, {**pkw, "local_dim": int(env.local_dim)}  # GlobalStateVecEnv's
    model = cls(policy, env, policy_kwargs=pkw, seed=cfg.seed, device="cpu", verbose=0, **kw)
    if cfg.init_policy is not None:  # fine-tuning: start from another run's policy (same sizes)
        try:
            model.set_parameters(cfg.init_policy, exact_match=True, device="cpu")
        except Exception as exc:  # noqa: BLE001 - one clear error naming the file
            raise ValueError(f"init_policy {cfg.init_policy!r} does not fit this run's {cfg.algo} {cfg.policy} "
                             f"(observation, action or network sizes differ): {exc}") from None
    return model


def make_train_env(cfg: TrainConfig, seed: int):
    from formation_env.envs import FormationVecEnv

    env_config = make_env_config(cfg)
    env = FormationVecEnv(cfg.n_formations, env_config, seed=seed)
    layout = env.observation_layout  # the observations the guard and the residual's agent read
    if cfg.action_guard:  # the separation guard filters the policy's set-points (inside MAPPO's global state)
        from .guard import GuardedVecEnv

        env = GuardedVecEnv(env, cfg.action_guard, layout=layout)
    if cfg.residual_on is not None:  # the agent's set-points plus the learner's (outside the guard: it filters the sum)
        from .residual import ResidualVecEnv

        env = ResidualVecEnv(env, cfg.residual_on, layout=layout)
    if cfg.policy == "CentralCriticPolicy":  # MAPPO: every row gets its formation's agent-specific global state
        from .central_critic import GlobalStateVecEnv

        env = GlobalStateVecEnv(env, env.batch.agents_per_formation)
    if cfg.reward_scale == 1.0:
        return env
    from .reward_scale import ScaleReward

    return ScaleReward(env, cfg.reward_scale)



def steps_to_run(model, asked: int) -> tuple[int, str]:
    """How many environment steps ``model.learn(asked)`` will take, and why it differs: SB3 stops only between
    whole rollouts (on-policy: ``n_steps`` per env index) or whole vector steps (one per env index)."""
    n_envs = int(model.n_envs)
    if hasattr(model, "n_steps"):  # PPO / A2C collect whole rollouts
        chunk = int(model.n_steps) * n_envs
        why = f"{type(model).__name__} collects whole rollouts of {model.n_steps} steps x {n_envs} env indices = {chunk}"
    else:
        chunk = n_envs
        why = f"the {n_envs} env indices step together"
    return -(-asked // chunk) * chunk, why

def train(*, scenario: str | None = None, algo: str | None = None, action_mode: str | None = None, seed: int = 0,
          steps: int | None = None, config_file: str | Path | None = None, out_dir: str | Path | None = None,
          overwrite: bool = False, resume: bool = False, progress_bar: bool | None = None,
          overrides: dict | None = None, log: Callable[[str], None] | None = None, command: str | None = None) -> dict:
    """Train (or resume) one run; returns its summary. ``action_mode`` None: the task's (its benchmark
    configuration's; set-points where no task poses the scenario). ``overrides``: hyperparameters merged last
    (a dict in the YAML format, used by the tests for tiny runs)."""
    import torch
    import yaml

    from formation_env.io import prepare_output_dir

    log = log or (lambda msg: print(msg, flush=True))
    if steps is not None and (isinstance(steps, bool) or not isinstance(steps, int) or steps <= 0):
        raise ValueError(f"steps must be a positive integer, got {steps!r}")
    if resume:
        if out_dir is None:
            raise ValueError("--resume needs --out RUN_DIR (the run to continue)")
        run_dir = Path(out_dir)
        if not (run_dir / "config.yaml").is_file():
            raise ValueError(f"cannot resume: {str(run_dir)!r} holds no config.yaml (not a training run directory)")
        saved = yaml.safe_load((run_dir / "config.yaml").read_text())
        if saved.get("backend") == "rllib":
            raise ValueError(f"{str(run_dir)!r} is an RLlib run: resume it with --backend rllib")
        cfg = TrainConfig.from_dict(saved["config"])
        for name, given in (("scenario", scenario), ("algo", algo)):
            if given is not None and given != getattr(cfg, name):
                raise ValueError(f"--resume: {name} {given!r} differs from the run's {getattr(cfg, name)!r}")
        if steps is not None:
            cfg.n_timesteps = steps
        ck = latest_checkpoint(run_dir)
        if ck is None:
            raise ValueError(f"cannot resume: no checkpoint in {str(run_dir / 'checkpoints')!r}")
    else:
        if scenario is None or algo is None:
            raise ValueError("give --scenario and --algo")
        if action_mode is None:
            action_mode = default_action_mode(scenario)
        params = load_hyperparams(algo, scenario, config_file)
        if overrides:
            params = merge_config(params, overrides)
        cfg = TrainConfig.from_hyperparams(params, scenario=scenario, algo=algo, action_mode=action_mode, seed=seed,
                                           n_timesteps=steps)
        run_dir = Path(out_dir) if out_dir is not None else default_run_dir(scenario, algo, action_mode, seed)
        run_dir = prepare_output_dir(run_dir, overwrite=overwrite)
        write_text_atomic(run_dir / "config.yaml", yaml.safe_dump(
            {"command": command, "config": cfg.to_dict()}, sort_keys=False))
        ck = None

    torch.set_num_threads(cfg.torch_threads)
    if progress_bar is None:
        progress_bar = progress_bar_available() and sys.stderr.isatty()
    elif progress_bar and not progress_bar_available():
        log("progress bar needs tqdm and rich; using the plain progress log")
        progress_bar = False

    state = {"curve": [], "evaluations": [], "best_score": None, "best_steps": None, "start_steps": 0,
             "total": cfg.n_timesteps}
    if ck is None:
        env = make_train_env(cfg, cfg.seed)
        model = build_model(cfg, env)
        log_dir = run_dir / "logs"
    else:
        path, ck_steps = ck
        if ck_steps >= cfg.n_timesteps:
            raise ValueError(f"the run is already at {ck_steps} steps (>= --steps {cfg.n_timesteps}); give a larger --steps")
        reseed = int(np.random.SeedSequence([cfg.seed, ck_steps]).generate_state(1)[0])
        env = make_train_env(cfg, reseed)
        model = _algo_class(cfg.algo).load(str(path), env=env, device="cpu")
        model.set_random_seed(reseed)
        buf = path.parent / "replay_buffer.pkl"
        if hasattr(model, "load_replay_buffer") and buf.is_file():
            model.load_replay_buffer(str(buf))
        st_path = run_dir / "checkpoint_state.json"
        st = json.loads(st_path.read_text()) if st_path.is_file() else {}
        if (run_dir / "curve.csv").is_file():
            with (run_dir / "curve.csv").open() as fh:
                rows = [(int(a), float(b), int(c)) for a, b, c in list(csv.reader(fh))[1:]]
            state["curve"] = [r for r in rows if r[0] <= ck_steps]
        if (run_dir / "evaluations.json").is_file():
            state["evaluations"] = [e for e in json.loads((run_dir / "evaluations.json").read_text())
                                    if e["num_timesteps"] <= ck_steps]
        state["best_score"], state["best_steps"] = st.get("best_score"), st.get("best_steps")
        state["start_steps"] = ck_steps
        log(f"resuming {run_dir} from {path.name} ({ck_steps} steps) to {cfg.n_timesteps}")
        log_dir = run_dir / "logs" / f"resume-{ck_steps}"
        n = 1
        while log_dir.exists():
            log_dir = run_dir / "logs" / f"resume-{ck_steps}-{n}"
            n += 1

    from stable_baselines3.common.logger import configure

    formats = ["csv"] + (["tensorboard"] if tensorboard_available() else [])
    model.set_logger(configure(str(log_dir), formats))
    asked = cfg.n_timesteps - state["start_steps"]
    runs, why = steps_to_run(model, asked)
    state["total"] = state["start_steps"] + runs  # what the progress log counts towards
    callbacks, _ = build_callbacks(cfg, run_dir, state, log, progress_bar)
    log(f"training {cfg.algo} on {cfg.scenario} ({cfg.action_mode} actions), seed {cfg.seed}, {cfg.n_formations} "
        f"formations -> {run_dir}")
    log(f"steps: {asked} asked for, {runs} will run" + ("" if runs == asked else f" ({why})"))
    t0 = time.perf_counter()
    model.learn(total_timesteps=cfg.n_timesteps - state["start_steps"], callback=callbacks,
                reset_num_timesteps=ck is None, progress_bar=progress_bar)
    wall = time.perf_counter() - t0
    save_model_atomic(model, run_dir / "final_model.zip")
    write_text_atomic(run_dir / "final_model.json", json.dumps(run_metadata(cfg, model.num_timesteps), indent=2) + "\n")
    if cfg.checkpoint_freq:
        save_checkpoint(model, run_dir, state)
    write_curve(run_dir, state["curve"])
    if state["evaluations"]:
        write_text_atomic(run_dir / "evaluations.json", json.dumps(state["evaluations"], indent=2) + "\n")
    summary = {"run_dir": str(run_dir), "algo": cfg.algo, "scenario": cfg.scenario, "action_mode": cfg.action_mode,
               "seed": cfg.seed, "num_timesteps": int(model.num_timesteps), "resumed_from": state["start_steps"] or None,
               "wall_s": round(wall, 1), "steps_per_s": round((model.num_timesteps - state["start_steps"]) / max(wall, 1e-9), 1),
               "best_score": state["best_score"], "best_steps": state["best_steps"], "episodes": len(state["curve"]),
               "torch_threads": cfg.torch_threads, "tensorboard": tensorboard_available()}
    name = "summary.json" if ck is None else f"summary-resume-{state['start_steps']}.json"
    write_text_atomic(run_dir / name, json.dumps(summary, indent=2) + "\n")
    log(f"done in {wall:.0f} s: {summary['num_timesteps']} steps, best validation score {state['best_score']} "
        f"at {state['best_steps']} -> {run_dir}")
    return summary
