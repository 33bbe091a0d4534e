"""Attitude control (thesis A.3, Table A.9): pitch and bank P+I wrapped around the SAS.

``elevator_demand = Kp_theta e_theta + Ki_theta int(e_theta)``, ``e_theta = theta_demand - theta``
(gains -0.8, -0.8: pitch up wanted -> trailing edge up), saturated at the elevator's full
deflection with conditional-integration anti-windup. ``aileron_demand = Kp_phi e_phi + Ki_phi
int(e_phi)``, ``e_phi = phi_demand - phi`` (gains -0.2, -0.1: right bank wanted -> negative
aileron, which rolls right on AeroSim).
"""

from __future__ import annotations

from .common import pi_integrator_rate, saturate
from .gains import AttitudeGains

__all__ = ["pitch_controller", "roll_controller"]


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
