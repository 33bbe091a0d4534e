"""One frozen (Taylor) Dryden turbulence field per formation, batched and compiled with numba.

Method (see docs/aircraft.md, "Frozen turbulence field"):

* **Lanes.** Per formation and per velocity component k (u along-track, v cross-track to starboard,
  w down) there are V independent unit-variance Dryden processes ("lanes", one per aircraft),
  discretised exactly as :mod:`.dryden` does (u: first order, v and w: second order, time constant
  T_k = L_k / V_air, stationary start); the filter coefficients come from ``dryden._first_order`` and
  ``dryden._second_order``.
* **Ring buffer.** The lanes' last ``buffer_steps + 1`` values (current one included) are kept.
* **Reading (Taylor).** Aircraft i reads every lane delayed by its transport delay
  tau_i = (x_front - x_i) / V_air, x the along-track coordinate in the formation's track frame and
  x_front the foremost aircraft's (tau = 0 for it). Fractional delays interpolate linearly between
  buffer samples; delays beyond the buffer are clipped to ``buffer_steps * dt`` (that aircraft then
  reads a field older by less than it should, i.e. is correlated with the leader as if it were
  ``V_air * buffer_steps * dt`` behind: at 25 m/s and 4 s that is 100 m).
* **Mixing.** gust_i,k = sigma_k sum_j L^k_ij lane_j,k(t - tau_i), L^k the lower Cholesky factor of
  the V x V correlation matrix of the aircraft's current cross-track and vertical separations,
  C^u = g(r), C^v = (f - g) dy^2 / r^2 + g, C^w = (f - g) dz^2 / r^2 + g (isotropic R_kk for a
  separation (0, dy, dz), Dryden f(r) = exp(-r/L), g(r) = (1 - r/(2L)) exp(-r/L)). It is recomputed
  at every sample (V <= 5: cheap), so reconfiguring formations are handled. The factorisation clamps
  a non-positive pivot (coincident cross positions, rounding) to zero and renormalises each row to
  unit norm, so it never fails and each aircraft's variance stays sigma^2.
* **Output** in NED, rotated by the track angle chi: north = c u - s v, east = s u + c v, down = w.

Resulting statistics: each aircraft's spectrum is exactly Dryden (its autocorrelation at lag s is
f(V s) for u, g(V s) for v and w); for two aircraft separated by (dx, dy, dz) in the track frame the
covariance of aircraft A at t and B at t + s is sigma_k^2 C^k(dy, dz) rho_k(s + dx / V)
(:func:`frozen_field_theory`). That is exactly the isotropic R_kk of a frozen field at the transport
lag s = -dx / V and for dx = 0, and a frequency-independent-coherence approximation otherwise: at the
thesis slot (-2b, 1b, 0.3b), zero lag, it gives 0.967 / 0.962 / 0.958 against the isotropic
0.977 / 0.970 / 0.968 (u / v / w). Neglected: cross-component covariances (u-v, u-w, v-w), of size
(f - g) r_i r_j / r^2 <= (f - g) / 2 ~ r / (4L) (0.0014 for v-w, 0.004 for u-v at the thesis slot).

Random numbers are counter based: the 64-bit uniform of (formation key, filter-step counter, stream)
is splitmix64 applied twice (key's splitmix sequence at counter + 1, then that value's sequence at
stream + 1); two uniforms give two normals by Box-Muller. Stream 6 j + m, m = 0..5, is lane j's m-th
normal (u filter m = 0; v m = 1, 2; w m = 3, 4; m = 5 unused), independent of V. The key is
``SeedSequence(seed).generate_state(1, dtype=np.uint64)[0]``. There is no Python loop per formation
per step and a formation's field depends only on its seed: batch == single runs bit for bit.

Design: pure functions over arrays with a leading batch axis B, compiled with numba (no prange),
parameters in :class:`FrozenFieldParams`, state in :class:`FrozenFieldState` (arrays only, updated
in place). Call :func:`frozen_field_reset` before sampling (a fresh state gives zero gusts).
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numba as nb
import numpy as np

from .dryden import _first_order, _second_order

__all__ = [
    "FrozenFieldParams",
    "FrozenFieldState",
    "FrozenTurbulenceField",
    "dryden_correlation",
    "formation_key",
    "frozen_field_advance",
    "frozen_field_init",
    "frozen_field_params",
    "frozen_field_reset",
    "frozen_field_rollout",
    "frozen_field_sample",
    "frozen_field_theory",
    "isotropic_correlation",
    "advance_kernel",
    "counter_bits",
    "counter_normal_pair",
    "reset_kernel",
    "rollout_kernel",
    "sample_kernel",
]

_jit = nb.njit(cache=True, error_model="numpy")

N_STREAMS_PER_LANE = 6  # normals drawn per lane per filter step (5 used)
_PIVOT_TOL = 1e-12  # a Cholesky pivot below this (relative to the diagonal) is clamped to zero
_SNAP_TOL = 1e-9  # a delay within this many steps of an integer is read exactly at that integer

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_S11 = np.uint64(11)
_S27 = np.uint64(27)
_S30 = np.uint64(30)
_S31 = np.uint64(31)
_ONE_U64 = np.uint64(1)
_TWO_M53 = 2.0 ** -53
_TWO_PI = 2.0 * math.pi


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


# --------------------------------------------------------------------------- parameters, theory


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
    return FrozenFieldParams(sigma, length, airspeed, dt, buffer_steps, airspeed * dt, float(a_u),
                             float(g_u), ad, gd, c, p0)


def dryden_correlation(r_m, length_scale_m):
    """Dryden longitudinal and transverse correlations (f, g) at distance ``r_m`` (array-like):
    f = exp(-r/L), g = (1 - r/(2L)) exp(-r/L)."""
    r = np.abs(np.asarray(r_m, dtype=np.float64))
    length = np.asarray(length_scale_m, dtype=np.float64)
    f = np.exp(-r / length)
    return f, (1.0 - r / (2.0 * length)) * f


def isotropic_correlation(separation_m, length_scale_m):
    """R_kk / sigma_k^2 of isotropic Dryden turbulence for separation vectors (..., 3) given in the
    track frame (along, cross, down); ``length_scale_m`` (3,) gives L per component. Returns
    (..., 3): (f - g) r_k^2 / r^2 + g with f, g at component k's scale length."""
    sep = np.asarray(separation_m, dtype=np.float64)
    length = np.broadcast_to(np.asarray(length_scale_m, dtype=np.float64), (3,))
    r = np.linalg.norm(sep, axis=-1)
    out = np.empty(sep.shape[:-1] + (3,))
    with np.errstate(invalid="ignore", divide="ignore"):
        for k in range(3):
            f, g = dryden_correlation(r, length[k])
            frac = np.where(r > 0.0, sep[..., k] ** 2 / np.where(r > 0.0, r, 1.0) ** 2, 0.0)
            out[..., k] = (f - g) * frac + g
    return out


