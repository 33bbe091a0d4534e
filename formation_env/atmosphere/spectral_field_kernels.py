"""Compiled kernels of the spectral turbulence field (see :mod:`.spectral_field` for the method): the
modes drawn at reset from a formation's key, the span/tail coefficients of the rotational gusts, and
the field (and rotational gusts) evaluated at points and at the aircraft.

Parameters :class:`SpectralFieldParams`, state :class:`SpectralFieldState` (arrays, updated in place;
per formation b: wavevector[b] (3, N) rad/m NED, amplitude[b] (3, N) m/s NED, phase[b] (N,) rad).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np

from ..frames import ned_to_track_xy, quaternion_dcm_terms, track_to_ned_xy
from .frozen_field_rng import counter_bits

__all__ = ["SpectralFieldParams", "SpectralFieldState", "N_MODE_STREAMS", "LATTICE_COUNTER", "sincos", "draw_modes_one",
           "reset_modes_kernel", "omega_coefficients_one", "sample_modes_one", "velocity_points_one", "sample_modes_kernel"]

_jit = nb.njit(cache=True, error_model="numpy")

N_MODE_STREAMS = 5  # uniform streams per mode counter (0: position in its shell, 4: phase; 1-3 unused)
LATTICE_COUNTER = 0xFFFFFFFF  # the counter of a formation's lattice shift (streams 0-2), beyond any mode index
_PHI3 = 1.2207440846057594  # the plastic number: x^3 = x + 1
_R3 = (1.0 / _PHI3, 1.0 / _PHI3**2, 1.0 / _PHI3**3)  # Roberts' R3 sequence (low-discrepancy in 3-D)
_S11 = np.uint64(11)
_TWO_M53 = 2.0 ** -53
_TWO_PI = 2.0 * math.pi
_INV_TWO_PI = 1.0 / _TWO_PI
_TWO_PI_HI = 6.28125  # 2 pi = _TWO_PI_HI + _TWO_PI_LO (Cody-Waite: the high part has 8 significant bits)
_TWO_PI_LO = _TWO_PI - 6.28125


class SpectralFieldParams(NamedTuple):
    """Field parameters (build with :func:`formation_env.atmosphere.spectral_field.spectral_field_params`)."""

    kind: int  # 0 von Karman, 1 Dryden (the spectrum the shell tables were built from)
    sigma_mps: float  # RMS of every component, m/s
    length_scale_m: float  # integral scale L, m (isotropic)
    k_min: float  # the modes' wavenumber range, rad/m
    k_max: float
    shell_lnk: np.ndarray  # (N, M) ln k of each shell's table, from its lower to its upper edge
    shell_cdf: np.ndarray  # (N, M) cumulative energy within the shell at shell_lnk, 0 .. 1
    shell_amplitude: np.ndarray  # (N,) mode amplitude 2 sqrt(integral of E over the shell), m/s
    span_m: float  # b: the span line of the rolling gust (least-squares slope) and of the span average
    tail_arm_m: float  # l: the baseline of the pitching and yawing gusts' central differences
    dt_s: float  # physics step, s (the time of a sample after a step)


class SpectralFieldState(NamedTuple):
    """Modes of B formations (build with ``spectral_field_init``)."""

    key: np.ndarray  # (B,) uint64 random key of each formation (from its seed)
    wavevector: np.ndarray  # (B, 3, N) k_n, rad/m NED
    amplitude: np.ndarray  # (B, 3, N) a_n = A_n e_n (perpendicular to k_n), m/s NED
    phase: np.ndarray  # (B, N) rad
    omega_coef: np.ndarray  # (B, 3, N) rotational-gust coefficients (track frame) for the track angle coef_chi
    coef_chi: np.ndarray  # (B,) track angle the coefficients are for, rad (NaN: none yet)
    scratch: np.ndarray  # (B, 2, N) cos and sin of one aircraft's phases (working space of a sample)


@_jit
def sincos(theta):
    """(cos theta, sin theta) by arithmetic only, so that a loop over modes vectorises (numba has no
    vector libm here, and a scalar math.cos + math.sin per mode and point is several times this): theta reduced to
    r in [-pi, pi] (Cody-Waite, two-part 2 pi), Taylor polynomials of degree 13 / 14 at h = r / 4 in
    [-pi/4, pi/4] (truncation 3e-14), two double-angle steps. Absolute error < 1e-13 for |theta| < 10,
    < 2e-10 for |theta| < 3e6 rad (the rounding of theta itself is 5e-10 there)."""
    q = math.floor(theta * _INV_TWO_PI + 0.5)
    h = 0.25 * ((theta - q * _TWO_PI_HI) - q * _TWO_PI_LO)
    h2 = h * h
    sn = h * (1.0 + h2 * (-1.0 / 6.0 + h2 * (1.0 / 120.0 + h2 * (-1.0 / 5040.0 + h2 * (
        1.0 / 362880.0 + h2 * (-1.0 / 39916800.0 + h2 / 6227020800.0))))))
    cs = 1.0 + h2 * (-0.5 + h2 * (1.0 / 24.0 + h2 * (-1.0 / 720.0 + h2 * (1.0 / 40320.0 + h2 * (
        -1.0 / 3628800.0 + h2 * (1.0 / 479001600.0 - h2 / 87178291200.0))))))
    s2 = 2.0 * sn * cs
    c2 = cs * cs - sn * sn
    return c2 * c2 - s2 * s2, 2.0 * s2 * c2


@_jit
def _uniform(key, counter, stream):
    """A uniform in [0, 1) from (key, counter, stream)."""
    return np.float64(counter_bits(key, np.uint64(counter), np.uint64(stream)) >> _S11) * _TWO_M53


@_jit
def draw_modes_one(params, state, b, key):
    """Formation b's modes from its key (uint64), in place. Mode n: |k| from the shell's energy
    distribution (inverse of its tabulated cumulative energy at the uniform of counter n, stream 0), the
    phase uniform (counter n, stream 4); its direction (cos of the polar angle mu, azimuth psi) and the
    angle alpha of its amplitude vector in the plane perpendicular to k (incompressible) from a randomly
    shifted Kronecker lattice over the modes, (mu, psi, alpha) = (1 - 2 u1, 2 pi u2, 2 pi u3),
    u = frac(n g + U), g the R3 generalised golden ratios, U three uniforms of the key (counter
    LATTICE_COUNTER): each mode's direction is uniform on the sphere (so every expected two-point
    statistic is exact), while neighbouring shells' directions spread evenly (a realisation's variance
    per axis varies 3x less than with independent directions at 256 modes). Rotational coefficients
    marked stale."""
    state.key[b] = key
    shift0 = _uniform(key, LATTICE_COUNTER, 0)
    shift1 = _uniform(key, LATTICE_COUNTER, 1)
    shift2 = _uniform(key, LATTICE_COUNTER, 2)
    for n in range(params.shell_amplitude.shape[0]):
        u0 = _uniform(key, n, 0)
        state.phase[b, n] = _TWO_PI * _uniform(key, n, 4)
        fn = float(n)
        mu = 1.0 - 2.0 * ((fn * _R3[0] + shift0) % 1.0)  # in (-1, 1]
        psi = _TWO_PI * ((fn * _R3[1] + shift1) % 1.0)
        alpha = _TWO_PI * ((fn * _R3[2] + shift2) % 1.0)
        k = math.exp(np.interp(u0, params.shell_cdf[n], params.shell_lnk[n]))
        st = math.sqrt(max(0.0, 1.0 - mu * mu))
        cp, sp = math.cos(psi), math.sin(psi)
        ca, sa = math.cos(alpha), math.sin(alpha)
        amp = params.shell_amplitude[n]
        state.wavevector[b, 0, n] = k * st * cp
        state.wavevector[b, 1, n] = k * st * sp
        state.wavevector[b, 2, n] = k * mu
        # e = cos(alpha) e_theta + sin(alpha) e_psi: both unit vectors perpendicular to k
        state.amplitude[b, 0, n] = amp * (ca * mu * cp - sa * sp)
        state.amplitude[b, 1, n] = amp * (ca * mu * sp + sa * cp)
        state.amplitude[b, 2, n] = amp * (-ca * st)
    state.coef_chi[b] = np.nan


@_jit
def reset_modes_kernel(params, state, indices, keys):
    """Draw the modes of formations ``indices`` (int64 (n,)) from ``keys`` (uint64 (n,))."""
    for q in range(indices.shape[0]):
        draw_modes_one(params, state, indices[q], keys[q])


@_jit
def _sinc(x):
    """sin(x) / x (1 at 0)."""
    if abs(x) < 1e-4:
        return 1.0 - x * x / 6.0
    return math.sin(x) / x


@_jit
def _slope_factor(x):
    """Least-squares slope over [-h, h] of a sinusoid of wavenumber k, relative to its derivative,
    x = k h: 3 j1(x) / x = 3 (sin x - x cos x) / x^3."""
    if abs(x) < 1e-2:
        x2 = x * x
        return 1.0 - x2 / 10.0 + x2 * x2 / 280.0
    return 3.0 * (math.sin(x) - x * math.cos(x)) / (x * x * x)


@_jit
def omega_coefficients_one(params, state, b, chi):
    """Formation b's rotational-gust coefficients for the track angle chi (rad), in place: with the
    field's mode n, cos theta_n at the CG, k and a in the track frame (x along, y starboard, z down),
    h = b/2, l the tail arm, the gusts in the kernel's convention (subtracted from the body rates) are
    sum_n c_n sin theta_n with (MIL-F-8785C p_g, -q_g, -r_g):

    * p_g = dw/dy, the least-squares slope over the span: c_x = -a_z k_y 3 j1(k_y h) / (k_y h);
    * -q_g = -dw/dx, q_g the central difference over l of the span-averaged w:
      c_y = a_z (2 / l) sin(k_x l / 2) sinc(k_y h);
    * -r_g = dv/dx: c_z = -a_y (2 / l) sin(k_x l / 2) sinc(k_y h).

    Each is exactly that difference / fit of the plane wave (no truncation), from the CG's phase."""
    cs, sn = math.cos(chi), math.sin(chi)
    h = 0.5 * params.span_m
    half_l = 0.5 * params.tail_arm_m
    for n in range(state.phase.shape[1]):
        kx, ky = ned_to_track_xy(cs, sn, state.wavevector[b, 0, n], state.wavevector[b, 1, n])
        ay = -sn * state.amplitude[b, 0, n] + cs * state.amplitude[b, 1, n]
        az = state.amplitude[b, 2, n]
        span_avg = _sinc(ky * h)
        dx = kx * _sinc(kx * half_l) * span_avg  # d/dx of the span average over the tail arm, per unit phase
        state.omega_coef[b, 0, n] = -az * ky * _slope_factor(ky * h)
        state.omega_coef[b, 1, n] = az * dx
        state.omega_coef[b, 2, n] = -ay * dx
    state.coef_chi[b] = chi


