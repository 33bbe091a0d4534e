"""Chapter 5.4 validation study: the delta wing of Table 5.5 (V = 19.8171 m/s, alpha = theta =
8 deg) leading an identical follower, swept laterally, longitudinally and vertically.

Each sweep gives, per follower position, the follower's effective induced wind in its body axes
(translational m/s, rotational rad/s), the change of its angle of attack, and two estimates of its
incremental lift coefficient:

* ``dCL_buildup``: the thesis's method (Eq. 5.24): dCL = CL_alpha (alpha_2 - alpha_1), alpha_2 from
  the air-relative velocity V_1 - Vi (Eqs. 5.19, 5.21), CL_alpha the isolated wing's ELL lift
  slope. The CL_q term is left out: the thesis takes CL_q from Dogan et al. and does not print it;
  the pitch-rate input (-omega_y) is reported alongside.
* the Kutta-Joukowski increments (formation minus isolated) of every force and moment coefficient
  and the induced-drag saving. With only 10 panels, and the follower's wing in the plane of the
  leader's trailing legs, these carry a ripple of one panel width as legs pass control points.

The study uses quarter-chord evaluation points (section 4.3.7; the chapter 5.4 figures), the
default Kurylowich core with the viscous AIC (smooth loads as the follower crosses the leader's
legs) and the thesis's nseg = 10, on a 0.05 b grid. All positions of a sweep are one batched call.
Positions are relative to the leader in NED, in spans b.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..frames import wind_axes_velocity_body
from ..geometry import delta_wing
from ..wake import FormationState, WakeModel, formation_benefit, vehicle_loads

__all__ = ["Sweep", "run_sweep", "lateral_sweep", "longitudinal_sweep", "vertical_sweep", "VALIDATION_AIRDATA"]

VALIDATION_AIRDATA = {"V_mps": 19.8171, "alpha_deg": 8.0, "theta_deg": 8.0}


@dataclass(frozen=True)
class Sweep:
    name: str
    variable: str  # "x", "y" or "z": the swept coordinate
    offsets_b: np.ndarray  # (P, 3) follower position relative to the leader, in spans
    wind_body: np.ndarray  # (P, 3) follower effective translational wind, body axes, m/s
    omega_body: np.ndarray  # (P, 3) follower effective rotational wind, body axes, rad/s
    dalpha_rad: np.ndarray  # (P,) alpha_2 - alpha_1
    dCL_buildup: np.ndarray  # (P,) Eq. 5.24 without the CL_q term
    cl_alpha_per_rad: float  # isolated wing lift slope used in dCL_buildup
    increments: dict  # Kutta-Joukowski dCL, dCD, dCY, dCl, dCm, dCn, induced_drag_saving: (P,)

    @property
    def coordinate(self) -> np.ndarray:
        return self.offsets_b[:, "xyz".index(self.variable)]

    def as_dict(self) -> dict:
        return {
            "name": self.name, "variable": self.variable, "offsets_b": self.offsets_b.tolist(),
            "wind_body": self.wind_body.tolist(), "omega_body": self.omega_body.tolist(),
            "dalpha_rad": self.dalpha_rad.tolist(), "dCL_buildup": self.dCL_buildup.tolist(),
            "cl_alpha_per_rad": self.cl_alpha_per_rad,
            "increments": {k: v.tolist() for k, v in self.increments.items()},
        }


def isolated_lift_slope(vehicle, airspeed: float, alpha_rad: float, dalpha_rad: float = np.radians(0.5)) -> float:
    """ELL lift-curve slope (per rad) of a vehicle flying alone, by central difference."""
    model = WakeModel([vehicle])
    a = alpha_rad + np.array([-dalpha_rad, dalpha_rad])
    state = FormationState(np.zeros((2, 1, 3)), np.zeros((2, 1, 3)), airspeed, a[:, None], 0.0)
    cl = vehicle_loads(model, state, model.evaluate(state)).CL[:, 0]
    return float((cl[1] - cl[0]) / (2 * dalpha_rad))


def run_sweep(name: str, variable: str, offsets_b: np.ndarray, *, eval_points: str = "quarter_chord",
              core: str = "kurylowich", rotational: str = "lstsq", nseg: int = 10, viscous_aic: bool = True) -> Sweep:
    vehicle = delta_wing(nseg=nseg)
    b = vehicle.ref_span_m
    model = WakeModel([vehicle, vehicle], eval_points=eval_points, core=core, rotational=rotational, viscous_aic=viscous_aic)
    offsets_b = np.asarray(offsets_b, dtype=float)
    p = offsets_b.shape[0]
    pos = np.zeros((p, 2, 3))
    pos[:, 1] = offsets_b * b
    euler = np.zeros((p, 2, 3))
    euler[..., 1] = np.radians(VALIDATION_AIRDATA["theta_deg"])
    state = FormationState(pos, euler, VALIDATION_AIRDATA["V_mps"], np.radians(VALIDATION_AIRDATA["alpha_deg"]), 0.0)
    sol = model.evaluate(state)
    fb = formation_benefit(model, state, sol)
    inc = {k: v[:, 1] for k, v in fb.items() if k.startswith("d") or k == "induced_drag_saving"}
    v_air = np.asarray(wind_axes_velocity_body(VALIDATION_AIRDATA["V_mps"], np.radians(VALIDATION_AIRDATA["alpha_deg"]), 0.0))
    v2 = v_air - sol.wind_body[:, 1]  # Eq. 5.19: air-relative velocity = ground velocity - wind
    dalpha = np.arctan2(v2[:, 2], v2[:, 0]) - np.radians(VALIDATION_AIRDATA["alpha_deg"])
    cla = isolated_lift_slope(vehicle, VALIDATION_AIRDATA["V_mps"], np.radians(VALIDATION_AIRDATA["alpha_deg"]))
    return Sweep(name, variable, offsets_b, sol.wind_body[:, 1], sol.omega_body[:, 1], dalpha, cla * dalpha, cla, inc)


def lateral_sweep(y_b=None, x_b: float = -2.0, z_b: float = 0.0, **kw) -> Sweep:
    """Fig. 5.6 / 5.10: x = -2b, z = 0, y swept."""
    y_b = np.round(np.linspace(-2.0, 2.0, 81), 6) if y_b is None else np.asarray(y_b, dtype=float)
    return run_sweep("lateral", "y", np.stack([np.full_like(y_b, x_b), y_b, np.full_like(y_b, z_b)], -1), **kw)


def longitudinal_sweep(x_b=None, y_b: float = 1.0, z_b: float = 0.5, **kw) -> Sweep:
    """Fig. 5.7: y = b, z = b/2, x swept."""
    x_b = np.round(np.linspace(-5.0, 2.0, 141), 6) if x_b is None else np.asarray(x_b, dtype=float)
    return run_sweep("longitudinal", "x", np.stack([x_b, np.full_like(x_b, y_b), np.full_like(x_b, z_b)], -1), **kw)


def vertical_sweep(z_b=None, x_b: float = -2.0, y_b: float = 1.0, **kw) -> Sweep:
    """Fig. 5.8 (y = b) and the y = 0.75b case of Figs. 5.10-5.16: x = -2b, z swept."""
    z_b = np.round(np.linspace(-1.0, 1.0, 41), 6) if z_b is None else np.asarray(z_b, dtype=float)
    return run_sweep(f"vertical_y{y_b:g}b", "z", np.stack([np.full_like(z_b, x_b), np.full_like(z_b, y_b), z_b], -1), **kw)
