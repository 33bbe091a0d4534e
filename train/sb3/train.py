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
import io
import json
import math
import re
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .config import MIN_VALIDATION_EPISODES, VALIDATION_SEED_BASE, TrainConfig, load_hyperparams, make_env_config

__all__ = ["train", "default_run_dir", "latest_checkpoint", "progress_bar_available", "build_model"]

_CKPT = re.compile(r"model_(\d+)_steps\.zip$")


def progress_bar_available() -> bool:
    return all(importlib.util.find_spec(m) is not None for m in ("tqdm", "rich"))


def tensorboard_available() -> bool:
    return importlib.util.find_spec("tensorboard") is not None


def default_run_dir(scenario: str, algo: str, action_mode: str, seed: int, root: str | Path = "runs") -> Path:
    stamp = time.strftime("%Y%m%d-%H%M%S")
    return Path(root) / f"{scenario}-{algo}-{action_mode}-seed{seed}-{stamp}"


def save_model_atomic(model, path: Path) -> Path:
    """``model.save`` to a temporary name in the same directory, then rename into place (the run's
    own files are replaced: checkpoints and final/best models belong to this run)."""
    from formation_env.io import atomic_write

    return atomic_write(path, lambda tmp: model.save(str(tmp)), overwrite=True)


def _save_buffer_atomic(model, path: Path) -> None:
    from formation_env.io import atomic_write

    atomic_write(path, lambda tmp: model.save_replay_buffer(str(tmp)), overwrite=True)


def _write_text_atomic(path: Path, text: str) -> None:
    from formation_env.io import atomic_write_text

    atomic_write_text(path, text, overwrite=True)


def latest_checkpoint(run_dir: str | Path) -> tuple[Path, int] | None:
    ckdir = Path(run_dir) / "checkpoints"
    if not ckdir.is_dir():
        return None
    found = [(int(m.group(1)), p) for p in ckdir.iterdir() if (m := _CKPT.match(p.name))]
    if not found:
        return None
    steps, path = max(found)
    return path, steps


def _algo_class(algo: str):
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
    if cfg.algo in ("sac", "td3"):
        noise = kw.pop("action_noise", None)
        if noise:
            from stable_baselines3.common.noise import NormalActionNoise, VectorizedActionNoise

            base = NormalActionNoise(np.zeros(4), float(noise) * np.ones(4))
            kw["action_noise"] = VectorizedActionNoise(base, env.num_envs) if env.num_envs > 1 else base
    return cls(cfg.policy, env, policy_kwargs=_policy_kwargs(cfg), seed=cfg.seed, device="cpu", verbose=0, **kw)


def make_train_env(cfg: TrainConfig, seed: int):
    from stable_baselines3.common.vec_env import VecEnvWrapper

    from formation_env.envs import FormationVecEnv

    env = FormationVecEnv(cfg.n_formations, make_env_config(cfg), seed=seed)
    if cfg.reward_scale == 1.0:
        return env

    class ScaleReward(VecEnvWrapper):
        """Multiplies the learner's rewards by ``reward_scale`` (infos['episode'] stays unscaled)."""

        def reset(self):
            return self.venv.reset()

        def step_wait(self):
            obs, rew, done, infos = self.venv.step_wait()
            return obs, rew * cfg.reward_scale, done, infos

    return ScaleReward(env)


def _meta(cfg: TrainConfig, steps: int, extra: dict | None = None) -> dict:
    env = make_env_config(cfg)
    d = {"algo": cfg.algo, "scenario": cfg.scenario, "action_mode": cfg.action_mode, "control_hz": env.control_hz,
         "seed": cfg.seed, "num_timesteps": int(steps)}
    if extra:
        d.update(extra)
    return d


