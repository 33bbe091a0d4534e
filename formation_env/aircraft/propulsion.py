"""Fixed-pitch propeller and piston engine (AeroSim Propulsion library, Aerosonde data).

All inputs are arrays over the batch axis. The engine torque ``P / Omega`` is singular at
Omega = 0; the shaft speed is floored at ``OMEGA_FLOOR`` inside the kernels so a stopped engine
gives large but finite numbers (the envelope check reports a stalled shaft).
"""

from __future__ import annotations

import numpy as np

from .lookup import interp1_extrap, interp2_extrap
from .params import AerosondeParams

__all__ = ["propeller", "engine", "OMEGA_FLOOR"]

OMEGA_FLOOR = 1.0  # rad/s; AeroSim divides by Omega unguarded


def propeller(airspeed, rho, omega, params: AerosondeParams):
    """Thrust (N, along body +x at the hub), shaft load torque (N m, negative = absorbs power),
    advance ratio J, CT and CP. ``airspeed`` is the clipped airspeed."""
    om = np.maximum(omega, OMEGA_FLOOR)
    radius = params.prop_radius
    adv = np.pi * airspeed / (om * radius)
    ct = interp1_extrap(params.prop_J, params.prop_CT, adv)
    cp = interp1_extrap(params.prop_J, params.prop_CP, adv)
    rho_om2 = rho * om * om
    thrust = (4.0 / np.pi**2) * radius**4 * rho_om2 * ct
    torque = -(4.0 / np.pi**3) * radius**5 * rho_om2 * cp
    return thrust, torque, adv, ct, cp


def engine(throttle, p_static_pa, temperature_k, omega, params: AerosondeParams):
    """Manifold pressure (kPa), shaft power (W), engine torque (N m) and fuel flow (kg/s).

    MAP = max(MAPmin, MAPmin + throttle (p/1000 - MAPmin)); there is no upper bound (AeroSim).
    Power from the table, corrected by sqrt(T_sl / T); fuel flow has no altitude correction.
    """
    map_min = params.map_min_kpa
    map_kpa = np.maximum(map_min, map_min + throttle * (p_static_pa / 1000.0 - map_min))
    om = np.maximum(omega, OMEGA_FLOOR)
    rpm = om * (30.0 / np.pi)
    power = interp2_extrap(params.engine_rpm, params.engine_map_kpa, params.engine_power_w, rpm, map_kpa)
    power = power * np.sqrt(params.T_sl / temperature_k)
    torque = power / om
    fuel_flow = interp2_extrap(
        params.engine_rpm, params.engine_map_kpa, params.engine_fuel_flow_g_per_h, rpm, map_kpa
    ) / 3.6e6
    return map_kpa, power, torque, fuel_flow
