"""Per-agent rewards and episode-ending events (see :class:`formation_env.envs.config.RewardWeights`)."""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from .config import RewardWeights

__all__ = ["slot_error_m", "min_separation_m", "reward_terms"]


def slot_error_m(state: np.ndarray, position_demand: np.ndarray) -> np.ndarray:
    """(B, V) distance of each UAV's CG from its slot (demanded position), m."""
    return np.linalg.norm(state[..., 10:13] - position_demand, axis=-1)


def min_separation_m(state: np.ndarray) -> np.ndarray:
    """(B, V) distance from each UAV to its nearest neighbour (inf when flying alone), m."""
    out = np.empty(state.shape[:2])
    _min_separation(np.ascontiguousarray(state), out)
    return out


@nb.njit(cache=True, error_model="numpy")
def _min_separation(state, out):
    for b in range(state.shape[0]):
        for i in range(state.shape[1]):
            best = np.inf
            for j in range(state.shape[1]):
                if j != i:
                    d = math.sqrt((state[b, i, 10] - state[b, j, 10]) ** 2 + (state[b, i, 11] - state[b, j, 11]) ** 2
                                  + (state[b, i, 12] - state[b, j, 12]) ** 2)
                    if d < best or d != d:
                        best = d
            out[b, i] = best


def reward_terms(w: RewardWeights, error, previous_error, action, previous_action, saving, collided, crashed) -> dict:
    """Reward components (B, V) and their sum under ``"total"``. Non-finite inputs count as a crash."""
    with np.errstate(all="ignore"):
        err = np.where(np.isfinite(error), error, 1e6)  # a diverged UAV counts as far from its slot
        prev = np.where(np.isfinite(previous_error), previous_error, 1e6)
        terms = {
            "slot": -w.slot * np.minimum(err / w.slot_scale_m, 5.0),
            "effort": -w.effort * np.sum(action * action, axis=-1) / 4.0,
            "rate": -w.rate * np.sum((action - previous_action) ** 2, axis=-1) / 4.0,
            "benefit": w.benefit * np.where(np.isfinite(saving), saving, 0.0),
            "progress": w.progress * np.clip((prev - err) / w.slot_scale_m, -1.0, 1.0),
            "collision": -w.collision * collided.astype(float),
            "crash": -w.crash * crashed.astype(float),
        }
    terms["total"] = sum(terms.values())
    return terms
