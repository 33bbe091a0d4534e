"""Per-agent rewards and episode-ending events (see :class:`formation_env.envs.config.RewardWeights`)."""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from .config import RewardWeights

__all__ = ["slot_error_m", "min_separation_m", "reward_terms", "huber"]


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


_ERROR_CAP_M = 5000.0
_TERMINAL_ERROR_CAP_M = 100.0


def huber(x):
    """h(x) = x^2 / 2 for |x| <= 1, |x| - 1/2 beyond: quadratic near zero, linear far, never flat."""
    ax = np.abs(x)
    return np.where(ax <= 1.0, 0.5 * ax * ax, ax - 0.5)


def reward_terms(w: RewardWeights, error, previous_error, action, previous_action, saving, separation, collided,
                 crashed, collision_separation_m: float, span_m: float, remaining_decisions=0) -> dict:
    """Reward components (B, V) and their sum under ``"total"`` (see :class:`RewardWeights`).

    error, previous_error: distance from the slot now and at the previous decision (m); separation:
    distance to the nearest other UAV (m, inf alone); remaining_decisions (B,): decisions left until
    the time limit. Non-finite inputs count as a crash: a diverged UAV is treated as 5 km from its slot.

    A collision or crash ends the episode, which would also end the slot costs still to come: with
    costs per decision, ending early could pay. So the terminal penalty also charges the slot cost
    at the error the UAV had before the end (at most 100 m) for every decision left: ending an
    episode is never cheaper than flying on where the UAV is."""
    with np.errstate(all="ignore"):
        # 5 km is beyond any distance a UAV can reach in an episode (25 m/s for minutes): the cap only
        # bounds the reward of a diverged (non-finite) UAV, whose episode ends with the crash penalty
        err = np.where(np.isfinite(error), np.minimum(error, _ERROR_CAP_M), _ERROR_CAP_M)
        prev = np.where(np.isfinite(previous_error), np.minimum(previous_error, _ERROR_CAP_M), _ERROR_CAP_M)
        cost, cost_prev = huber(err / w.slot_scale_m), huber(prev / w.slot_scale_m)
        d_safe = w.barrier_separation_b * span_m
        sep = np.where(np.isnan(separation), 0.0, separation)
        depth = np.clip((d_safe - sep) / max(d_safe - collision_separation_m, 1e-9), 0.0, 1.0)
        remaining = np.asarray(remaining_decisions, dtype=float)
        remaining = remaining[:, None] if remaining.ndim == 1 else remaining
        forfeit = w.terminal_forfeit * w.slot * huber(np.minimum(prev, _TERMINAL_ERROR_CAP_M) / w.slot_scale_m) * remaining
        terms = {
            "slot": -w.slot * cost,
            "progress": w.progress * (cost_prev - w.shaping_gamma * cost),  # gamma * Phi(s') - Phi(s), Phi = -cost
            "separation": -w.separation * depth * depth,
            "effort": -w.effort * np.sum(action * action, axis=-1) / 4.0,
            "rate": -w.rate * np.sum((action - previous_action) ** 2, axis=-1) / 4.0,
            "benefit": w.benefit * np.where(np.isfinite(saving), saving, 0.0),
            "collision": -(w.collision + forfeit) * collided.astype(float),
            "crash": -(w.crash + forfeit) * crashed.astype(float),
        }
    terms["total"] = sum(terms.values())
    return terms
