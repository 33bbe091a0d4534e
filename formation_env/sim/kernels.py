"""Compiled physics step of one formation: ELL effective wind -> Aerosonde RK4 -> envelope status
(:func:`step_one`; :func:`step_range` over a slice of a batch, without the GIL).

It fuses the same compiled kernels the wake and aircraft packages use
(:func:`formation_env.wake.kernels.evaluate_one`, :func:`formation_env.aircraft.kernels.rk4_batch`),
so there is no second implementation of the physics; only the envelope check is repeated here,
and a test holds it equal to :func:`formation_env.aircraft.check_envelope`. The separations the
decision step judges collisions by (never NaN, also across a step that diverges a UAV) are here too
(:func:`step_separation`, :func:`separation_each_known`), and the observation's and reward's
nearest-neighbour distance (:func:`min_separation_each`): every CG distance of the compiled code is
:func:`pair_distance`.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..aircraft.kernels import air_data_kernel, rk4_batch
from ..aircraft.state import POS_D, POS_E, POS_N
from ..frames import quaternion_dcm_terms
from ..wake.coupling import EFFECTIVE_WIND, CouplingArrays, coupled_wind

_jit = nb.njit(cache=True, error_model="numpy")

# EnvelopeLimits packed: airspeed min, max, altitude min, max, max bank, max pitch, omega min, flag fuel
N_LIMITS = 8
# Status bits (formation_env.aircraft.envelope.Status)
_NON_FINITE, _AS_LOW, _AS_HIGH, _ALT_LOW, _ALT_HIGH, _ATT, _ENG, _FUEL = 1, 2, 4, 8, 16, 32, 64, 128


def pack_limits(limits) -> np.ndarray:
    return np.array([limits.airspeed_min_mps, limits.airspeed_max_mps, limits.altitude_min_m, limits.altitude_max_m,
                     limits.max_bank_rad, limits.max_pitch_rad, limits.omega_min_rad_s,
                     1.0 if limits.flag_out_of_fuel else 0.0])


@_jit
def envelope_status(x, wind12, v, lim):
    """Status bits of one aircraft (state x (16,), wind as rk4_batch's 12-vector)."""
    for i in range(x.shape[0]):
        if not math.isfinite(x[i]):
            return _NON_FINITE
    status = 0
    va = air_data_kernel(x, wind12, v)[0]
    if va < lim[0]:
        status |= _AS_LOW
    if va > lim[1]:
        status |= _AS_HIGH
    alt = -x[POS_D]
    if alt < lim[2]:
        status |= _ALT_LOW
    if alt > lim[3]:
        status |= _ALT_HIGH
    e0, ex, ey, ez = x[6], x[7], x[8], x[9]
    n2 = e0 * e0 + ex * ex + ey * ey + ez * ez
    phi = math.atan2(2 * (e0 * ex + ey * ez), e0 * e0 - ex * ex - ey * ey + ez * ez)
    st = 2 * (e0 * ey - ex * ez) / n2
    theta = math.asin(min(1.0, max(-1.0, st)))
    if abs(phi) > lim[4] or abs(theta) > lim[5]:
        status |= _ATT
    if x[14] < lim[6]:
        status |= _ENG
    if lim[7] != 0.0 and x[13] <= 0.0:
        status |= _FUEL
    return status


@_jit
def ell_inputs(state, ambient, wing_origin_b, pos, euler, speed, alpha, beta):
    """Pose of each aircraft's wing origin and its air data relative to the ambient wind."""
    r = np.empty((3, 3))  # body -> NED
    vb = np.empty(3)
    for a in range(state.shape[0]):
        x = state[a]
        e0, ex, ey, ez = x[6], x[7], x[8], x[9]
        (r[0, 0], r[0, 1], r[0, 2], r[1, 0], r[1, 1], r[1, 2],
         r[2, 0], r[2, 1], r[2, 2]) = quaternion_dcm_terms(e0, ex, ey, ez)
        for i in range(3):
            pos[a, i] = x[POS_N + i] + r[i, 0] * wing_origin_b[0] + r[i, 1] * wing_origin_b[1] + r[i, 2] * wing_origin_b[2]
        for i in range(3):  # air-relative velocity in body axes: u_b - R^T w_ned
            vb[i] = x[i] - (r[0, i] * ambient[a, 0] + r[1, i] * ambient[a, 1] + r[2, i] * ambient[a, 2])
        sp = math.sqrt(vb[0] * vb[0] + vb[1] * vb[1] + vb[2] * vb[2])
        speed[a] = max(sp, 1e-3)
        alpha[a] = math.atan2(vb[2], vb[0])
        beta[a] = math.asin(min(1.0, max(-1.0, vb[1] / max(sp, 1e-9))))
        euler[a, 0] = math.atan2(2.0 * (e0 * ex + ey * ez), e0 * e0 - ex * ex - ey * ey + ez * ez)
        euler[a, 1] = math.asin(min(1.0, max(-1.0, 2.0 * (e0 * ey - ex * ez) / (e0 * e0 + ex * ex + ey * ey + ez * ez))))
        euler[a, 2] = math.atan2(2.0 * (ex * ey + e0 * ez), e0 * e0 + ex * ex - ey * ey - ez * ez)


@_jit
def clear_wake(held_wind, held_omega, gamma):
    """No induced wind and no circulation (a formation outside the envelope, or a degenerate solve)."""
    for a in range(held_wind.shape[0]):
        for i in range(3):
            held_wind[a, i] = 0.0
            held_omega[a, i] = 0.0
    for j in range(gamma.shape[0]):
        gamma[j] = 0.0


#: what a physics step does with the ELL (:func:`wake_action`): keep the held induced wind, solve, or clear it
WAKE_HOLD, WAKE_SOLVE, WAKE_CLEAR = 0, 1, 2

# the functions below are inlined into their callers at numba IR level (the decision, step_range): as compiled
# functions of their own each was one more copy of the ELL solve or the RK4 for numba to link and re-optimise
_jit_inline = nb.njit(cache=True, error_model="numpy", inline="always")


@_jit_inline
def wake_action(state, ambient, turb, held_wind, held_omega, update_wake, wake_on, aircraft):
    """What one physics step of a formation (V aircraft) does with the ELL: ``WAKE_HOLD`` (not an update step:
    the held induced wind stays), ``WAKE_SOLVE``, or ``WAKE_CLEAR`` (the wake is off, or an aircraft is outside
    the envelope with the held wind: its episode is ending, it flies without induced wind). Arguments as
    :func:`step_one`'s."""
    if not update_wake:
        return WAKE_HOLD
    if not wake_on:
        return WAKE_CLEAR
    wind = np.zeros(12)
    for a in range(state.shape[0]):
        for i in range(3):
            wind[i] = ambient[a, i]
            wind[3 + i] = turb[a, i]
            wind[6 + i] = held_wind[a, i]
            wind[9 + i] = held_omega[a, i]
        if envelope_status(state[a], wind, aircraft.scalars, aircraft.limits) != 0:
            return WAKE_CLEAR
    return WAKE_SOLVE


@_jit_inline
def clear_if_not_finite(held_wind, held_omega, gamma):
    """After a solve: the ELL stays bounded at any separation (the overlap core); should a solve still come out
    non-finite (degenerate input), the formation flies without induced wind this step rather than feeding NaN to
    the aircraft."""
    finite = True
    for a in range(held_wind.shape[0]):
        for i in range(3):
            if not (math.isfinite(held_wind[a, i]) and math.isfinite(held_omega[a, i])):
                finite = False
    if not finite:
        clear_wake(held_wind, held_omega, gamma)


@_jit_inline
def integrate_one(state, controls, ambient, turb, turb_omega, held_wind, held_omega, aircraft, dt, out_state,
                  out_status):
    """RK4 of one formation over dt with the held induced wind and the envelope status after it (arguments as
    :func:`step_one`'s)."""
    ac = aircraft
    nv = state.shape[0]
    wind = np.zeros((nv, 12))
    for a in range(nv):
        for i in range(3):
            wind[a, i] = ambient[a, i]
            wind[a, 3 + i] = turb[a, i]
            wind[a, 6 + i] = held_wind[a, i]
            wind[a, 9 + i] = held_omega[a, i] + turb_omega[a, i]
    rk4_batch(state, controls, wind, dt, ac, out_state)
    for a in range(nv):
        out_status[a] = envelope_status(out_state[a], wind[a], ac.scalars, ac.limits)


@_jit_inline
def step_one(state, controls, ambient, turb, turb_omega, held_wind, held_omega, gamma, update_wake, wake_on, wake,
             coupling, aircraft, dt, out_state, out_status, keep=None):
    """One formation (V aircraft) by one step dt: ELL induced wind when ``update_wake`` (held
    otherwise; held_wind/held_omega/gamma are updated in place), RK4, envelope status.

    state (V, 16); controls (V, 4|5); ambient (V, 3) NED and turb (V, 3) body wind, m/s; turb_omega (V, 3)
    rotational gusts, rad/s body, added to the held induced rotational wind; ``wake`` a
    :class:`~formation_env.wake.arrays.WakeArrays`, ``coupling`` a
    :class:`~formation_env.wake.coupling.CouplingArrays` (the thesis's effective wind or the load-weighted
    wind, :func:`~formation_env.wake.coupling.coupled_wind`), ``aircraft`` an
    :class:`~formation_env.sim.params.AircraftArrays`. A formation with an aircraft outside the
    envelope gets no wake solve and zero induced wind (its episode is ending). ``keep``: the solve's AIC and
    right-hand side before elimination (:func:`formation_env.wake.aic.assemble_and_solve`; None or empty: not kept).
    The decision step runs the same stages with the solve of a chunk of formations at once
    (:func:`formation_env.sim.physics.physics_before_wake`)."""
    nv = state.shape[0]
    act = wake_action(state, ambient, turb, held_wind, held_omega, update_wake, wake_on, aircraft)
    if act == WAKE_SOLVE:
        pos = np.empty((nv, 3))
        euler = np.empty((nv, 3))
        speed = np.empty(nv)
        alpha = np.empty(nv)
        beta = np.empty(nv)
        ell_inputs(state, ambient, wake.wing_origin_body, pos, euler, speed, alpha, beta)
        coupled_wind(wake, coupling, pos, euler, speed, alpha, beta, gamma, np.empty((wake.n_panels, 3)),
                     held_wind, np.empty((nv, 3)), held_omega, np.empty((nv, 3)), keep)
        clear_if_not_finite(held_wind, held_omega, gamma)
    elif act == WAKE_CLEAR:
        clear_wake(held_wind, held_omega, gamma)
    integrate_one(state, controls, ambient, turb, turb_omega, held_wind, held_omega, aircraft, dt, out_state,
                  out_status)


@nb.njit(cache=True, nogil=True, error_model="numpy")
def step_range(state, controls, ambient, turb, held_wind, held_omega, gamma, update_wake, wake_on, wake, aircraft, dt,
               out_state, out_status, start, stop):
    """:func:`step_one` for formations start..stop-1 of a batch (B, V, ...) with the thesis's effective-wind
    coupling; releases the GIL."""
    no_omega = np.zeros((state.shape[1], 3))  # no rotational gusts in this harness
    thesis = CouplingArrays(mode=EFFECTIVE_WIND, panel_length_m=np.zeros(0), roll_weight=np.zeros(0),
                            normal_b=np.zeros((0, 3)), cl_beta=0.0, cl_p=1.0, cl_r=0.0, span_m=1.0)
    for b in range(start, stop):
        step_one(state[b], controls[b], ambient[b], turb[b], no_omega, held_wind[b], held_omega[b], gamma[b], update_wake,
                 wake_on, wake, thesis, aircraft, dt, out_state[b], out_status[b])


@_jit
def pair_distance(p, i, j, k):
    """Distance between rows i and j of the positions p, columns k..k+2 (k = POS_N for aircraft states
    (V, 16), 0 for (V, 3) positions): the CG separation, m (NaN if either is non-finite)."""
    return math.sqrt((p[i, k] - p[j, k]) ** 2 + (p[i, k + 1] - p[j, k + 1]) ** 2 + (p[i, k + 2] - p[j, k + 2]) ** 2)


@_jit
def min_separation(state):
    """Smallest CG distance between any two aircraft of one formation (inf for one aircraft; NaN if a
    position is non-finite)."""
    best = np.inf
    nv = state.shape[0]
    for i in range(nv):
        for j in range(i + 1, nv):
            d = pair_distance(state, i, j, POS_N)
            if d < best or d != d:
                best = d
    return best


@_jit
def min_separation_each(x, out):
    """(V,) distance from each UAV's CG to its nearest neighbour, state x (V, 16) (inf alone; NaN if
    non-finite: :func:`separation_each_known` then gives the distances at the last finite positions)."""
    nv = x.shape[0]
    for i in range(nv):
        best = np.inf
        for j in range(nv):
            if j != i:
                d = pair_distance(x, i, j, POS_N)
                if d < best or d != d:
                    best = d
        out[i] = best


@_jit
def separations_if_finite(x, out):
    """Whether every element of the states x (V, 16) is finite; if so :func:`min_separation_each` into out (the
    infos' check and distances in one call: a formation whose state is finite has finite infos)."""
    for i in range(x.shape[0]):
        for k in range(x.shape[1]):
            if not math.isfinite(x[i, k]):
                return False
    min_separation_each(x, out)
    return True


@_jit
def position_finite(x, a):
    """Whether aircraft a's CG position (state x (V, 16)) is finite."""
    return math.isfinite(x[a, POS_N]) and math.isfinite(x[a, POS_E]) and math.isfinite(x[a, POS_D])


@_jit
def step_separation(pre, pre_vel, post, dt):
    """Smallest CG distance of any pair of one formation over one physics step, never NaN (inf when
    no pair is known). A pair finite after the step: its distance after the step (as before). A pair
    with an aircraft whose state went non-finite in this step: the closest approach over the step of
    straight-line motion from the (finite) pre-step positions and velocities, so a step that both
    overlaps two aircraft and makes a state non-finite still counts as a collision. A pair with an
    aircraft non-finite before and after the step: unknown, skipped."""
    nv = post.shape[0]
    best = np.inf
    for i in range(nv):
        for j in range(i + 1, nv):
            if position_finite(post, i) and position_finite(post, j):
                d = pair_distance(post, i, j, POS_N)
            elif position_finite(pre, i) and position_finite(pre, j):
                dx = pre[i, POS_N] - pre[j, POS_N]
                dy = pre[i, POS_E] - pre[j, POS_E]
                dz = pre[i, POS_D] - pre[j, POS_D]
                vx = pre_vel[i, 0] - pre_vel[j, 0]
                vy = pre_vel[i, 1] - pre_vel[j, 1]
                vz = pre_vel[i, 2] - pre_vel[j, 2]
                if not (math.isfinite(vx) and math.isfinite(vy) and math.isfinite(vz)):
                    vx = vy = vz = 0.0
                v2 = vx * vx + vy * vy + vz * vz
                t = 0.0 if v2 == 0.0 else min(max(-(dx * vx + dy * vy + dz * vz) / v2, 0.0), dt)
                d = math.sqrt((dx + t * vx) ** 2 + (dy + t * vy) ** 2 + (dz + t * vz) ** 2)
            else:
                continue
            if d < best:
                best = d
    return best


@_jit
def separation_each_known(last, known, out):
    """(V,) distance from each UAV to its nearest neighbour at their last finite positions ``last``
    (V, 3) (``known``: a finite position was seen); inf where nothing is known (never NaN)."""
    nv = last.shape[0]
    for i in range(nv):
        best = np.inf
        if known[i]:
            for j in range(nv):
                if j != i and known[j]:
                    d = pair_distance(last, i, j, 0)
                    if d < best:
                        best = d
        out[i] = best
