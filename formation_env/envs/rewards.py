"""Distances the rewards and evaluations measure (the reward itself is compiled in
:func:`formation_env.sim.observe.reward_formation`; its readable numpy definition is in tests/oracles)."""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["slot_error_m", "min_separation_m", "huber"]


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


def huber(x):
    """h(x) = x^2 / 2 for |x| <= 1, |x| - 1/2 beyond: quadratic near zero, linear far, never flat."""
    ax = np.abs(x)
    return np.where(ax <= 1.0, 0.5 * ax * ax, ax - 0.5)
