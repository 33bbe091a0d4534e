"""The thesis FCS (Appendix A) layer by layer in readable numpy: the definition the compiled law
(formation_env.control.law) is held equal to. Batched over aircraft (arrays (B,) / (B, 3))."""

from __future__ import annotations

import numpy as np

from formation_env.control.gains import AttitudeGains, AutopilotGains, FCSStructure, SASGains, TrackerGains
from formation_env.control.law import CSTATE_NAMES
from formation_env.control.tracker import track_errors  # Eqs. A.16-A.21, pinned by test_fcs_policy

_I = {n: i for i, n in enumerate(CSTATE_NAMES)}


# ---------------------------------------------------------------- common (thesis A layers)
def wrap_angle(x: np.ndarray) -> np.ndarray:
    """Angle wrapped into [-pi, pi)."""
    return (np.asarray(x) + np.pi) % (2.0 * np.pi) - np.pi


def saturate(x: np.ndarray, lo, hi) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(clipped, at_upper, at_lower)``: the saturated value and where each limit is active."""
    x = np.asarray(x, dtype=float)
    return np.clip(x, lo, hi), x > hi, x < lo


def pi_integrator_rate(error: np.ndarray, ki: float, at_upper: np.ndarray, at_lower: np.ndarray,
                       anti_windup: bool) -> np.ndarray:
    """Rate of a PI controller's error integrator with conditional-integration anti-windup:
    the integral is frozen while the output is saturated and the error would drive it further
    into the limit (``ki * error`` has the sign of the exceeded limit)."""
    if not anti_windup:
        return error
    push = ki * error
    frozen = (at_upper & (push > 0.0)) | (at_lower & (push < 0.0))
    return np.where(frozen, 0.0, error)


# ---------------------------------------------------------------- sas (thesis A layers)
def washout_output_and_rate(r: np.ndarray, x_w: np.ndarray, gains: SASGains, structure: FCSStructure):
    """Washout filter on the yaw rate: output ``r_w = r - x_w`` and the low-pass state's rate.

    ``"time_constant"`` form ``T s/(T s + 1)``: ``x_w' = (r - x_w) / T``;
    ``"pole"`` form ``s/(s + T)``: ``x_w' = T (r - x_w)``.
    """
    r_w = r - x_w
    rate = r_w / gains.T_r_washout_s if structure.washout == "time_constant" else gains.T_r_washout_s * r_w
    return r_w, rate


def sas_surfaces(elevator_demand, aileron_demand, q, theta_pert, phi, r_washout, gains: SASGains,
                 structure: FCSStructure):
    """Surface perturbations about trim (rad): ``(d_elevator, d_aileron, d_rudder)``.

    ``elevator_demand``/``aileron_demand`` come from the attitude controllers; ``theta_pert`` is
    ``theta - theta_trim``.
    """
    d_elev = elevator_demand - (gains.K_q_elevator * q + gains.K_theta_elevator * theta_pert)
    d_ail = aileron_demand - gains.K_phi_aileron * phi
    interlink = aileron_demand if structure.interlink_source == "demand" else d_ail
    if structure.interlink_path == "yaw_damper":
        d_rud = -gains.K_r_rudder * (r_washout + gains.K_aileron_rudder_interlink * interlink)
    else:
        d_rud = -gains.K_r_rudder * r_washout + gains.K_aileron_rudder_interlink * interlink
    return d_elev, d_ail, d_rud


# ---------------------------------------------------------------- attitude (thesis A layers)
def pitch_controller(theta_demand, theta, integral, gains: AttitudeGains, limit: float, anti_windup: bool = True):
    """``(elevator_demand (saturated), integral_rate)``."""
    e = theta_demand - theta
    raw = gains.Kp_theta * e + gains.Ki_theta * integral
    out, hi, lo = saturate(raw, -limit, limit)
    return out, pi_integrator_rate(e, gains.Ki_theta, hi, lo, anti_windup)


def roll_controller(phi_demand, phi, integral, gains: AttitudeGains):
    """``(aileron_demand, integral_rate)`` (the aileron is saturated at the actuator)."""
    e = phi_demand - phi
    return gains.Kp_phi * e + gains.Ki_phi * integral, e


# ---------------------------------------------------------------- autopilot (thesis A layers)
def speed_controller(v_demand, airspeed, integral, throttle_trim: float, gains: AutopilotGains,
                     limits: tuple[float, float], anti_windup: bool = True):
    """``(throttle (saturated), integral_rate)``."""
    e = v_demand - airspeed
    raw = throttle_trim + gains.Kp_speed * e + gains.Ki_speed * integral
    out, hi, lo = saturate(raw, limits[0], limits[1])
    return out, pi_integrator_rate(e, gains.Ki_speed, hi, lo, anti_windup)


def altitude_controller(z_demand, z, vz_demand, vz, integral, theta_trim: float, gains: AutopilotGains):
    """``(theta_demand, integral_rate)``; z and vz are NED down position and velocity."""
    e = z_demand - z
    theta_d = theta_trim + gains.Kp_altitude * e + gains.Ki_altitude * integral + gains.Kd_altitude * (vz_demand - vz)
    return theta_d, e


def heading_controller(chi_demand, chi, integral, gains: AutopilotGains):
    """``(phi_demand, integral_rate)``."""
    e = wrap_angle(chi_demand - chi)
    return gains.Kp_heading * e + gains.Ki_heading * integral, e


# ---------------------------------------------------------------- tracker (thesis A layers)
def trajectory_tracker(position_ned, velocity_ned, position_demand_ned, velocity_demand_ned, integral,
                       gains: TrackerGains, anti_windup: bool = True):
    """``(chi_demand, V_demand, integral_rate, errors dict)``."""
    atd, otd, dotd, chi_d = track_errors(position_ned, velocity_ned, position_demand_ned, velocity_demand_ned)
    lim = gains.track_angle_demand_limit_rad
    raw = gains.Kp_offtrack * otd + gains.Ki_offtrack * integral + gains.Kd_offtrack * dotd
    corr, hi, lo = saturate(raw, -lim, lim)
    chi_demand = chi_d - corr
    speed_d = np.linalg.norm(np.asarray(velocity_demand_ned), axis=-1)
    dv, _, _ = saturate(gains.Kp_alongtrack * atd, -gains.velocity_demand_limit_mps, gains.velocity_demand_limit_mps)
    v_demand = speed_d - dv
    rate = pi_integrator_rate(otd, gains.Ki_offtrack, hi, lo, anti_windup)
    return chi_demand, v_demand, rate, {"along_track": atd, "off_track": otd, "off_track_rate": dotd,
                                        "track_demand": chi_d}


def evaluate_numpy(cfg, obs: dict, cstate: np.ndarray):
    """Continuous-time law: ``(command (B, 4), cstate_rate (B, 7), signals dict)``."""
    pos, vel = obs["position_ned"], obs["velocity_ned"]
    phi, theta, psi = obs["euler"][:, 0], obs["euler"][:, 1], obs["euler"][:, 2]
    q, r = obs["rates_body"][:, 1], obs["rates_body"][:, 2]
    pd, vd = obs["position_demand_ned"], obs["velocity_demand_ned"]
    rate = np.zeros_like(cstate)
    signals: dict = {}
    if cfg.use_tracker:
        chi_dem, v_dem, rate[:, _I["int_offtrack"]], errs = trajectory_tracker(
            pos, vel, pd, vd, cstate[:, _I["int_offtrack"]], cfg.tracker, cfg.anti_windup)
        signals.update(errs)
    else:
        chi_dem = np.arctan2(vd[:, 1], vd[:, 0])
        v_dem = np.linalg.norm(vd, axis=1)
    trim_e, trim_a, trim_r, trim_t = cfg.trim_controls
    throttle, rate[:, _I["int_speed"]] = speed_controller(
        v_dem, obs["airspeed"], cstate[:, _I["int_speed"]], trim_t, cfg.autopilot, cfg.throttle_limits, cfg.anti_windup)
    theta_dem, rate[:, _I["int_altitude"]] = altitude_controller(
        pd[:, 2], pos[:, 2], vd[:, 2], vel[:, 2], cstate[:, _I["int_altitude"]], cfg.trim_theta_rad, cfg.autopilot)
    chi = psi if cfg.structure.direction_feedback == "heading" else np.arctan2(vel[:, 1], vel[:, 0])
    phi_dem, rate[:, _I["int_heading"]] = heading_controller(chi_dem, chi, cstate[:, _I["int_heading"]], cfg.autopilot)
    lim = cfg.surface_limit_rad
    # the elevator demand saturates at full deflection (about trim: the total stays within limits)
    elev_dem, rate[:, _I["int_theta"]] = pitch_controller(theta_dem, theta, cstate[:, _I["int_theta"]],
                                                          cfg.attitude, lim, cfg.anti_windup)
    ail_dem, rate[:, _I["int_phi"]] = roll_controller(phi_dem, phi, cstate[:, _I["int_phi"]], cfg.attitude)
    r_w, rate[:, _I["washout"]] = washout_output_and_rate(r, cstate[:, _I["washout"]], cfg.sas, cfg.structure)
    d_e, d_a, d_r = sas_surfaces(elev_dem, ail_dem, q, theta - cfg.trim_theta_rad, phi, r_w, cfg.sas, cfg.structure)
    cmd = np.empty((cstate.shape[0], 4))
    cmd[:, 0] = np.clip(trim_e + d_e, -lim, lim)
    cmd[:, 1] = np.clip(trim_a + d_a, -lim, lim)
    cmd[:, 2] = np.clip(trim_r + d_r, -lim, lim)
    cmd[:, 3] = throttle
    signals.update({"speed_demand": v_dem, "track_angle_demand": chi_dem, "theta_demand": theta_dem,
                    "phi_demand": phi_dem, "elevator_demand": elev_dem, "aileron_demand": ail_dem})
    return cmd, rate, signals