def frozen_field_theory(separation_m, lag_s, length_scale_m, airspeed_mps, exact: bool = False):
    """Correlation (..., 3) between aircraft A at time t and aircraft B at t + ``lag_s``, B displaced
    from A by ``separation_m`` (..., 3) = (dx along, dy cross, dz down) in the track frame.

    ``exact=False``: what this module's field has, C^k(dy, dz) rho_k(lag + dx / V) with
    rho_u(s) = f(V s), rho_v = rho_w = g(V s) (within the transport buffer).
    ``exact=True``: an isotropic Dryden field frozen (Taylor): R_kk(dx + V lag, dy, dz) / sigma^2.
    """
    sep = np.asarray(separation_m, dtype=np.float64)
    lag = np.asarray(lag_s, dtype=np.float64)
    length = np.broadcast_to(np.asarray(length_scale_m, dtype=np.float64), (3,))
    v = float(airspeed_mps)
    sep, lag = np.broadcast_arrays(sep, lag[..., None])
    lag = lag[..., 0]
    if exact:
        moved = sep.copy()
        moved[..., 0] = sep[..., 0] + v * lag
        return isotropic_correlation(moved, length)
    cross = sep.copy()
    cross[..., 0] = 0.0
    c = isotropic_correlation(cross, length)
    s = np.abs(v * lag + sep[..., 0])
    out = np.empty_like(c)
    for k in range(3):
        f, g = dryden_correlation(s, length[k])
        out[..., k] = c[..., k] * (f if k == 0 else g)
    return out


def formation_key(seed: int) -> np.uint64:
    """The 64-bit key of a formation: SeedSequence(seed).generate_state(1, uint64)[0]."""
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or int(seed) < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    return np.random.SeedSequence(int(seed)).generate_state(1, dtype=np.uint64)[0]


# --------------------------------------------------------------------------- compiled kernels


@_jit
def _mix64(z):
    """splitmix64 finaliser (uint64, wrap-around arithmetic)."""
    z = (z ^ (z >> _S30)) * _MIX1
    z = (z ^ (z >> _S27)) * _MIX2
    return z ^ (z >> _S31)


