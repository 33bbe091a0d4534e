"""Distances the rewards and evaluations measure (the reward itself is compiled in
:func:`formation_env.sim.observe.reward_formation`; its readable numpy definition is in tests/oracles)."""

from __future__ import annotations

import numpy as np

from ..aircraft.state import POS
from ..sim.kernels import min_separation_each

__all__ = ["slot_error_m", "min_separation_m", "huber"]


def slot_error_m(state: np.ndarray, position_demand: np.ndarray) -> np.ndarray:
    """(B, V) distance of each UAV's CG from its slot (demanded position), m."""
    return np.linalg.norm(state[..., POS] - position_demand, axis=-1)


def min_separation_m(state: np.ndarray) -> np.ndarray:
    """(B, V) distance from each UAV to its nearest neighbour (inf when flying alone), m: the decision step's own
    kernel (:func:`formation_env.sim.kernels.min_separation_each`) per formation."""
    x = np.ascontiguousarray(state, dtype=float)
    out = np.empty(x.shape[:2])
    for b in range(x.shape[0]):
        min_separation_each(x[b], out[b])
    return out


def huber(x):
    """h(x) = x^2 / 2 for |x| <= 1, |x| - 1/2 beyond: quadratic near zero, linear far, never flat."""
    ax = np.abs(x)
    return np.where(ax <= 1.0, 0.5 * ax * ax, ax - 0.5)
