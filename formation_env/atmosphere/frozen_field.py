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

The code: :mod:`.frozen_field_rng` (counter-based normals), :mod:`.frozen_field_filters` (parameters,
state, lane filters and ring), :mod:`.frozen_field_sampling` (delayed reads, mixing, rollout),
:mod:`.frozen_field_correlation` (the statistics, numpy); this module is the checked Python API and
re-exports their names.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .frozen_field_correlation import dryden_correlation, frozen_field_theory, isotropic_correlation
from .frozen_field_filters import (FrozenFieldParams, FrozenFieldState, advance_field_one, advance_kernel,
                                   frozen_field_params, reset_kernel)
from .frozen_field_rng import N_STREAMS_PER_LANE, counter_bits, counter_normal_pair, formation_key, reset_keys
from .frozen_field_sampling import rollout_kernel, sample_field_one, sample_kernel

# advance_field_one and sample_field_one (one formation's filter step and read) are for compiled
# callers that fuse the field into their own loops.

__all__ = [
    "FrozenFieldParams",
    "FrozenFieldState",
    "FrozenTurbulenceField",
    "N_STREAMS_PER_LANE",
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
    "advance_field_one",
    "sample_field_one",
    "counter_bits",
    "counter_normal_pair",
    "reset_kernel",
    "rollout_kernel",
    "sample_kernel",
]


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
    idx, keys = reset_keys(bsz, indices, seeds)
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