@_jit
def _phases(state, b, x0, x1, x2):
    """cos and sin of formation b's mode phases k_n . x + phi_n at the point x (m) into state.scratch[b]
    (no reduction in the loop: it vectorises)."""
    kv, ph, cs = state.wavevector[b], state.phase[b], state.scratch[b]
    for n in range(ph.shape[0]):
        c, s = sincos(kv[0, n] * x0 + kv[1, n] * x1 + kv[2, n] * x2 + ph[n])
        cs[0, n] = c
        cs[1, n] = s


@_jit
def velocity_points_one(state, b, points, time_s, wind, out):
    """The field of formation b at ``points`` (M, 3) m NED and time ``time_s`` (s), frozen in the air
    moving at ``wind`` (3,) m/s NED (Taylor): u(x - W t), into out (M, 3) m/s NED."""
    av, cs = state.amplitude[b], state.scratch[b]
    for m in range(points.shape[0]):
        _phases(state, b, points[m, 0] - wind[0] * time_s, points[m, 1] - wind[1] * time_s,
                points[m, 2] - wind[2] * time_s)
        u0 = 0.0
        u1 = 0.0
        u2 = 0.0
        for n in range(cs.shape[1]):
            c = cs[0, n]
            u0 += av[0, n] * c
            u1 += av[1, n] * c
            u2 += av[2, n] * c
        out[m, 0] = u0
        out[m, 1] = u1
        out[m, 2] = u2


