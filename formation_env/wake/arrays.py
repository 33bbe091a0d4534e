"""The ELL lattice of a :class:`~formation_env.wake.WakeModel` as one named struct of arrays, the
form compiled kernels take (instead of 21 positional arguments)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

import numba as nb

from .kernels import CORE_NONE, SHEET_ON, evaluate_one

__all__ = ["WakeArrays", "wake_arrays", "evaluate_formation"]


class WakeArrays(NamedTuple):
    """The ELL lattice of the formation (:class:`formation_env.wake.WakeModel`) as arrays."""

    knot_x1_b: np.ndarray
    knot_x3_b: np.ndarray
    knot_vehicle: np.ndarray
    knot_surface: np.ndarray
    surface_origin_b: np.ndarray
    surface_vehicle: np.ndarray
    surface_knot_start: np.ndarray
    surface_panel_start: np.ndarray
    surface_core_scale: np.ndarray
    panel_left_knot: np.ndarray
    panel_vehicle: np.ndarray
    control_b: np.ndarray
    normal_b: np.ndarray
    aic_static: np.ndarray
    eval_b: np.ndarray
    grad_w: np.ndarray
    vehicle_panel_start: np.ndarray
    cutoff_m: float
    core_mode: int
    aic_core_mode: int
    kinematic_viscosity: float
    overlap_core_m: float  # minimum core of the other vehicles' branches, m (WakeModel.overlap_core_m)
    sheet: float | None  # SHEET_ON: the other vehicles' trailing legs take the sheet law (WakeModel.sheet); None: the
    #                      thesis (a switch by type: each compiles its own kernels, the thesis's without the law)
    wing_origin_body: np.ndarray  # (3,) wing root quarter chord relative to the CG, body axes, m
    n_panels: int
    saving_scale: float  # factor on the induced-drag saving (WakeModel.saving_scale; 1.0: the thesis)
    residual: object  # None, or the residual table of pairs (formation_env.wake.residual.ResidualTable; WakeModel.residual):
    #                   a switch by type, as sheet



def wake_arrays(model, wing_origin_body) -> WakeArrays:
    """The struct of ``model`` (a WakeModel) with the wing origin relative to the CG (body axes, m)."""
    t = model.template
    return WakeArrays(
        knot_x1_b=t.knot_x1_b, knot_x3_b=t.knot_x3_b, knot_vehicle=t.knot_vehicle, knot_surface=t.knot_surface,
        surface_origin_b=t.surface_origin_b, surface_vehicle=t.surface_vehicle,
        surface_knot_start=t.surface_knot_start, surface_panel_start=t.surface_panel_start,
        surface_core_scale=t.surface_core_scale, panel_left_knot=t.panel_left_knot, panel_vehicle=t.panel_vehicle,
        control_b=t.control_b, normal_b=t.normal_b, aic_static=model.aic_static, eval_b=model.eval_b,
        grad_w=model.grad_w, vehicle_panel_start=t.vehicle_panel_start, cutoff_m=float(t.cutoff_m),
        core_mode=int(model.core_mode), aic_core_mode=int(model.core_mode if model.viscous_aic else CORE_NONE),
        kinematic_viscosity=float(model.kinematic_viscosity), overlap_core_m=float(model.overlap_core_m),
        sheet=SHEET_ON if model.sheet else None,
        wing_origin_body=np.ascontiguousarray(wing_origin_body, dtype=float), n_panels=int(model.n_panels),
        saving_scale=float(getattr(model, "saving_scale", 1.0)), residual=getattr(model, "residual", None))


@nb.njit(cache=True, error_model="numpy")
def evaluate_formation(w, pos, euler, airspeed, alpha, beta, gamma_out, vpts_out, wind_ned_out, wind_b_out, omega_b_out,
                       omega_ned_out, keep=None):
    """:func:`formation_env.wake.kernels.evaluate_one` (pose, joint solve, effective wind; Eqs. 4.4-4.7)
    of one formation with its lattice as the struct ``w`` (:class:`WakeArrays`); ``keep`` as
    :func:`formation_env.wake.aic.assemble_and_solve`'s."""
    evaluate_one(pos, euler, airspeed, alpha, beta, w.knot_x1_b, w.knot_x3_b, w.knot_vehicle, w.knot_surface,
                 w.surface_origin_b, w.surface_vehicle, w.surface_knot_start, w.surface_panel_start,
                 w.surface_core_scale, w.panel_left_knot, w.panel_vehicle, w.control_b, w.normal_b, w.aic_static,
                 w.eval_b, w.grad_w, w.vehicle_panel_start, w.cutoff_m, w.core_mode, w.aic_core_mode,
                 w.kinematic_viscosity, gamma_out, vpts_out, wind_ned_out, wind_b_out, omega_b_out, omega_ned_out,
                 w.overlap_core_m, w.sheet, keep)