@_jit
def counter_bits(key, counter, stream):
    """64 random bits of (key, counter, stream), all uint64."""
    s = _mix64(key + (counter + _ONE_U64) * _GOLDEN)
    return _mix64(s + (stream + _ONE_U64) * _GOLDEN)


@_jit
def counter_normal_pair(key, counter, pair):
    """Two independent standard normals from streams 2 pair, 2 pair + 1 (Box-Muller)."""
    stream = np.uint64(2) * pair
    b1 = counter_bits(key, counter, stream)
    b2 = counter_bits(key, counter, stream + _ONE_U64)
    u1 = (np.float64(b1 >> _S11) + 1.0) * _TWO_M53  # (0, 1]
    u2 = np.float64(b2 >> _S11) * _TWO_M53  # [0, 1)
    rad = math.sqrt(-2.0 * math.log(u1))
    ang = _TWO_PI * u2
    return rad * math.cos(ang), rad * math.sin(ang)


@_jit
def _lane_normals(key, counter, lane, n):
    """The 6 normals of one lane at one filter step into n (6,)."""
    base = np.uint64(lane) * np.uint64(N_STREAMS_PER_LANE // 2)
    for p in range(N_STREAMS_PER_LANE // 2):
        a, b = counter_normal_pair(key, np.uint64(counter), base + np.uint64(p))
        n[2 * p] = a
        n[2 * p + 1] = b


@_jit
def _advance_one(params, state, b, n):
    """One filter step of formation b; writes the new lane values to the next ring slot."""
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
            _advance_one(params, state, b, n)


@_jit
def advance_kernel(params, state):
    """Every formation one dt forward."""
    n = np.empty(N_STREAMS_PER_LANE)
    for b in range(state.x_u.shape[0]):
        _advance_one(params, state, b, n)


@_jit
def _cholesky_rows(c, lo):
    """Lower Cholesky factor of the correlation matrix c (V, V) into lo, pivots <= _PIVOT_TOL
    clamped to zero (their column is dropped), each row renormalised to unit norm."""
    nveh = c.shape[0]
    for i in range(nveh):
        for j in range(nveh):
            lo[i, j] = 0.0
    for j in range(nveh):
        d = c[j, j]
        for m in range(j):
            d -= lo[j, m] * lo[j, m]
        if d > _PIVOT_TOL * c[j, j]:
            piv = math.sqrt(d)
            lo[j, j] = piv
            for i in range(j + 1, nveh):
                s = c[i, j]
                for m in range(j):
                    s -= lo[i, m] * lo[j, m]
                lo[i, j] = s / piv
        # else: column j stays zero (aircraft j's cross position duplicates earlier ones)
    for i in range(nveh):
        s = 0.0
        for m in range(i + 1):
            s += lo[i, m] * lo[i, m]
        if s > 0.0 and s != 1.0:
            s = math.sqrt(s)
            for m in range(i + 1):
                lo[i, m] /= s


@_jit
def _sample_one(params, state, b, positions, chi, out, along, cross, down, slot0, slot1, frac,
                corr, lo, gust):
    nveh = state.x_u.shape[1]
    nslot = state.ring.shape[1]
    head = state.head[b]
    cs = math.cos(chi)
    sn = math.sin(chi)
    front = -np.inf
    for i in range(nveh):
        pn = positions[b, i, 0]
        pe = positions[b, i, 1]
        along[i] = cs * pn + sn * pe
        cross[i] = -sn * pn + cs * pe
        down[i] = positions[b, i, 2]
        if along[i] > front:
            front = along[i]
    max_d = float(nslot - 1)
    for i in range(nveh):
        d = (front - along[i]) / params.step_length_m
        if not (d > 0.0):  # also NaN
            d = 0.0
        rd = math.floor(d + 0.5)
        if abs(d - rd) < _SNAP_TOL:
            d = rd
        if d >= max_d:
            d = max_d
        d0 = int(math.floor(d))
        fr = d - d0
        if d0 >= nslot - 1:
            d0 = nslot - 1
            fr = 0.0
        s0 = (head - d0) % nslot
        slot0[i] = s0
        slot1[i] = (s0 - 1) % nslot
        frac[i] = fr
    for k in range(3):
        length = params.length_scale_m[k]
        for i in range(nveh):
            corr[i, i] = 1.0
            for j in range(i):
                dy = cross[i] - cross[j]
                dz = down[i] - down[j]
                r2 = dy * dy + dz * dz
                r = math.sqrt(r2)
                f = math.exp(-r / length)
                g = (1.0 - r / (2.0 * length)) * f
                if k == 0 or r2 == 0.0:
                    cij = g
                elif k == 1:
                    cij = (f - g) * dy * dy / r2 + g
                else:
                    cij = (f - g) * dz * dz / r2 + g
                corr[i, j] = cij
                corr[j, i] = cij
        _cholesky_rows(corr, lo)
        sig = params.sigma_mps[k]
        for i in range(nveh):
            s0 = slot0[i]
            s1 = slot1[i]
            fr = frac[i]
            acc = 0.0
            for j in range(i + 1):
                lane = (1.0 - fr) * state.ring[b, s0, k, j] + fr * state.ring[b, s1, k, j]
                acc += lo[i, j] * lane
            gust[i, k] = sig * acc
    for i in range(nveh):
        u = gust[i, 0]
        v = gust[i, 1]
        out[b, i, 0] = cs * u - sn * v
        out[b, i, 1] = sn * u + cs * v
        out[b, i, 2] = gust[i, 2]


@_jit
def sample_kernel(params, state, positions_ned, track_angle_rad, out_gust_ned):
    """Gusts (B, V, 3) m/s NED at the current time into ``out_gust_ned``; positions (B, V, 3) m NED,
    track angles (B,) rad. No checks (see :func:`frozen_field_sample`)."""
    nveh = state.x_u.shape[1]
    along = np.empty(nveh)
    cross = np.empty(nveh)
    down = np.empty(nveh)
    slot0 = np.empty(nveh, dtype=np.int64)
    slot1 = np.empty(nveh, dtype=np.int64)
    frac = np.empty(nveh)
    corr = np.empty((nveh, nveh))
    lo = np.empty((nveh, nveh))
    gust = np.empty((nveh, 3))
    for b in range(state.x_u.shape[0]):
        _sample_one(params, state, b, positions_ned, track_angle_rad[b], out_gust_ned, along, cross,
                    down, slot0, slot1, frac, corr, lo, gust)


@_jit
def rollout_kernel(params, state, positions_ned, track_angle_rad, out_gust_ned):
    """``n_steps = out_gust_ned.shape[0]`` times: sample into out_gust_ned[t] (B, V, 3), then
    advance; positions and track angles held fixed."""
    for t in range(out_gust_ned.shape[0]):
        sample_kernel(params, state, positions_ned, track_angle_rad, out_gust_ned[t])
        advance_kernel(params, state)


# --------------------------------------------------------------------------- checked Python API


def frozen_field_init(params: FrozenFieldParams, batch_size: int, n_vehicles: int) -> FrozenFieldState:
    """Zeroed state of ``batch_size`` formations of ``n_vehicles`` aircraft (gusts are zero until
    :func:`frozen_field_reset`)."""
    _check_params(params)
    bsz, nveh = int(batch_size), int(n_vehicles)
    if bsz < 1 or bsz != batch_size:
        raise ValueError(f"batch_size must be a positive integer, got {batch_size!r}")
    if nveh < 1 or nveh != n_vehicles:
        raise ValueError(f"n_vehicles must be a positive integer, got {n_vehicles!r}")
    return FrozenFieldState(
        key=np.zeros(bsz, dtype=np.uint64),
        step=np.zeros(bsz, dtype=np.int64),
        head=np.zeros(bsz, dtype=np.int64),
        x_u=np.zeros((bsz, nveh)),
        x_vw=np.zeros((bsz, 2, nveh, 2)),
        ring=np.zeros((bsz, params.buffer_steps + 1, 3, nveh)),
    )


def _check_params(params) -> None:
    if not isinstance(params, FrozenFieldParams):
        raise ValueError(f"params must be a FrozenFieldParams (use frozen_field_params), got {type(params)}")


def _check_state(params: FrozenFieldParams, state) -> tuple[int, int]:
    _check_params(params)
    if not isinstance(state, FrozenFieldState):
        raise ValueError(f"state must be a FrozenFieldState (use frozen_field_init), got {type(state)}")
    bsz, nveh = state.x_u.shape
    if state.ring.shape != (bsz, params.buffer_steps + 1, 3, nveh):
        raise ValueError(f"state.ring has shape {state.ring.shape}, params need "
                         f"{(bsz, params.buffer_steps + 1, 3, nveh)}")
    return bsz, nveh


def frozen_field_reset(params: FrozenFieldParams, state: FrozenFieldState, indices, seeds) -> None:
    """Restart formations ``indices`` from integer ``seeds`` (one per index, >= 0), in place."""
    bsz, _ = _check_state(params, state)
    idx = np.atleast_1d(np.asarray(indices))
    if idx.ndim != 1 or (idx.size and not np.issubdtype(idx.dtype, np.integer)):
        raise ValueError(f"indices must be a 1-D integer array, got {indices!r}")
    idx = idx.astype(np.int64)
    if idx.size and (idx.min() < 0 or idx.max() >= bsz):
        raise ValueError(f"indices must lie in [0, {bsz}), got {indices!r}")
    seed_list = [seeds] if np.isscalar(seeds) else list(seeds)
    if len(seed_list) != idx.size:
        raise ValueError(f"{len(seed_list)} seeds for {idx.size} indices")
    keys = np.array([formation_key(s) for s in seed_list], dtype=np.uint64)
    reset_kernel(params, state, idx, keys)


def _check_geometry(state, positions_ned, track_angle_rad):
    bsz, nveh = state.x_u.shape
    pos = np.ascontiguousarray(positions_ned, dtype=np.float64)
    if pos.shape != (bsz, nveh, 3):
        raise ValueError(f"positions_ned has shape {np.shape(positions_ned)}, expected {(bsz, nveh, 3)}")
    chi = np.ascontiguousarray(track_angle_rad, dtype=np.float64)
    if chi.shape != (bsz,):
        raise ValueError(f"track_angle_rad has shape {np.shape(track_angle_rad)}, expected {(bsz,)}")
    if not (np.all(np.isfinite(pos)) and np.all(np.isfinite(chi))):
        raise ValueError("positions_ned and track_angle_rad must be finite")
    return pos, chi


def frozen_field_sample(params: FrozenFieldParams, state: FrozenFieldState, positions_ned, track_angle_rad,
                        out_gust_ned) -> None:
    """Write the gusts (B, V, 3) m/s NED of the current time into ``out_gust_ned`` (float64,
    C-contiguous); positions (B, V, 3) m NED, track angle (B,) rad (chi = 0 north, positive east)."""
    bsz, nveh = _check_state(params, state)
    pos, chi = _check_geometry(state, positions_ned, track_angle_rad)
    _check_out(out_gust_ned, (bsz, nveh, 3))
    sample_kernel(params, state, pos, chi, out_gust_ned)


def _check_out(out, shape) -> None:
    if not (isinstance(out, np.ndarray) and out.shape == shape and out.dtype == np.float64
            and out.flags.c_contiguous and out.flags.writeable):
        raise ValueError(f"out_gust_ned must be a writeable C-contiguous float64 array of shape {shape}, got "
                         f"{getattr(out, 'dtype', type(out))} {getattr(out, 'shape', '')}")


def frozen_field_advance(params: FrozenFieldParams, state: FrozenFieldState) -> None:
    """Every formation one dt forward, in place."""
    _check_state(params, state)
    advance_kernel(params, state)


def frozen_field_rollout(params: FrozenFieldParams, state: FrozenFieldState, positions_ned, track_angle_rad,
                         n_steps: int, out_gust_ned: np.ndarray | None = None) -> np.ndarray:
    """Sample-then-advance ``n_steps`` times with fixed positions; returns (n_steps, B, V, 3) m/s NED
    (identical to a loop of :func:`frozen_field_sample` and :func:`frozen_field_advance`)."""
    bsz, nveh = _check_state(params, state)
    pos, chi = _check_geometry(state, positions_ned, track_angle_rad)
    n = int(n_steps)
    if n < 0 or n != n_steps:
        raise ValueError(f"n_steps must be a non-negative integer, got {n_steps!r}")
    if out_gust_ned is None:
        out_gust_ned = np.empty((n, bsz, nveh, 3))
    _check_out(out_gust_ned, (n, bsz, nveh, 3))
    rollout_kernel(params, state, pos, chi, out_gust_ned)
    return out_gust_ned


class FrozenTurbulenceField:
    """Convenience wrapper holding params and state (the kernels above are the API).

    ``FrozenTurbulenceField(params, batch_size, n_vehicles, seeds)``; ``sample(positions, chi)`` returns a
    new (B, V, 3) array; ``advance()``; ``reset(indices, seeds)``.
    """

    def __init__(self, params: FrozenFieldParams, batch_size: int, n_vehicles: int, seeds: Sequence[int]):
        self.params = params
        self.state = frozen_field_init(params, batch_size, n_vehicles)
        self.reset(np.arange(batch_size), seeds)

    def reset(self, indices, seeds) -> None:
        frozen_field_reset(self.params, self.state, indices, seeds)

    def sample(self, positions_ned, track_angle_rad) -> np.ndarray:
        out = np.empty(self.state.x_u.shape + (3,))
        frozen_field_sample(self.params, self.state, positions_ned, track_angle_rad, out)
        return out

    def advance(self) -> None:
        frozen_field_advance(self.params, self.state)