@_jit
def sample_modes_one(params, state, b, pos, quat, time_s, wind, chi, gust_out, omega_out):
    """Gusts of formation b's V aircraft now: ``gust_out`` (V, 3) m/s NED, the field at each CG ``pos``
    (V, 3) m NED at ``time_s`` (s), frozen in the air moving at ``wind`` (3,) m/s NED; ``omega_out``
    (V, 3) rad/s body axes (attitude quaternions ``quat`` (V, 4) as stored), the rotational gusts of
    :func:`omega_coefficients_one` for the track angle ``chi`` (recomputed when chi changes), rotated
    from the track frame to NED to body as a vector. A non-finite position or attitude reads as zero.
    One :func:`sincos` per mode and aircraft."""
    if state.coef_chi[b] != chi:
        omega_coefficients_one(params, state, b, chi)
    av, co, cs = state.amplitude[b], state.omega_coef[b], state.scratch[b]
    cchi, schi = math.cos(chi), math.sin(chi)
    for a in range(pos.shape[0]):
        _phases(state, b, pos[a, 0] - wind[0] * time_s, pos[a, 1] - wind[1] * time_s, pos[a, 2] - wind[2] * time_s)
        u0 = 0.0
        u1 = 0.0
        u2 = 0.0
        w0 = 0.0
        w1 = 0.0
        w2 = 0.0
        for n in range(cs.shape[1]):
            c = cs[0, n]
            s = cs[1, n]
            u0 += av[0, n] * c
            u1 += av[1, n] * c
            u2 += av[2, n] * c
            w0 += co[0, n] * s
            w1 += co[1, n] * s
            w2 += co[2, n] * s
        on, oe = track_to_ned_xy(cchi, schi, w0, w1)
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = quaternion_dcm_terms(quat[a, 0], quat[a, 1], quat[a, 2],
                                                                           quat[a, 3])
        o0 = r00 * on + r10 * oe + r20 * w2  # body = (body-to-NED)^T ned
        o1 = r01 * on + r11 * oe + r21 * w2
        o2 = r02 * on + r12 * oe + r22 * w2
        if math.isfinite(u0 + u1 + u2 + o0 + o1 + o2):
            gust_out[a, 0] = u0
            gust_out[a, 1] = u1
            gust_out[a, 2] = u2
            omega_out[a, 0] = o0
            omega_out[a, 1] = o1
            omega_out[a, 2] = o2
        else:
            for i in range(3):
                gust_out[a, i] = 0.0
                omega_out[a, i] = 0.0


@_jit
def sample_modes_kernel(params, state, pos, quat, time_s, wind, chi, gust_out, omega_out):
    """:func:`sample_modes_one` for every formation: pos (B, V, 3), quat (B, V, 4), time_s (B,),
    wind (B, 3), chi (B,), outputs (B, V, 3)."""
    for b in range(pos.shape[0]):
        sample_modes_one(params, state, b, pos[b], quat[b], time_s[b], wind[b], chi[b], gust_out[b], omega_out[b])
