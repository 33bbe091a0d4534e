"""Autopilot (thesis A.4, Table A.10), wrapped around the attitude controllers.

* speed: ``throttle = throttle_trim + Kp_V e_V + Ki_V int(e_V)``, ``e_V = V_demand - airspeed``,
  saturated to the throttle range with conditional-integration anti-windup;
* altitude, on the NED *down* coordinate Z (= -altitude): ``theta_demand = theta_trim + Kp_Z e_Z +
  Ki_Z int(e_Z) + Kd_Z de_Z/dt``, ``e_Z = Z_demand - Z``; the derivative is formed from velocities
  (``de_Z/dt = Vz_demand - Vz``), not by differencing (gains -0.03, -0.0001, -0.05: too low
  (e_Z < 0) -> nose up);
* heading: ``phi_demand = Kp_chi e_chi + Ki_chi int(e_chi)``, ``e_chi`` the wrapped difference of the
  demanded and measured direction (heading psi by default, see :class:`FCSStructure`).
"""

from __future__ import annotations

from .common import pi_integrator_rate, saturate, wrap_angle
from .gains import AutopilotGains

__all__ = ["speed_controller", "altitude_controller", "heading_controller"]


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
