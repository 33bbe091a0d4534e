"""Loads from the circulation (Kutta-Joukowski per bound vortex) and the formation benefit.

F_k = rho Gamma_k (V_rel,k x l_k), with l_k the bound vortex X1[k] -> X1[k+1] and V_rel,k the air
velocity relative to the vehicle at the bound vortex's midpoint: minus the vehicle's air-relative
velocity plus the velocity induced there. The vehicle's own horseshoes are evaluated with the law
used in the solve (plain Biot-Savart, Eq. 4.31 cutoff); the other vehicles' with the field law
(viscous core), as the effective wind is.

Coefficients use the vehicle's reference area, span (roll, yaw) and chord (pitch); moments are
about the vehicle's body origin, in body axes. Lift, drag and side force are in wind axes.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..frames import dcm_ned_to_body
from .model import WakeModel, WakeSolution
from .state import FormationState

__all__ = ["VehicleLoads", "vehicle_loads", "isolated_loads", "formation_benefit", "isolated_model", "AIR_DENSITY_SL"]

AIR_DENSITY_SL = 1.225  # kg/m^3


@dataclass(frozen=True)
class VehicleLoads:
    """Aerodynamic loads of every vehicle from ELL, arrays (B, V[, 3]).

    force_body_n, moment_body_nm: body axes, moments about the body origin.
    lift_n, drag_n (induced drag), side_n: wind axes.
    CL, CD (induced), CY, Cl, Cm, Cn: coefficients on the vehicle's reference geometry.
    """

    force_body_n: np.ndarray
    moment_body_nm: np.ndarray
    lift_n: np.ndarray
    drag_n: np.ndarray
    side_n: np.ndarray
    CL: np.ndarray
    CD: np.ndarray
    CY: np.ndarray
    Cl: np.ndarray
    Cm: np.ndarray
    Cn: np.ndarray


def vehicle_loads(model: WakeModel, state: FormationState, solution: WakeSolution,
                  air_density: float = AIR_DENSITY_SL) -> VehicleLoads:
    """Kutta-Joukowski loads of every vehicle of the formation (own and others' wakes included)."""
    if not (np.isfinite(air_density) and air_density > 0):
        raise ValueError(f"vehicle_loads: air_density must be finite and > 0, got {air_density!r}")
    t = model.template
    x1, _ = model.knots_ned(state)  # (B, K, 3)
    left = t.panel_left_knot
    a, b = x1[:, left], x1[:, left + 1]
    mid = 0.5 * (a + b)
    owner = t.panel_vehicle
    v_own = model.induced_velocity(state, solution, mid, only_vehicle=owner, core="none")
    # with the sheet law the other vehicles' wake is averaged over each bound vortex (its force's integral)
    width = np.linalg.norm(t.knot_x1_b[left + 1] - t.knot_x1_b[left], axis=1) if model.sheet else None
    v_others = model.induced_velocity(state, solution, mid, exclude_vehicle=owner, receiving_width_m=width)
    rot = dcm_ned_to_body(state.euler_rad)  # (B, V, 3, 3)
    ub = np.stack([np.cos(state.alpha_rad) * np.cos(state.beta_rad), np.sin(state.beta_rad),
                   np.sin(state.alpha_rad) * np.cos(state.beta_rad)], axis=-1)  # (B, V, 3) body
    vel_ned = state.airspeed_mps[..., None] * np.einsum("bvji,bvj->bvi", rot, ub)
    v_rel = -vel_ned[:, owner] + v_own + v_others
    f_panel = air_density * solution.circulation[..., None] * np.cross(v_rel, b - a)  # (B, N, 3) NED
    arm = mid - state.position_ned[:, owner]
    m_panel = np.cross(arm, f_panel)
    nb, nv = state.batch_size, model.n_vehicles
    f_ned = np.zeros((nb, nv, 3))
    m_ned = np.zeros((nb, nv, 3))
    np.add.at(f_ned, (slice(None), owner), f_panel)
    np.add.at(m_ned, (slice(None), owner), m_panel)
    f_b = np.einsum("bvij,bvj->bvi", rot, f_ned)
    m_b = np.einsum("bvij,bvj->bvi", rot, m_ned)
    # Wind axes in body components.
    x_w = ub
    z_w = np.stack([-np.sin(state.alpha_rad), np.zeros_like(state.alpha_rad), np.cos(state.alpha_rad)], axis=-1)
    y_w = np.cross(z_w, x_w)
    drag = -np.sum(f_b * x_w, axis=-1)
    lift = -np.sum(f_b * z_w, axis=-1)
    side = np.sum(f_b * y_w, axis=-1)
    q = 0.5 * air_density * state.airspeed_mps**2
    s_ref = np.array([v.ref_area_m2 for v in model.vehicles])
    b_ref = np.array([v.ref_span_m for v in model.vehicles])
    c_ref = np.array([v.ref_chord_m for v in model.vehicles])
    qs = q * s_ref
    return VehicleLoads(
        force_body_n=f_b, moment_body_nm=m_b, lift_n=lift, drag_n=drag, side_n=side,
        CL=lift / qs, CD=drag / qs, CY=side / qs,
        Cl=m_b[..., 0] / (qs * b_ref), Cm=m_b[..., 1] / (qs * c_ref), Cn=m_b[..., 2] / (qs * b_ref),
    )


@lru_cache(maxsize=64)
def isolated_model(vehicle, core, eval_points, rotational, kinematic_viscosity, viscous_aic) -> WakeModel:
    """The one-vehicle model of ``vehicle`` with a formation model's options (built once per make-up)."""
    # Vehicles are frozen (hashable) dataclasses: the isolated model of each is built once.
    return WakeModel([vehicle], core=core, eval_points=eval_points, rotational=rotational,
                     kinematic_viscosity=kinematic_viscosity, viscous_aic=viscous_aic)


def isolated_loads(model: WakeModel, state: FormationState, air_density: float = AIR_DENSITY_SL) -> VehicleLoads:
    """Loads each vehicle would have flying alone with the same pose and air data."""
    per_vehicle = []
    for v, vehicle in enumerate(model.vehicles):
        alone = isolated_model(vehicle, model.core, model.eval_points, model.rotational, model.kinematic_viscosity,
                             model.viscous_aic)
        sv = FormationState(state.position_ned[:, v:v + 1], state.euler_rad[:, v:v + 1], state.airspeed_mps[:, v:v + 1],
                            state.alpha_rad[:, v:v + 1], state.beta_rad[:, v:v + 1])
        per_vehicle.append(vehicle_loads(alone, sv, alone.evaluate(sv), air_density))
    return VehicleLoads(**{f: np.concatenate([getattr(l, f) for l in per_vehicle], axis=1)
                           for f in VehicleLoads.__dataclass_fields__})


def formation_benefit(model: WakeModel, state: FormationState, solution: WakeSolution | None = None,
                      air_density: float = AIR_DENSITY_SL) -> dict:
    """Incremental coefficients (formation minus isolated) and the induced-drag saving per vehicle.

    Returns arrays (B, V): ``dCL, dCD, dCY, dCl, dCm, dCn`` and ``induced_drag_saving``
    = 1 - D_i(formation) / D_i(isolated) (positive: the formation reduces the vehicle's induced drag).
    """
    solution = model.evaluate(state) if solution is None else solution
    form = vehicle_loads(model, state, solution, air_density)
    alone = isolated_loads(model, state, air_density)
    out = {f"d{c}": getattr(form, c) - getattr(alone, c) for c in ("CL", "CD", "CY", "Cl", "Cm", "Cn")}
    with np.errstate(divide="ignore", invalid="ignore"):
        saving = np.where(np.abs(alone.drag_n) > 0, 1.0 - form.drag_n / alone.drag_n, 0.0)
    if model.saving_scale != 1.0:  # the span-efficiency correction (WakeModel saving_scale)
        saving = saving * model.saving_scale
    if getattr(model, "residual", None) is not None:  # the residual table of pairs (the saving only; the loads are the lattice's)
        from .residual import add_saving_residual

        saving = np.array(saving, dtype=float)
        for b in range(saving.shape[0]):
            add_saving_residual(model.residual, np.ascontiguousarray(state.position_ned[b], dtype=float),
                                np.ascontiguousarray(state.euler_rad[b], dtype=float), saving[b])
    out["induced_drag_saving"] = saving
    out["formation"] = form
    out["isolated"] = alone
    return out


