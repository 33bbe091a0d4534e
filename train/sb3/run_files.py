"""The files of an SB3 run directory (layout: :mod:`train.sb3.train`): models and checkpoints written
atomically, the learning curve, the checkpoint state and the models' metadata sidecars."""

from __future__ import annotations

import csv
import io
import json
import re
from pathlib import Path

from formation_env.sim.layout import ObservationLayout

from ..config import task_stamp
from .config import TrainConfig, make_env_config

__all__ = ["save_model_atomic", "save_buffer_atomic", "write_text_atomic", "latest_checkpoint", "run_metadata",
           "write_curve", "save_checkpoint"]

_CKPT = re.compile(r"model_(\d+)_steps\.zip$")


def save_model_atomic(model, path: Path) -> Path:
    """``model.save`` to a temporary name in the same directory, then rename into place (the run's
    own files are replaced: checkpoints and final/best models belong to this run)."""
    from formation_env.io import atomic_write

    return atomic_write(path, lambda tmp: model.save(str(tmp)), overwrite=True)


def save_buffer_atomic(model, path: Path) -> None:
    from formation_env.io import atomic_write

    atomic_write(path, lambda tmp: model.save_replay_buffer(str(tmp)), overwrite=True)


def write_text_atomic(path: Path, text: str) -> None:
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


def run_metadata(cfg: TrainConfig, steps: int, extra: dict | None = None) -> dict:
    """The metadata sidecar (``NAME.json``) of a model saved at ``steps``."""
    env = make_env_config(cfg)
    d = {"algo": cfg.algo, "scenario": cfg.scenario, "action_mode": cfg.action_mode, "control_hz": env.control_hz,
         "seed": cfg.seed, "num_timesteps": int(steps)}
    if cfg.action_guard:
        d["action_guard"] = cfg.action_guard  # True, or the guard's gains
    d["observation"] = ObservationLayout.for_config(env).to_dict()  # the groups the policy must be flown with
    if cfg.residual_on is not None:
        d["residual_on"] = cfg.residual_on  # the agent the learner's actions are added to, and their scale
    d.update(task_stamp(cfg.scenario, cfg.env_kwargs, cfg.action_mode))
    if extra:
        d.update(extra)
    return d


def write_curve(run_dir: Path, rows) -> None:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["num_timesteps", "episode_return", "episode_length"])
    w.writerows(rows)
    write_text_atomic(run_dir / "curve.csv", buf.getvalue())


def save_checkpoint(model, run_dir: Path, state: dict) -> Path:
    ckdir = run_dir / "checkpoints"
    path = save_model_atomic(model, ckdir / f"model_{model.num_timesteps}_steps.zip")
    if hasattr(model, "replay_buffer") and model.replay_buffer is not None:
        buf = ckdir / "replay_buffer.pkl"
        save_buffer_atomic(model, buf)
    write_curve(run_dir, state["curve"])
    state["last_checkpoint"] = int(model.num_timesteps)
    write_text_atomic(run_dir / "checkpoint_state.json",
                       json.dumps({"num_timesteps": int(model.num_timesteps), "best_score": state.get("best_score"),
                                   "best_steps": state.get("best_steps"), "n_curve_rows": len(state["curve"]),
                                   "n_evaluations": len(state["evaluations"])}, indent=2) + "\n")
    return path
