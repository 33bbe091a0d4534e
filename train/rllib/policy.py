"""Inference: an RLlib checkpoint of this project as an :class:`~train.evaluation.policy.EvalPolicy`."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from formation_env.sim.layout import ObservationLayout

from ..evaluation.policy import EvalPolicy
from .checkpoints import CHECKPOINT_META, latest_rllib_checkpoint
from .cluster import require_rllib

__all__ = ["load_rllib_policy"]


def load_rllib_policy(spec: str | Path, *, name: str | None = None, module_id: str | None = None):
    """An ``EvalPolicy`` flying the follower (or shared) RLModule of an RLlib checkpoint written by
    this backend; ``spec`` may also be a run directory (its latest checkpoint). Deterministic: the mean
    of the Gaussian, clipped to the [-1, 1] action box (RLlib's unsquashing is the identity on it)."""
    require_rllib()
    import torch
    from ray.rllib.core.rl_module.rl_module import RLModule

    path = Path(spec)
    if not (path / CHECKPOINT_META).is_file():
        ck = latest_rllib_checkpoint(path) if path.is_dir() else None
        if ck is None:
            raise ValueError(f"{str(spec)!r} is not an RLlib checkpoint of this project (no {CHECKPOINT_META}) nor a "
                             "run directory holding one")
        path = ck[0]
    meta = json.loads((path / CHECKPOINT_META).read_text())
    modules = meta["modules"]
    module_id = module_id or ("follower" if "follower" in modules else "shared")
    if module_id not in modules:
        raise ValueError(f"checkpoint {str(path)!r} has no module {module_id!r}; it has {modules}")
    module = RLModule.from_checkpoint(str((path / "learner_group" / "learner" / "rl_module" / module_id).resolve()))
    dist_cls = module.get_inference_action_dist_cls()
    obs_size = int(np.prod(module.observation_space.shape))

    def act(obs: np.ndarray) -> np.ndarray:
        obs = np.asarray(obs)
        if obs.ndim != 2 or obs.shape[1] != obs_size:
            raise ValueError(f"RLlib policy {str(path)!r} (trained on {meta['scenario']!r}) takes observations of "
                             f"size {obs_size}; got shape {obs.shape} (a scenario with another number of UAVs?)")
        x = torch.from_numpy(np.ascontiguousarray(obs, dtype=np.float32))
        with torch.no_grad():
            out = module.forward_inference({"obs": x})
            a = dist_cls.from_logits(out["action_dist_inputs"]).to_deterministic().sample()
        return np.clip(a.numpy(), -1.0, 1.0)

    run_name = path.resolve().parent.parent.name
    label = name or f"{'' if 'rllib' in run_name else 'rllib-'}{run_name}-{path.name}"
    return EvalPolicy(label, meta["action_mode"], act, float(meta.get("control_hz", 10.0)), str(path),
                      observation=ObservationLayout.from_dict(meta.get("observation"), meta))