def _callbacks(cfg: TrainConfig, run_dir: Path, state: dict, log: Callable[[str], None], progress_bar: bool):
    from stable_baselines3.common.callbacks import BaseCallback

    from .eval_episodes import eval_env_config, run_episodes
    from .eval_summary import selection_score, summarise

    class Curve(BaseCallback):
        """Records every finished training episode (from infos['episode']) for curve.csv."""

        def _on_step(self) -> bool:
            for info in self.locals.get("infos", ()):
                ep = info.get("episode")
                if ep is not None:
                    state["curve"].append((int(self.num_timesteps), round(float(ep["r"]), 6), int(ep["l"])))
            return True

    class Checkpoint(BaseCallback):
        def __init__(self):
            super().__init__()
            self.next = (state["start_steps"] // cfg.checkpoint_freq + 1) * cfg.checkpoint_freq if cfg.checkpoint_freq else None

        def _on_step(self) -> bool:
            if self.next is not None and self.num_timesteps >= self.next:
                self.next += cfg.checkpoint_freq * max(1, math.ceil((self.num_timesteps - self.next + 1) / cfg.checkpoint_freq))
                save_checkpoint(self.model, run_dir, state)
            return True

    class Evaluate(BaseCallback):
        """Validation (model selection) on held-out seeds; keeps the best model (lowest selection score).

        The validation episodes are drawn exactly like the test set of ``formation-env evaluate``: the
        same ``eval_env_config`` with its defaults (wake on, Dryden sigma 1 m/s, no other randomisation,
        the scenario's duration), whatever the training's ``env_kwargs`` (turbulence, wake, initial
        offsets, randomisation) say; only the seeds differ (``VALIDATION_SEED_BASE + i`` vs
        ``TEST_SEED_BASE + i``, both out of the training's range). ``eval_episodes`` of them (32 by
        default). One exception, logged: a run whose ``env_kwargs`` shortens the episodes
        (``duration_s``: quick development runs, the tests) validates on episodes of that length, with
        the same seeds and conditions (like ``formation-env evaluate --duration``)."""

        def __init__(self):
            super().__init__()
            from formation_env.scenarios import get_scenario

            self.next = (state["start_steps"] // cfg.eval_freq + 1) * cfg.eval_freq if cfg.eval_freq else None
            env = make_env_config(cfg)
            full = get_scenario(cfg.scenario).duration_s
            short = env.duration_s if env.duration_s is not None and env.duration_s < full else None
            self.config = eval_env_config(cfg.scenario, cfg.action_mode, control_hz=env.control_hz, duration_s=short)
            self.seeds = [VALIDATION_SEED_BASE + i for i in range(cfg.eval_episodes)]
            if short is not None:
                log(f"note: validation episodes cut to {short:g} s like the training's (the test set flies {full:g} s)")
            if cfg.eval_episodes < MIN_VALIDATION_EPISODES:
                log(f"note: validation on {cfg.eval_episodes} episodes (< {MIN_VALIDATION_EPISODES}): the model "
                    "selection follows noise more than skill")

        def _on_step(self) -> bool:
            if self.next is not None and self.num_timesteps >= self.next:
                self.next += cfg.eval_freq * max(1, math.ceil((self.num_timesteps - self.next + 1) / cfg.eval_freq))
                self.evaluate()
            return True

        def evaluate(self) -> None:
            model = self.model
            summ = summarise(run_episodes(lambda o: model.predict(o, deterministic=True)[0], self.config, self.seeds))
            score = selection_score(summ)
            entry = {"num_timesteps": int(self.num_timesteps), "score": score, **summ}
            state["evaluations"].append(entry)
            for k in ("rms_slot_error_m", "return", "collisions", "reconfig_success_rate", "min_separation_m",
                      "induced_drag_saving", "box_outside_over_1s"):
                if k in summ:
                    self.logger.record(f"eval/{k}", summ[k])
            best = state.get("best_score")
            if best is None or score < best:
                state["best_score"], state["best_steps"] = score, int(self.num_timesteps)
                save_model_atomic(model, run_dir / "best_model.zip")
                _write_text_atomic(run_dir / "best_model.json",
                                   json.dumps(_meta(cfg, self.num_timesteps, {"validation": entry}), indent=2) + "\n")
            _write_text_atomic(run_dir / "evaluations.json", json.dumps(state["evaluations"], indent=2) + "\n")
            log(f"[eval] steps {self.num_timesteps}: RMS slot error {summ['rms_slot_error_m']:.3f} m, "
                f"collisions {summ['collisions']}, crashes {summ['crashes']}"
                + (f", reconfig success {summ['reconfig_success_rate']:.2f}" if "reconfig_success_rate" in summ else "")
                + (f", saving {summ['induced_drag_saving']:.3f}, >1 s outside the box {summ['box_outside_over_1s']}"
                   if "box_outside_over_1s" in summ else "")
                + f", score {score:.3f} (best {state['best_score']:.3f} at {state['best_steps']})")

    class Progress(BaseCallback):
        """A plain progress line (when tqdm/rich are missing or the bar is off)."""

        def __init__(self):
            super().__init__()
            self.every = max(1, (state["total"] - state["start_steps"]) // 20)
            self.next = state["start_steps"] + self.every
            self.t0 = time.perf_counter()

        def _on_step(self) -> bool:
            if self.num_timesteps >= self.next:
                self.next += self.every
                recent = [r for _, r, _ in state["curve"][-50:]]
                rate = (self.num_timesteps - state["start_steps"]) / max(time.perf_counter() - self.t0, 1e-9)
                log(f"steps {self.num_timesteps}/{state['total']} ({rate:.0f}/s)"
                    + (f", mean return (last {len(recent)} episodes) {np.mean(recent):.1f}" if recent else ""))
            return True

    cbs = [Curve(), Checkpoint()]
    ev = Evaluate() if cfg.eval_freq else None
    if ev is not None:
        cbs.append(ev)
    if not progress_bar:
        cbs.append(Progress())
    return cbs, ev


def _write_curve(run_dir: Path, rows) -> None:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["num_timesteps", "episode_return", "episode_length"])
    w.writerows(rows)
    _write_text_atomic(run_dir / "curve.csv", buf.getvalue())


def save_checkpoint(model, run_dir: Path, state: dict) -> Path:
    ckdir = run_dir / "checkpoints"
    path = save_model_atomic(model, ckdir / f"model_{model.num_timesteps}_steps.zip")
    if hasattr(model, "replay_buffer") and model.replay_buffer is not None:
        buf = ckdir / "replay_buffer.pkl"
        _save_buffer_atomic(model, buf)
    _write_curve(run_dir, state["curve"])
    state["last_checkpoint"] = int(model.num_timesteps)
    _write_text_atomic(run_dir / "checkpoint_state.json",
                       json.dumps({"num_timesteps": int(model.num_timesteps), "best_score": state.get("best_score"),
                                   "best_steps": state.get("best_steps"), "n_curve_rows": len(state["curve"]),
                                   "n_evaluations": len(state["evaluations"])}, indent=2) + "\n")
    return path


def train(*, scenario: str | None = None, algo: str | None = None, action_mode: str = "residual", seed: int = 0,
          steps: int | None = None, config_file: str | Path | None = None, out_dir: str | Path | None = None,
          overwrite: bool = False, resume: bool = False, progress_bar: bool | None = None,
          overrides: dict | None = None, log: Callable[[str], None] | None = None, command: str | None = None) -> dict:
    """Train (or resume) one run; returns its summary. ``overrides``: hyperparameters merged last
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
        params = load_hyperparams(algo, scenario, config_file)
        if overrides:
            from .config import _merge

            params = _merge(params, overrides)
        cfg = TrainConfig.from_hyperparams(params, scenario=scenario, algo=algo, action_mode=action_mode, seed=seed,
                                           n_timesteps=steps)
        run_dir = Path(out_dir) if out_dir is not None else default_run_dir(scenario, algo, action_mode, seed)
        run_dir = prepare_output_dir(run_dir, overwrite=overwrite)
        _write_text_atomic(run_dir / "config.yaml", yaml.safe_dump(
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
    callbacks, _ = _callbacks(cfg, run_dir, state, log, progress_bar)
    log(f"training {cfg.algo} on {cfg.scenario} ({cfg.action_mode} actions), seed {cfg.seed}, {cfg.n_timesteps} steps, "
        f"{cfg.n_formations} formations -> {run_dir}")
    t0 = time.perf_counter()
    model.learn(total_timesteps=cfg.n_timesteps - state["start_steps"], callback=callbacks,
                reset_num_timesteps=ck is None, progress_bar=progress_bar)
    wall = time.perf_counter() - t0
    save_model_atomic(model, run_dir / "final_model.zip")
    _write_text_atomic(run_dir / "final_model.json", json.dumps(_meta(cfg, model.num_timesteps), indent=2) + "\n")
    if cfg.checkpoint_freq:
        save_checkpoint(model, run_dir, state)
    _write_curve(run_dir, state["curve"])
    if state["evaluations"]:
        _write_text_atomic(run_dir / "evaluations.json", json.dumps(state["evaluations"], indent=2) + "\n")
    summary = {"run_dir": str(run_dir), "algo": cfg.algo, "scenario": cfg.scenario, "action_mode": cfg.action_mode,
               "seed": cfg.seed, "num_timesteps": int(model.num_timesteps), "resumed_from": state["start_steps"] or None,
               "wall_s": round(wall, 1), "steps_per_s": round((model.num_timesteps - state["start_steps"]) / max(wall, 1e-9), 1),
               "best_score": state["best_score"], "best_steps": state["best_steps"], "episodes": len(state["curve"]),
               "torch_threads": cfg.torch_threads, "tensorboard": tensorboard_available()}
    name = "summary.json" if ck is None else f"summary-resume-{state['start_steps']}.json"
    _write_text_atomic(run_dir / name, json.dumps(summary, indent=2) + "\n")
    log(f"done in {wall:.0f} s: {summary['num_timesteps']} steps, best validation score {state['best_score']} "
        f"at {state['best_steps']} -> {run_dir}")
    return summary
