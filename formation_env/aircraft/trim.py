"""Trim of the Aerosonde: straight and level, steady climb/descent, steady coordinated turn.

Unknowns (9): alpha, beta, phi, theta, elevator, aileron, rudder, throttle, shaft speed.
Residuals (9): the six body accelerations, the shaft acceleration, the climb rate
``h_dot - V sin(gamma)`` and the lateral specific force (coordination: the "ball" centred).
For straight flight the last one forces phi = 0, i.e. the thesis's wings-level trim with the
sideslip, aileron and rudder that balance the engine reaction torque (Table A.5).
In a turn the body rates are ``psi_dot (-sin theta, sin phi cos theta, cos phi cos theta)``.
Still air, alpha-dot = 0 (a trim is steady). Fuel burn is not a residual (it is slow).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import root

from .. import frames
from .eom import DEFAULT_OPTIONS, ModelOptions, derivatives, make_state, outputs
from .params import AEROSONDE, AerosondeParams

__all__ = ["TrimResult", "trim", "trim_state_and_controls"]


@dataclass(frozen=True, eq=False)
class TrimResult:
    """A trimmed flight condition. ``state`` (1, 16) and ``controls`` (1, 4) feed :func:`eom.step`."""

    state: np.ndarray
    controls: np.ndarray
    airspeed: float
    altitude: float
    fuel: float
    flight_path_angle: float
    turn_rate: float
    alpha: float
    beta: float
    phi: float
    theta: float
    psi: float
    elevator: float
    aileron: float
    rudder: float
    throttle: float
    omega: float
    residual_norm: float
    success: bool
    extras: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        d = {k: float(getattr(self, k)) for k in (
            "airspeed", "altitude", "fuel", "flight_path_angle", "turn_rate", "alpha", "beta", "phi",
            "theta", "psi", "elevator", "aileron", "rudder", "throttle", "omega", "residual_norm")}
        d["success"] = bool(self.success)
        d["u"], d["v"], d["w"] = (float(x) for x in self.state[0, 0:3])
        d.update({k: float(v) for k, v in self.extras.items()})
        return d


def _build(z, airspeed, altitude, fuel, turn_rate):
    alpha, beta, phi, theta = z[0], z[1], z[2], z[3]
    euler = np.array([phi, theta, 0.0])
    rates = turn_rate * np.array([-np.sin(theta), np.sin(phi) * np.cos(theta), np.cos(phi) * np.cos(theta)])
    vel = frames.wind_axes_velocity_body(airspeed, alpha, beta)
    s = make_state(vel, rates, euler, (0.0, 0.0, -altitude), fuel, z[8])
    controls = np.array([[z[4], z[5], z[6], z[7]]])
    return s, controls


def _residuals(z, airspeed, altitude, fuel, gamma, turn_rate, params, options):
    s, c = _build(z, airspeed, altitude, fuel, turn_rate)
    xdot, out = derivatives(s[:, :15], c, None, 0.0, params, options, want_outputs=True)
    res = np.empty(9)
    res[0:6] = xdot[0, 0:6]
    res[6] = xdot[0, 14] * 1e-2  # shaft acceleration is large per N m (tiny inertia): rescale
    res[7] = -xdot[0, 12] - airspeed * np.sin(gamma)
    res[8] = out["specific_force_body"][0, 1]
    return res


def trim(airspeed: float = 25.0, altitude: float = 1000.0, fuel: float = 2.0,
         flight_path_angle: float = 0.0, turn_rate: float = 0.0, course: float = 0.0,
         params: AerosondeParams = AEROSONDE, options: ModelOptions = DEFAULT_OPTIONS) -> TrimResult:
    """Trim for airspeed (m/s), altitude (m), fuel (kg), flight-path angle (rad, + climbing) and
    turn rate (rad/s, + to the right). ``course`` (rad) sets the heading so that the initial
    ground track points along it (thesis: psi = -0.0006 for a northbound track).

    Raises ValueError when the arguments are out of range or no trim is found.
    """
    for name, val in (("airspeed", airspeed), ("altitude", altitude), ("fuel", fuel),
                      ("flight_path_angle", flight_path_angle), ("turn_rate", turn_rate), ("course", course)):
        if not np.isfinite(val):
            raise ValueError(f"trim: {name} must be finite, got {val!r}")
    lo, hi = params.va_bounds
    if not lo <= airspeed <= hi:
        raise ValueError(f"trim: airspeed must be within the model's bounds [{lo}, {hi}] m/s, got {airspeed}")
    if not 0.0 <= altitude <= 86000.0:
        raise ValueError(f"trim: altitude must be in [0, 86000] m, got {altitude}")
    if not 0.0 < fuel <= params.fuel_capacity:
        raise ValueError(f"trim: fuel must be in (0, {params.fuel_capacity}] kg, got {fuel}")
    if abs(flight_path_angle) > 0.5:
        raise ValueError(f"trim: |flight_path_angle| must be <= 0.5 rad, got {flight_path_angle}")
    bank_guess = np.arctan(airspeed * turn_rate / options.g)
    if abs(bank_guess) > np.deg2rad(60.0):
        raise ValueError(f"trim: turn_rate {turn_rate} rad/s needs more than 60 deg of bank")
    z0 = np.array([0.05, 0.0, bank_guess, 0.05 + flight_path_angle, -0.07, 0.0, 0.0, 0.7, 545.0])
    args = (airspeed, altitude, fuel, flight_path_angle, turn_rate, params, options)
    sol = root(_residuals, z0, args=args, method="hybr", options={"xtol": 1e-14, "maxfev": 4000})
    z = sol.x
    res = _residuals(z, *args)
    norm = float(np.max(np.abs(res)))
    ok = bool(np.isfinite(norm) and norm < 1e-8)
    if not ok:
        raise ValueError(
            f"trim: no trim found for V={airspeed} m/s, h={altitude} m, fuel={fuel} kg, "
            f"gamma={flight_path_angle} rad, turn rate={turn_rate} rad/s (residual {norm:.3g}; {sol.message})"
        )
    s, c = _build(z, airspeed, altitude, fuel, turn_rate)
    # heading: rotate so the ground track points along `course` (psi does not enter the dynamics)
    v_ned = outputs(s, c, params=params, options=options)["velocity_ned"][0]
    psi = float(np.arctan2(np.sin(course - np.arctan2(v_ned[1], v_ned[0])),
                           np.cos(course - np.arctan2(v_ned[1], v_ned[0]))))
    euler = np.array([z[2], z[3], psi])
    s = make_state(s[0, 0:3], s[0, 3:6], euler, (0.0, 0.0, -altitude), fuel, z[8])
    out = outputs(s, c, params=params, options=options)
    extras = {k: float(np.asarray(out[k]).ravel()[0]) for k in
              ("map_kpa", "power", "thrust", "engine_torque", "fuel_flow", "CL", "CD", "mass")}
    extras["fuel_flow_g_per_h"] = extras["fuel_flow"] * 3.6e6
    return TrimResult(
        state=s, controls=c, airspeed=float(airspeed), altitude=float(altitude), fuel=float(fuel),
        flight_path_angle=float(flight_path_angle), turn_rate=float(turn_rate),
        alpha=float(z[0]), beta=float(z[1]), phi=float(z[2]), theta=float(z[3]), psi=psi,
        elevator=float(z[4]), aileron=float(z[5]), rudder=float(z[6]), throttle=float(z[7]),
        omega=float(z[8]), residual_norm=norm, success=ok, extras=extras,
    )


def trim_state_and_controls(batch_size: int, **kwargs) -> tuple[np.ndarray, np.ndarray]:
    """A trim tiled for ``batch_size`` aircraft: ``(state (B, 16), controls (B, 4))``."""
    t = trim(**kwargs)
    return np.repeat(t.state, batch_size, axis=0), np.repeat(t.controls, batch_size, axis=0)
