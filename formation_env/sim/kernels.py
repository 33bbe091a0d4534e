"""Compiled formation step: ELL effective wind -> Aerosonde RK4 -> envelope status, for B
formations of V aircraft in one call (numba, parallel over formations when B is large).

It fuses the same compiled kernels the wake and aircraft packages use
(:func:`formation_env.wake.kernels.evaluate_one`, :func:`formation_env.aircraft.kernels.rk4_batch`),
so there is no second implementation of the physics; only the envelope check is repeated here,
and a test holds it equal to :func:`formation_env.aircraft.check_envelope`.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..aircraft.kernels import _air, rk4_batch
from ..frames import quaternion_dcm_terms
from ..wake.kernels import evaluate_one

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
    va = _air(x, wind12, v)[0]
    if va < lim[0]:
        status |= _AS_LOW
    if va > lim[1]:
        status |= _AS_HIGH
    alt = -x[12]
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
    for a in range(state.shape[0]):
        x = state[a]
        e0, ex, ey, ez = x[6], x[7], x[8], x[9]
        r = np.empty((3, 3))  # body -> NED
        (r[0, 0], r[0, 1], r[0, 2], r[1, 0], r[1, 1], r[1, 2],
         r[2, 0], r[2, 1], r[2, 2]) = quaternion_dcm_terms(e0, ex, ey, ez)
        for i in range(3):
            pos[a, i] = x[10 + i] + r[i, 0] * wing_origin_b[0] + r[i, 1] * wing_origin_b[1] + r[i, 2] * wing_origin_b[2]
        vb = np.empty(3)
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
def step_one(
    state, controls, ambient, turb, held_wind, held_omega, gamma, update_wake, wake_on, wing_origin_b,
    knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
    surface_origin_b, surface_vehicle, surface_knot_start, surface_panel_start, surface_core_scale,
    panel_left_knot, panel_vehicle, control_b, normal_b, aic_static, eval_b, grad_w, vehicle_panel_start,
    cutoff, core_mode, aic_core_mode, nu,
    dt, v, pJ, pCT, pCP, eR, eM, eP, eF, tT, tP, tR, tA, lim,
    out_state, out_status,
):
    """One formation (V aircraft) by one step; held_wind/held_omega/gamma are updated in place
    when ``update_wake``."""
    nv = state.shape[0]
    wind = np.zeros((nv, 12))
    for a in range(nv):
        for i in range(3):
            wind[a, i] = ambient[a, i]
            wind[a, 3 + i] = turb[a, i]
    if update_wake:
        ok = wake_on
        if ok:
            for a in range(nv):
                for i in range(3):
                    wind[a, 6 + i] = held_wind[a, i]
                    wind[a, 9 + i] = held_omega[a, i]
                if envelope_status(state[a], wind[a], v, lim) != 0:
                    ok = False
        if ok:
            pos = np.empty((nv, 3))
            euler = np.empty((nv, 3))
            speed = np.empty(nv)
            alpha = np.empty(nv)
            beta = np.empty(nv)
            ell_inputs(state, ambient, wing_origin_b, pos, euler, speed, alpha, beta)
            scratch_pts = np.empty((panel_left_knot.shape[0], 3))
            omega_ned = np.empty((nv, 3))
            wind_b = np.empty((nv, 3))
            evaluate_one(pos, euler, speed, alpha, beta, knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
                         surface_origin_b, surface_vehicle, surface_knot_start, surface_panel_start, surface_core_scale,
                         panel_left_knot, panel_vehicle, control_b, normal_b, aic_static, eval_b, grad_w, vehicle_panel_start,
                         cutoff, core_mode, aic_core_mode, nu, gamma, scratch_pts, held_wind, wind_b, held_omega, omega_ned)
        else:
            for a in range(nv):
                for i in range(3):
                    held_wind[a, i] = 0.0
                    held_omega[a, i] = 0.0
            for j in range(gamma.shape[0]):
                gamma[j] = 0.0
    for a in range(nv):
        for i in range(3):
            wind[a, 6 + i] = held_wind[a, i]
            wind[a, 9 + i] = held_omega[a, i]
    new = rk4_batch(state, controls, wind, dt, v, pJ, pCT, pCP, eR, eM, eP, eF, tT, tP, tR, tA)
    for a in range(nv):
        for i in range(state.shape[1]):
            out_state[a, i] = new[a, i]
        out_status[a] = envelope_status(new[a], wind[a], v, lim)


def _make_batch(parallel: bool):
    @nb.njit(cache=True, parallel=parallel, error_model="numpy")
    def step_batch(
        state, controls, ambient, turb, held_wind, held_omega, gamma, update_wake, wake_on, wing_origin_b,
        knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
        surface_origin_b, surface_vehicle, surface_knot_start, surface_panel_start, surface_core_scale,
        panel_left_knot, panel_vehicle, control_b, normal_b, aic_static, eval_b, grad_w, vehicle_panel_start,
        cutoff, core_mode, aic_core_mode, nu,
        dt, v, pJ, pCT, pCP, eR, eM, eP, eF, tT, tP, tR, tA, lim,
        out_state, out_status,
    ):
        for b in nb.prange(state.shape[0]):
            step_one(state[b], controls[b], ambient[b], turb[b], held_wind[b], held_omega[b], gamma[b], update_wake,
                     wake_on, wing_origin_b, knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
                     surface_origin_b, surface_vehicle, surface_knot_start, surface_panel_start, surface_core_scale,
                     panel_left_knot, panel_vehicle, control_b, normal_b, aic_static, eval_b, grad_w, vehicle_panel_start,
                     cutoff, core_mode, aic_core_mode, nu,
                     dt, v, pJ, pCT, pCP, eR, eM, eP, eF, tT, tP, tR, tA, lim,
                     out_state[b], out_status[b])

    return step_batch


step_batch_serial = _make_batch(False)
step_batch_parallel = _make_batch(True)


@_jit
def min_separation(state):
    """Smallest CG distance between any two aircraft of one formation (inf for one aircraft)."""
    best = np.inf
    nv = state.shape[0]
    for i in range(nv):
        for j in range(i + 1, nv):
            d = math.sqrt((state[i, 10] - state[j, 10]) ** 2 + (state[i, 11] - state[j, 11]) ** 2
                          + (state[i, 12] - state[j, 12]) ** 2)
            if d < best or d != d:
                best = d
    return best


def _make_many(parallel: bool):
    @nb.njit(cache=True, parallel=parallel, error_model="numpy")
    def step_many_batch(
        state, controls, ambient_seq, turb_seq, held_wind, held_omega, gamma, step0, update_every, wake_on,
        wing_origin_b,
        knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
        surface_origin_b, surface_vehicle, surface_knot_start, surface_panel_start, surface_core_scale,
        panel_left_knot, panel_vehicle, control_b, normal_b, aic_static, eval_b, grad_w, vehicle_panel_start,
        cutoff, core_mode, aic_core_mode, nu,
        dt, v, pJ, pCT, pCP, eR, eM, eP, eF, tT, tP, tR, tA, lim,
        out_state, out_status, out_status_any, out_min_sep,
    ):
        """S = ambient_seq.shape[0] steps with the controls held: the same step_one per step;
        status flags OR-ed over the steps and the smallest separation seen are returned too."""
        nsub = ambient_seq.shape[0]
        for b in nb.prange(state.shape[0]):
            cur = state[b].copy()
            nxt = np.empty_like(cur)
            st = np.zeros(cur.shape[0], dtype=np.int64)
            for a in range(cur.shape[0]):
                out_status_any[b, a] = 0
            sep = np.inf
            for s in range(nsub):
                update = (step0 + s) % update_every == 0
                step_one(cur, controls[b], ambient_seq[s, b], turb_seq[s, b], held_wind[b], held_omega[b], gamma[b],
                         update, wake_on, wing_origin_b, knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
                         surface_origin_b, surface_vehicle, surface_knot_start, surface_panel_start, surface_core_scale,
                         panel_left_knot, panel_vehicle, control_b, normal_b, aic_static, eval_b, grad_w, vehicle_panel_start,
                         cutoff, core_mode, aic_core_mode, nu,
                         dt, v, pJ, pCT, pCP, eR, eM, eP, eF, tT, tP, tR, tA, lim,
                         nxt, st)
                cur[:, :] = nxt
                for a in range(cur.shape[0]):
                    out_status_any[b, a] |= st[a]
                d = min_separation(cur)
                if d < sep or d != d:
                    sep = d
            out_state[b] = cur
            for a in range(cur.shape[0]):
                out_status[b, a] = st[a]
            out_min_sep[b] = sep

    return step_many_batch


step_many_serial = _make_many(False)
step_many_parallel = _make_many(True)


@nb.njit(cache=True, parallel=True, error_model="numpy")
def min_separation_batch(state, out):
    """:func:`min_separation` of each formation of a batch (B, V, 16) -> out (B,)."""
    for b in nb.prange(state.shape[0]):
        out[b] = min_separation(state[b])
