"""One frozen spatial turbulence field per formation: random Fourier modes (Kraichnan type), von Karman
(default) or Dryden, evaluable at any point, advected with the mean wind, with rotational gusts.

Spectrum. Isotropic turbulence, intensity sigma and integral scale L on every axis: the project's
MIL-F-8785C low-altitude scale lengths (:func:`formation_env.atmosphere.dryden.mil_f_8785c_low_altitude`) at
the scenarios' altitude, 1000 m, where the low-altitude forms are clipped to 1000 ft and give the isotropic
case L_u = L_v = L_w = 1000 ft = 304.8 m, sigma_u = sigma_v = sigma_w. von Karman: the MIL-HDBK-1797 /
MIL-F-8785C form, E(k) = sigma^2 a 55/(9 sqrt pi) Gamma(5/6)/Gamma(1/3) (ak)^4 / (1 + (ak)^2)^(17/6),
a = 1.339 L (one-point spectra Phi_u = sigma^2 2L/pi / (1 + (1.339 L Omega)^2)^(5/6), ...); Dryden:
E(k) = 8 sigma^2 L/pi (kL)^4 / (1 + (kL)^2)^3, the field whose correlations are the exponential forms
behind the MIL-F-8785C Dryden transfer functions. Correlations and spectra: :mod:`.spectral_theory`.

Modes. u(x) = sum_n a_n cos(k_n . x + phi_n), n = 1..N (N = 256 by default, chosen by measurement:
docs/aircraft.md). The wavenumber range [k_min, k_max] = [0.02 / L, 30 rad/m] (5.7 decades) is cut into N
log-spaced shells (stratified sampling: every decade gets its modes); mode n lies in shell n, |k_n| drawn
from E(k) restricted to the shell, A_n = 2 sqrt(integral of E over the shell), a_n = A_n e_n with e_n a
unit vector in the plane perpendicular to k_n (incompressible), phi_n uniform. Directions and e_n come
from a randomly shifted low-discrepancy (Kronecker, R3) lattice over n: each mode's direction is
uniform on the sphere, so E[u_i(x) u_j(x + r)] = R_ij(r) of the isotropic field of the band exactly (in
expectation over the modes, for every r, no grid), while neighbouring shells' directions spread evenly
and a realisation's variance per axis varies less. The variance beyond k_max is left out (von Karman
0.27 %, Dryden 0.02 %; below k_min < 1e-9): it decorrelates within centimetres, so it lowers 1 - rho
at half a span by 12 % (von Karman) and the tests compare with the band's correlations
(:func:`.spectral_theory.correlation_fg` with ``band``). A sample costs one :func:`sincos` per mode and
aircraft (arithmetic only, so it vectorises over the modes).

Taylor. The field is frozen in the air mass: a UAV at ground position x at time t samples u(x - W t),
W the steady wind (NED), so every UAV samples the one field at its own position and any two points have
the field's correlation.

Rotational gusts, in the 6-DOF's convention (the rotational wind wind[9:12], body axes, subtracted from
the body rates like the ELL's induced rotational wind): (p_g, -q_g, -r_g) with MIL-F-8785C's
p_g = dw/dy, q_g = dw/dx, r_g = -dv/dx (x along the track, y starboard, z down). For the Aerosonde's span b
and tail arm l: p_g is the least-squares slope of w over the span line [-b/2, b/2] (as the ELL fits its
evenly spread points); q_g and r_g are central differences over l of the span-averaged w and v. Each is
the exact difference / fit of every plane-wave mode, computed from the CG's phase with a per-mode factor
(:func:`.spectral_field_kernels.omega_coefficients_one`) rather than from extra field points: the same
numbers as sampling the span and the tail, at no extra cos/sin per aircraft. The frame of the span and
tail lines is the formation's track frame (chi), the result is rotated to each UAV's body axes as a
vector (attitude angles of a few degrees make the difference negligible).

Seeds. Counter based: mode n uses the uniforms of (formation key, counter n, streams 0 and 4), the
lattice shift those of (key, counter 2^32 - 1, streams 0..2), from :func:`.frozen_field_rng.counter_bits`;
the key ``SeedSequence(seed).generate_state(1, uint64)[0]``
(:func:`.frozen_field_rng.formation_key`). A formation's field depends only on its seed: batch == single
bit for bit. The modes are drawn at reset; nothing advances in time (the field is frozen), so sampling
is a pure function of position and time.

Kernels: :mod:`.spectral_field_kernels`; this module builds the parameters and is the checked Python API.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import integrate

from ..constants import AEROSONDE_SPAN_M
from ..geometry.presets import AEROSONDE_TAIL_ARM_M
from .frozen_field_rng import reset_keys
from .spectral_field_kernels import (N_MODE_STREAMS, SpectralFieldParams, SpectralFieldState, reset_modes_kernel,
                                     sample_modes_kernel, velocity_points_one)
from .spectral_theory import FIELD_KINDS, energy_spectrum

__all__ = ["SpectralFieldParams", "SpectralFieldState", "FIELD_KINDS", "DEFAULT_N_MODES", "DEFAULT_K_MIN_L",
           "DEFAULT_K_MAX", "N_MODE_STREAMS", "spectral_field_params", "spectral_field_init", "spectral_field_reset",
           "spectral_field_velocity", "spectral_field_sample"]

DEFAULT_N_MODES = 256  # chosen by measurement: docs/aircraft.md, "Frozen turbulence field"
DEFAULT_K_MIN_L = 0.02  # k_min L: below it the spectrum holds < 1e-9 of the variance
DEFAULT_K_MAX = 30.0  # rad/m (a 0.2 m wavelength, a tenth of the tail arm's): the rotational gusts converge
_TABLE = 129  # points of each shell's cumulative-energy table


def _positive(name: str, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{name} must be positive and finite, got {value!r}")
    return v


def spectral_field_params(kind: str, sigma_mps: float, length_scale_m: float, dt_s: float,
                          n_modes: int = DEFAULT_N_MODES, k_min: float | None = None, k_max: float = DEFAULT_K_MAX,
                          span_m: float = AEROSONDE_SPAN_M, tail_arm_m: float = AEROSONDE_TAIL_ARM_M
                          ) -> SpectralFieldParams:
    """Parameters of the field: ``kind`` in :data:`FIELD_KINDS` ("von_karman" | "dryden"), sigma (m/s,
    >= 0; 0 gives zero gusts), isotropic scale length L (m, > 0), physics step dt (s), ``n_modes`` (>= 1)
    over [k_min, k_max] rad/m (default k_min = 0.02 / L), the span and tail arm of the rotational gusts (m)."""
    if kind not in FIELD_KINDS:
        raise ValueError(f"kind must be one of {FIELD_KINDS}, got {kind!r}")
    sigma = float(sigma_mps)
    if not (math.isfinite(sigma) and sigma >= 0.0):
        raise ValueError(f"sigma_mps must be >= 0 and finite, got {sigma_mps!r}")
    length = _positive("length_scale_m", length_scale_m)
    dt = _positive("dt_s", dt_s)
    if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or not 1 <= n_modes <= 100000:
        raise ValueError(f"n_modes must be an integer in [1, 100000], got {n_modes!r}")
    lo = DEFAULT_K_MIN_L / length if k_min is None else _positive("k_min", k_min)
    hi = _positive("k_max", k_max)
    if not hi > lo:
        raise ValueError(f"k_max must exceed k_min, got k_min={lo!r}, k_max={k_max!r}")
    span, arm = _positive("span_m", span_m), _positive("tail_arm_m", tail_arm_m)
    n = int(n_modes)
    edges = np.exp(np.linspace(math.log(lo), math.log(hi), n + 1))
    lnk = np.empty((n, _TABLE))
    cdf = np.empty((n, _TABLE))
    amp = np.empty(n)
    for j in range(n):
        # the shell's energy by quadrature (unit sigma), its cumulative distribution on a fine log grid
        energy = integrate.quad(lambda k: energy_spectrum(kind, k, 1.0, length), edges[j], edges[j + 1],
                                epsabs=0.0, epsrel=1e-10, limit=200)[0]
        fine = np.linspace(math.log(edges[j]), math.log(edges[j + 1]), 8 * (_TABLE - 1) + 1)
        dens = energy_spectrum(kind, np.exp(fine), 1.0, length) * np.exp(fine)  # E(k) dk = E k d(ln k)
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(fine))])
        lnk[j] = fine[::8]
        cdf[j] = cum[::8] / cum[-1]
        amp[j] = 2.0 * sigma * math.sqrt(energy)
    return SpectralFieldParams(kind=FIELD_KINDS.index(kind), sigma_mps=sigma, length_scale_m=length, k_min=lo,
                               k_max=hi, shell_lnk=lnk, shell_cdf=cdf, shell_amplitude=amp, span_m=span,
                               tail_arm_m=arm, dt_s=dt)


def spectral_field_init(params: SpectralFieldParams, batch_size: int) -> SpectralFieldState:
    """Zeroed modes of ``batch_size`` formations (zero field until :func:`spectral_field_reset`)."""
    _check_params(params)
    bsz = int(batch_size)
    if isinstance(batch_size, bool) or bsz < 1 or bsz != batch_size:
        raise ValueError(f"batch_size must be a positive integer, got {batch_size!r}")
    n = params.shell_amplitude.shape[0]
    return SpectralFieldState(key=np.zeros(bsz, dtype=np.uint64), wavevector=np.zeros((bsz, 3, n)),
                              amplitude=np.zeros((bsz, 3, n)), phase=np.zeros((bsz, n)),
                              omega_coef=np.zeros((bsz, 3, n)), coef_chi=np.full(bsz, np.nan),
                              scratch=np.zeros((bsz, 2, n)))


def _check_params(params) -> None:
    if not isinstance(params, SpectralFieldParams):
        raise ValueError(f"params must be a SpectralFieldParams (use spectral_field_params), got {type(params)}")


def _check_state(params, state) -> int:
    _check_params(params)
    if not isinstance(state, SpectralFieldState):
        raise ValueError(f"state must be a SpectralFieldState (use spectral_field_init), got {type(state)}")
    if state.phase.shape[1] != params.shell_amplitude.shape[0]:
        raise ValueError(f"state has {state.phase.shape[1]} modes, params {params.shell_amplitude.shape[0]}")
    return state.phase.shape[0]


def spectral_field_reset(params: SpectralFieldParams, state: SpectralFieldState, indices, seeds) -> None:
    """Draw the modes of formations ``indices`` from integer ``seeds`` (one per index, >= 0), in place."""
    bsz = _check_state(params, state)
    idx, keys = reset_keys(bsz, indices, seeds)
    reset_modes_kernel(params, state, idx, keys)


def _finite_array(name: str, value, shape) -> np.ndarray:
    try:
        arr = np.array(np.broadcast_to(np.asarray(value, dtype=np.float64), shape))  # a C-contiguous copy
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be finite numbers broadcastable to {shape}, got {value!r}") from exc
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    return arr


def spectral_field_velocity(params: SpectralFieldParams, state: SpectralFieldState, index: int, points_ned,
                            time_s: float = 0.0, wind_ned=(0.0, 0.0, 0.0)) -> np.ndarray:
    """The field of formation ``index`` at ``points_ned`` (..., 3) m NED at ``time_s``, frozen in the air
    moving at ``wind_ned`` (3,) m/s: (..., 3) m/s NED."""
    bsz = _check_state(params, state)
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < bsz:
        raise ValueError(f"index must be an integer in [0, {bsz}), got {index!r}")
    pts = np.asarray(points_ned, dtype=np.float64)
    if pts.ndim < 1 or pts.shape[-1] != 3 or not np.all(np.isfinite(pts)):
        raise ValueError(f"points_ned must be finite with a last axis of 3, got shape {pts.shape}")
    flat = np.ascontiguousarray(pts.reshape(-1, 3))
    out = np.empty_like(flat)
    t = float(_finite_array("time_s", time_s, ())[()])
    velocity_points_one(state, int(index), flat, t, _finite_array("wind_ned", wind_ned, (3,)), out)
    return out.reshape(pts.shape)


def spectral_field_sample(params: SpectralFieldParams, state: SpectralFieldState, positions_ned, time_s=0.0,
                          wind_ned=(0.0, 0.0, 0.0), track_angle_rad=0.0, quaternions=None):
    """Gusts at B formations' V aircraft: positions (B, V, 3) m NED, time (B,) s, steady wind (B, 3) m/s
    NED, track angle (B,) rad (0 north, positive east), attitude quaternions (B, V, 4) as stored (None:
    level, heading along the track). Returns (gust (B, V, 3) m/s NED, rotational gust (B, V, 3) rad/s body,
    the 6-DOF's convention: (p_g, -q_g, -r_g))."""
    bsz = _check_state(params, state)
    pos = np.asarray(positions_ned, dtype=np.float64)
    if pos.ndim != 3 or pos.shape[0] != bsz or pos.shape[2] != 3:
        raise ValueError(f"positions_ned must have shape ({bsz}, V, 3), got {pos.shape}")
    pos = _finite_array("positions_ned", pos, pos.shape)
    nv = pos.shape[1]
    chi = _finite_array("track_angle_rad", track_angle_rad, (bsz,))
    if quaternions is None:
        quat = np.zeros((bsz, nv, 4))
        quat[..., 0] = np.cos(0.5 * chi)[:, None]
        quat[..., 3] = np.sin(0.5 * chi)[:, None]  # yaw by chi
    else:
        quat = _finite_array("quaternions", quaternions, (bsz, nv, 4))
    gust, omega = np.empty((bsz, nv, 3)), np.empty((bsz, nv, 3))
    sample_modes_kernel(params, state, pos, quat, _finite_array("time_s", time_s, (bsz,)),
                        _finite_array("wind_ned", wind_ned, (bsz, 3)), chi, gust, omega)
    return gust, omega
