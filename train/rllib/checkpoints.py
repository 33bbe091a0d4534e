"""RLlib checkpoints of a run directory: the metadata ``formation-env evaluate`` needs, finding the
latest one, and writing one atomically. Ray is imported only inside functions."""

from __future__ import annotations

import json
import os
import re
import tempfile
from pathlib import Path

from formation_env.sim.layout import ObservationLayout

from ..config import env_config_for
from .config import RLlibTrainConfig

__all__ = ["checkpoint_metadata", "latest_rllib_checkpoint", "is_rllib_checkpoint", "CHECKPOINT_META"]

CHECKPOINT_META = "formation_env.json"
_CKPT = re.compile(r"^iter_(\d+)$")


def checkpoint_metadata(cfg: RLlibTrainConfig, *, iteration: int, env_steps: int) -> dict:
    """What ``formation-env evaluate`` needs to fly a checkpoint (stored beside RLlib's own files)."""
    import ray

    env = env_config_for(cfg.scenario, cfg.action_mode, cfg.env_kwargs, learning=cfg.learning)
    return {"backend": "rllib", "algo": "ppo", "scenario": cfg.scenario, "action_mode": cfg.action_mode,
            "learning": cfg.learning, "policies": cfg.policies, "modules": cfg.modules, "control_hz": env.control_hz,
            "seed": cfg.seed, "iteration": int(iteration), "env_steps": int(env_steps), "ray_version": ray.__version__,
            "observation": ObservationLayout.for_config(env).to_dict()}


def latest_rllib_checkpoint(run_dir: str | Path) -> tuple[Path, int] | None:
    ckdir = Path(run_dir) / "checkpoints"
    if not ckdir.is_dir():
        return None
    found = [(int(m.group(1)), p) for p in ckdir.iterdir() if (m := _CKPT.match(p.name)) and p.is_dir()]
    if not found:
        return None
    it, path = max(found)
    return path, it


def is_rllib_checkpoint(path: str | Path) -> bool:
    """An RLlib checkpoint directory written by this backend, or a run directory holding one."""
    p = Path(path)
    return (p / CHECKPOINT_META).is_file() or (p.is_dir() and latest_rllib_checkpoint(p) is not None)


def _save_checkpoint(algo, cfg: RLlibTrainConfig, run_dir: Path, env_steps: int) -> Path:
    """``algo.save_to_path`` into a temporary directory beside the final one, then rename: a reader
    never sees half a checkpoint, and an existing checkpoint is never replaced."""
    ckdir = run_dir / "checkpoints"
    ckdir.mkdir(parents=True, exist_ok=True)
    final = ckdir / f"iter_{algo.iteration:06d}"
    if final.exists():
        raise FileExistsError(f"checkpoint {str(final)!r} exists already; not overwriting it")
    tmp = Path(tempfile.mkdtemp(prefix=f".{final.name}.", dir=ckdir))
    try:
        algo.save_to_path(str(tmp.resolve()))  # RLlib takes a path without a scheme for a URI unless absolute
        meta = checkpoint_metadata(cfg, iteration=algo.iteration, env_steps=env_steps)
        (tmp / CHECKPOINT_META).write_text(json.dumps(meta, indent=2) + "\n")
        os.chmod(tmp, 0o755)
        os.replace(tmp, final)
    finally:
        if tmp.exists():
            import shutil

            shutil.rmtree(tmp, ignore_errors=True)
    return final
