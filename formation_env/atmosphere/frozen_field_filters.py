"""The lanes of the frozen turbulence field (see :mod:`.frozen_field`): parameters and state, and the
compiled filter steps that advance every lane's unit-variance Dryden process and write it into the
ring buffer of past values.

Lane discretisation as :mod:`.dryden`: u first order, v and w second order (exact for the step),
time constant L_k / V_air, stationary start.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np

from .dryden import _first_order, _second_order
from .frozen_field_rng import N_STREAMS_PER_LANE, _lane_normals

__all__ = ["FrozenFieldParams", "FrozenFieldState", "frozen_field_params", "advance_kernel", "advance_field_one",
           "reset_kernel"]

_jit = nb.njit(cache=True, error_model="numpy")


class FrozenFieldParams(NamedTuple):
    """Field parameters (build with :func:`frozen_field_params`). Component order u, v, w
    (along-track, cross-track starboard, down)."""

    sigma_mps: np.ndarray  # (3,) RMS of each component, m/s
    length_scale_m: np.ndarray  # (3,) Dryden scale lengths L_u, L_v, L_w, m
    airspeed_mps: float  # nominal airspeed V_air (Taylor transport speed and filter T = L / V), m/s
    dt_s: float  # step, s
    buffer_steps: int  # longest transport delay kept, in steps (ring holds buffer_steps + 1 samples)
    step_length_m: float  # V_air * dt_s: air distance per step, m
    a_u: float  # u lane (first order, unit variance): x <- a_u x + g_u n
    g_u: float
    ad_vw: np.ndarray  # (2, 2, 2) [axis v|w]: exact state transition of the second-order filter
    gd_vw: np.ndarray  # (2, 2, 2) lower-triangular gain of the discrete noise covariance
    c_vw: np.ndarray  # (2, 2) output row (unit stationary variance)
    p0_vw: np.ndarray  # (2, 2, 2) Cholesky factor of the stationary state covariance


class FrozenFieldState(NamedTuple):
    """Field state of B formations of V aircraft (build with :func:`frozen_field_init`); all
    arrays are updated in place by the kernels."""

    key: np.ndarray  # (B,) uint64 random key of each formation (from its seed)
    step: np.ndarray  # (B,) int64 filter updates drawn since reset: the counter of the generator
    head: np.ndarray  # (B,) int64 ring slot of the current lane values
    x_u: np.ndarray  # (B, V) float64 u-lane filter states (= the unit-variance lane values)
    x_vw: np.ndarray  # (B, 2, V, 2) float64 v- and w-lane second-order filter states
    ring: np.ndarray  # (B, buffer_steps + 1, 3, V) float64 past unit-variance lane values [u, v, w]


def _vec3(name: str, value) -> np.ndarray:
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim == 0:
        arr = np.full(3, float(arr))
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be 3 finite numbers (or one), got {value!r}")
    return arr.copy()


def _positive(name: str, value) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{name} must be positive and finite, got {value!r}")
    return v


def frozen_field_params(sigma_mps, length_scale_m, airspeed_mps: float, dt_s: float,
                        buffer_s: float = 4.0) -> FrozenFieldParams:
    """Parameters of the field: sigma (3,) m/s (>= 0; 0 gives exactly zero gusts), scale lengths
    (3,) m (> 0), nominal airspeed m/s (> 0), step s (> 0) and the longest transport delay kept,
    ``buffer_s`` (>= 0, rounded up to whole steps)."""
    sigma = _vec3("sigma_mps", sigma_mps)
    if np.any(sigma < 0.0):
        raise ValueError(f"sigma_mps must be >= 0, got {sigma_mps!r}")
    length = _vec3("length_scale_m", length_scale_m)
    if np.any(length <= 0.0):
        raise ValueError(f"length_scale_m must be positive, got {length_scale_m!r}")
    airspeed = _positive("airspeed_mps", airspeed_mps)
    dt = _positive("dt_s", dt_s)
    buf = float(buffer_s)
    if not (math.isfinite(buf) and buf >= 0.0):
        raise ValueError(f"buffer_s must be >= 0 and finite, got {buffer_s!r}")
    buffer_steps = int(math.ceil(buf / dt - 1e-9))
    a_u, g_u = _first_order(length[0] / airspeed, dt)
    ad = np.empty((2, 2, 2))
    gd = np.empty((2, 2, 2))
    c = np.empty((2, 2))
    p0 = np.empty((2, 2, 2))
    for k in range(2):
        ad[k], gd[k], c[k], p0[k] = _second_order(length[k + 1] / airspeed, dt)
    return FrozenFieldParams(sigma_mps=sigma, length_scale_m=length, airspeed_mps=airspeed, dt_s=dt,
                             buffer_steps=buffer_steps, step_length_m=airspeed * dt, a_u=float(a_u), g_u=float(g_u),
                             ad_vw=ad, gd_vw=gd, c_vw=c, p0_vw=p0)


@_jit
def advance_field_one(params, state, b, n):
    """One filter step (dt) of formation b's lanes, in place: every lane's unit-variance Dryden
    filter advanced with the counter-based normals of the formation's key, the new lane values
    written to the next ring slot (which becomes the head). ``params`` a :class:`FrozenFieldParams`,
    ``state`` a :class:`FrozenFieldState` (B formations of V aircraft), b the formation, n a scratch
    float64 array of N_STREAMS_PER_LANE normals. For compiled callers that fuse the field into
    their own per-formation loops (:func:`advance_kernel` is the batch form)."""
    nveh = state.x_u.shape[1]
    nslot = state.ring.shape[1]
    counter = state.step[b]
    key = state.key[b]
    slot = (state.head[b] + 1) % nslot
    ad, gd, c = params.ad_vw, params.gd_vw, params.c_vw
    for j in range(nveh):
        _lane_normals(key, counter, j, n)
        xu = params.a_u * state.x_u[b, j] + params.g_u * n[0]
        state.x_u[b, j] = xu
        state.ring[b, slot, 0, j] = xu
        for k in range(2):
            x0 = state.x_vw[b, k, j, 0]
            x1 = state.x_vw[b, k, j, 1]
            m0 = n[1 + 2 * k]
            m1 = n[2 + 2 * k]
            y0 = ad[k, 0, 0] * x0 + ad[k, 0, 1] * x1 + gd[k, 0, 0] * m0
            y1 = ad[k, 1, 0] * x0 + ad[k, 1, 1] * x1 + gd[k, 1, 0] * m0 + gd[k, 1, 1] * m1
            state.x_vw[b, k, j, 0] = y0
            state.x_vw[b, k, j, 1] = y1
            state.ring[b, slot, k + 1, j] = c[k, 0] * y0 + c[k, 1] * y1
    state.head[b] = slot
    state.step[b] = counter + 1


@_jit
def reset_kernel(params, state, indices, keys):
    """Restart formations ``indices`` (int64 (n,)) with keys (uint64 (n,)): stationary filter start
    at counter 0, then ``buffer_steps`` filter steps fill the ring, so the buffered past is a
    stationary sample path and the statistics are right from t = 0."""
    nveh = state.x_u.shape[1]
    nslot = state.ring.shape[1]
    p0, c = params.p0_vw, params.c_vw
    n = np.empty(N_STREAMS_PER_LANE)
    for q in range(indices.shape[0]):
        b = indices[q]
        key = keys[q]
        state.key[b] = key
        for j in range(nveh):
            _lane_normals(key, 0, j, n)
            state.x_u[b, j] = n[0]
            state.ring[b, 0, 0, j] = n[0]
            for k in range(2):
                m0 = n[1 + 2 * k]
                m1 = n[2 + 2 * k]
                y0 = p0[k, 0, 0] * m0 + p0[k, 0, 1] * m1
                y1 = p0[k, 1, 0] * m0 + p0[k, 1, 1] * m1
                state.x_vw[b, k, j, 0] = y0
                state.x_vw[b, k, j, 1] = y1
                state.ring[b, 0, k + 1, j] = c[k, 0] * y0 + c[k, 1] * y1
        state.head[b] = 0
        state.step[b] = 1
        for _ in range(nslot - 1):
            advance_field_one(params, state, b, n)


@_jit
def advance_kernel(params, state):
    """Every formation one dt forward."""
    n = np.empty(N_STREAMS_PER_LANE)
    for b in range(state.x_u.shape[0]):
        advance_field_one(params, state, b, n)
