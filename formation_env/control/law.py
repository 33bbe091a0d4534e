"""The thesis FCS (Appendix A) as one compiled control law per aircraft.

:func:`fcs_law` is the continuous-time law of :class:`formation_env.control.PIDFlightControl`
(trajectory tracker A.5 -> autopilot A.4 -> attitude A.3 -> SAS A.2), one aircraft per call, so
the batched decision step (:mod:`formation_env.sim.step`) flies a PID-commanded UAV at the cost of
a learned one. Gains come in one named struct, :class:`FCSParams` (built by :func:`fcs_params` from
an :class:`~formation_env.control.gains.FCSConfig`). The readable numpy layers it implements are
held equal to it in ``tests/oracles``.

Frames: NED earth, body x forward / y starboard / z down; angles rad; controls (elevator, aileron,
rudder) rad and throttle 0..1. Controller state columns: :data:`CSTATE_NAMES`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb

__all__ = ["FCSParams", "fcs_params", "fcs_law", "fcs_update", "fcs_law_batch", "CSTATE_NAMES", "N_CSTATE",
           "SIGNAL_NAMES", "settled_controller"]

SIGNAL_NAMES = ("speed_demand", "track_angle_demand", "theta_demand", "phi_demand", "elevator_demand",
                "aileron_demand", "along_track", "off_track", "off_track_rate", "track_demand")
CSTATE_NAMES = ("int_speed", "int_altitude", "int_theta", "int_phi", "int_heading", "int_offtrack", "washout")
N_CSTATE = len(CSTATE_NAMES)
_INT_SPEED, _INT_ALT, _INT_THETA, _INT_PHI, _INT_HEADING, _INT_OFFTRACK, _WASHOUT = range(N_CSTATE)

_jit = nb.njit(cache=True, error_model="numpy")


class FCSParams(NamedTuple):
    """Every number the law needs (thesis Tables A.8-A.10, A.13; flags encode FCSStructure)."""

    K_q_elevator: float
    K_theta_elevator: float
    K_r_rudder: float
    T_r_washout_s: float
    K_phi_aileron: float
    K_aileron_rudder_interlink: float
    Kp_theta: float
    Ki_theta: float
    Kp_phi: float
    Ki_phi: float
    Kp_altitude: float
    Ki_altitude: float
    Kd_altitude: float
    Kp_heading: float
    Ki_heading: float
    Kp_speed: float
    Ki_speed: float
    Kp_offtrack: float
    Ki_offtrack: float
    Kd_offtrack: float
    Kp_alongtrack: float
    velocity_demand_limit_mps: float
    track_angle_demand_limit_rad: float
    trim_elevator: float
    trim_aileron: float
    trim_rudder: float
    trim_throttle: float
    trim_theta_rad: float
    surface_limit_rad: float
    throttle_min: float
    throttle_max: float
    dt_s: float
    use_tracker: bool
    anti_windup: bool
    interlink_from_demand: bool  # FCSStructure.interlink_source == "demand"
    washout_time_constant: bool  # FCSStructure.washout == "time_constant"
    feedback_heading: bool  # FCSStructure.direction_feedback == "heading"
    interlink_in_yaw_damper: bool  # FCSStructure.interlink_path == "yaw_damper"


def fcs_params(config, dt_s: float) -> FCSParams:
    """The struct of an :class:`~formation_env.control.gains.FCSConfig` advanced with step ``dt_s``."""
    s, a, p, t, st = config.sas, config.attitude, config.autopilot, config.tracker, config.structure
    te, ta, tr, tt = config.trim_controls
    return FCSParams(
        K_q_elevator=float(s.K_q_elevator), K_theta_elevator=float(s.K_theta_elevator),
        K_r_rudder=float(s.K_r_rudder), T_r_washout_s=float(s.T_r_washout_s), K_phi_aileron=float(s.K_phi_aileron),
        K_aileron_rudder_interlink=float(s.K_aileron_rudder_interlink),
        Kp_theta=float(a.Kp_theta), Ki_theta=float(a.Ki_theta), Kp_phi=float(a.Kp_phi), Ki_phi=float(a.Ki_phi),
        Kp_altitude=float(p.Kp_altitude), Ki_altitude=float(p.Ki_altitude), Kd_altitude=float(p.Kd_altitude),
        Kp_heading=float(p.Kp_heading), Ki_heading=float(p.Ki_heading),
        Kp_speed=float(p.Kp_speed), Ki_speed=float(p.Ki_speed),
        Kp_offtrack=float(t.Kp_offtrack), Ki_offtrack=float(t.Ki_offtrack), Kd_offtrack=float(t.Kd_offtrack),
        Kp_alongtrack=float(t.Kp_alongtrack), velocity_demand_limit_mps=float(t.velocity_demand_limit_mps),
        track_angle_demand_limit_rad=float(t.track_angle_demand_limit_rad),
        trim_elevator=float(te), trim_aileron=float(ta), trim_rudder=float(tr), trim_throttle=float(tt),
        trim_theta_rad=float(config.trim_theta_rad), surface_limit_rad=float(config.surface_limit_rad),
        throttle_min=float(config.throttle_limits[0]), throttle_max=float(config.throttle_limits[1]),
        dt_s=float(dt_s), use_tracker=bool(config.use_tracker), anti_windup=bool(config.anti_windup),
        interlink_from_demand=st.interlink_source == "demand", washout_time_constant=st.washout == "time_constant",
        feedback_heading=st.direction_feedback == "heading", interlink_in_yaw_damper=st.interlink_path == "yaw_damper")


def settled_controller(p: FCSParams, controls, theta_rad: float, phi_rad: float, yaw_rate_rad_s: float):
    """Controller state (N_CSTATE,) with which :func:`fcs_law`, flying an aircraft trimmed at ``controls``
    (elevator, aileron, rudder rad, throttle), pitch ``theta_rad`` and bank ``phi_rad`` with no tracking error,
    commands that trim: each integrator holds its loop's difference from the law's own trim (``p.trim_*``), so an
    aircraft trimmed for another weight or speed starts settled instead of winding its integrators up in flight
    (the altitude loop's Ki is 1e-4: that takes minutes). The rudder has no integrator (its trim difference,
    from the engine torque, is left to the yaw damper); the washout starts on the yaw rate."""
    import numpy as np

    c = np.zeros(N_CSTATE)
    d_theta = float(theta_rad) - p.trim_theta_rad
    if p.Ki_speed:
        c[_INT_SPEED] = (float(controls[3]) - p.trim_throttle) / p.Ki_speed
    if p.Ki_altitude:
        c[_INT_ALT] = d_theta / p.Ki_altitude
    if p.Ki_theta:
        c[_INT_THETA] = (float(controls[0]) - p.trim_elevator + p.K_theta_elevator * d_theta) / p.Ki_theta
    if p.Ki_heading:
        c[_INT_HEADING] = float(phi_rad) / p.Ki_heading
    if p.Ki_phi:
        c[_INT_PHI] = (float(controls[1]) - p.trim_aileron + p.K_phi_aileron * float(phi_rad)) / p.Ki_phi
    c[_WASHOUT] = float(yaw_rate_rad_s)
    return c


@_jit
def _clip(x, lo, hi):
    return min(max(x, lo), hi)


@_jit
def pi_integrator_rate(error, ki, at_upper, at_lower, anti_windup):
    """Conditional-integration anti-windup (A.3/A.4): the integral is frozen while the output is
    saturated and ``ki * error`` pushes further into the exceeded limit."""
    if anti_windup:
        push = ki * error
        if (at_upper and push > 0.0) or (at_lower and push < 0.0):
            return 0.0
    return error


@_jit
def trajectory_tracker(pn, pe, vn, ve, pdn, pde, vdn, vde, vdd, int_offtrack, p):
    """Thesis A.5, Eqs. A.16-A.21: ``(chi_demand, V_demand, d/dt int_offtrack, along, off-track)``."""
    chi_d = math.atan2(vde, vdn)
    c, s = math.cos(chi_d), math.sin(chi_d)
    dn, de = pn - pdn, pe - pde
    atd = c * dn + s * de
    otd = -s * dn + c * de
    dotd = -s * (vn - vdn) + c * (ve - vde)
    lim = p.track_angle_demand_limit_rad
    raw = p.Kp_offtrack * otd + p.Ki_offtrack * int_offtrack + p.Kd_offtrack * dotd
    chi_demand = chi_d - _clip(raw, -lim, lim)
    speed_d = math.sqrt(vdn * vdn + vde * vde + vdd * vdd)
    v_demand = speed_d - _clip(p.Kp_alongtrack * atd, -p.velocity_demand_limit_mps, p.velocity_demand_limit_mps)
    rate = pi_integrator_rate(otd, p.Ki_offtrack, raw > lim, raw < -lim, p.anti_windup)
    return chi_demand, v_demand, rate, atd, otd


@_jit
def fcs_law(pos, vel, phi, theta, psi, q, r, airspeed, pd, vd, c, p, cmd, rate, sig):
    """Continuous-time law of one aircraft: command (4,) and controller-state rates (7,) into
    ``cmd`` and ``rate``, internal signals (10,) into ``sig`` (:data:`SIGNAL_NAMES`). pos, vel, pd,
    vd (3,) NED m, m/s; euler angles rad; q, r body rad/s; airspeed m/s (relative to ambient +
    induced wind); c (7,) controller state."""
    if p.use_tracker:
        chi_dem, v_dem, rate[_INT_OFFTRACK], sig[6], sig[7] = trajectory_tracker(
            pos[0], pos[1], vel[0], vel[1], pd[0], pd[1], vd[0], vd[1], vd[2], c[_INT_OFFTRACK], p)
        chi_d = math.atan2(vd[1], vd[0])
        sig[8] = -math.sin(chi_d) * (vel[0] - vd[0]) + math.cos(chi_d) * (vel[1] - vd[1])
        sig[9] = chi_d
    else:
        chi_dem = math.atan2(vd[1], vd[0])
        v_dem = math.sqrt(vd[0] * vd[0] + vd[1] * vd[1] + vd[2] * vd[2])
        rate[_INT_OFFTRACK] = 0.0
        for k in range(6, 10):
            sig[k] = math.nan
    # speed PI -> throttle (A.4)
    e = v_dem - airspeed
    raw = p.trim_throttle + p.Kp_speed * e + p.Ki_speed * c[_INT_SPEED]
    throttle = _clip(raw, p.throttle_min, p.throttle_max)
    rate[_INT_SPEED] = pi_integrator_rate(e, p.Ki_speed, raw > p.throttle_max, raw < p.throttle_min, p.anti_windup)
    # altitude PID on the NED down coordinate -> pitch demand (A.4; derivative from velocities)
    e = pd[2] - pos[2]
    theta_dem = p.trim_theta_rad + p.Kp_altitude * e + p.Ki_altitude * c[_INT_ALT] + p.Kd_altitude * (vd[2] - vel[2])
    rate[_INT_ALT] = e
    # heading PI -> bank demand (A.4)
    chi = psi if p.feedback_heading else math.atan2(vel[1], vel[0])
    e = (chi_dem - chi + math.pi) % (2.0 * math.pi) - math.pi
    phi_dem = p.Kp_heading * e + p.Ki_heading * c[_INT_HEADING]
    rate[_INT_HEADING] = e
    # pitch PI -> elevator demand, saturated at full deflection (A.3)
    lim = p.surface_limit_rad
    e = theta_dem - theta
    raw = p.Kp_theta * e + p.Ki_theta * c[_INT_THETA]
    elev_dem = _clip(raw, -lim, lim)
    rate[_INT_THETA] = pi_integrator_rate(e, p.Ki_theta, raw > lim, raw < -lim, p.anti_windup)
    # bank PI -> aileron demand (A.3)
    e = phi_dem - phi
    ail_dem = p.Kp_phi * e + p.Ki_phi * c[_INT_PHI]
    rate[_INT_PHI] = e
    # SAS (A.2): washed-out yaw damper, pitch and spiral stabilisers, aileron-rudder interlink
    r_w = r - c[_WASHOUT]
    rate[_WASHOUT] = r_w / p.T_r_washout_s if p.washout_time_constant else p.T_r_washout_s * r_w
    d_e = elev_dem - (p.K_q_elevator * q + p.K_theta_elevator * (theta - p.trim_theta_rad))
    d_a = ail_dem - p.K_phi_aileron * phi
    interlink = ail_dem if p.interlink_from_demand else d_a
    if p.interlink_in_yaw_damper:
        d_r = -p.K_r_rudder * (r_w + p.K_aileron_rudder_interlink * interlink)
    else:
        d_r = -p.K_r_rudder * r_w + p.K_aileron_rudder_interlink * interlink
    cmd[0] = _clip(p.trim_elevator + d_e, -lim, lim)
    cmd[1] = _clip(p.trim_aileron + d_a, -lim, lim)
    cmd[2] = _clip(p.trim_rudder + d_r, -lim, lim)
    cmd[3] = throttle
    sig[0], sig[1], sig[2], sig[3], sig[4], sig[5] = v_dem, chi_dem, theta_dem, phi_dem, elev_dem, ail_dem


@_jit
def fcs_update(pos, vel, phi, theta, psi, q, r, airspeed, pd, vd, c, p, cmd, rate, sig):
    """One PID step: the command into ``cmd`` and the controller state ``c`` advanced in place by
    one explicit-Euler step of ``p.dt_s`` (the rates already include the anti-windup freezes)."""
    fcs_law(pos, vel, phi, theta, psi, q, r, airspeed, pd, vd, c, p, cmd, rate, sig)
    for k in range(c.shape[0]):
        c[k] = c[k] + p.dt_s * rate[k]


@nb.njit(cache=True, error_model="numpy")
def fcs_law_batch(pos, vel, euler, rates, airspeed, pd, vd, cstate, p, cmd, rate, sig):
    """:func:`fcs_law` over B aircraft: arrays (B, 3) / (B,) / (B, 7) in; cmd (B, 4), rate (B, 7),
    sig (B, 10) out."""
    for i in range(pos.shape[0]):
        fcs_law(pos[i], vel[i], euler[i, 0], euler[i, 1], euler[i, 2], rates[i, 1], rates[i, 2], airspeed[i], pd[i],
                vd[i], cstate[i], p, cmd[i], rate[i], sig[i])
