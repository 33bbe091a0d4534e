"""The ELL lattice of a :class:`~formation_env.wake.WakeModel` as the named structs compiled kernels take
(:mod:`formation_env.wake.structs`), and :func:`evaluate_formation`, one formation's solve on them."""

from __future__ import annotations

import numpy as np

import numba as nb

from .biot_savart import SHEET_OFF, SHEET_ON
from .kernels import CORE_NONE, evaluate_one
from .residual import NO_TABLE
from .structs import LatticeArrays, WakeArrays

__all__ = ["LatticeArrays", "WakeArrays", "lattice_arrays", "wake_arrays", "evaluate_formation"]


def lattice_arrays(model) -> LatticeArrays:
    """The :class:`LatticeArrays` of ``model`` (a WakeModel): its lattice and the settings of its solve."""
    t = model.template
    return LatticeArrays(
        knot_x1_b=t.knot_x1_b, knot_x3_b=t.knot_x3_b, knot_vehicle=t.knot_vehicle, knot_surface=t.knot_surface,
        surface_origin_b=t.surface_origin_b, surface_vehicle=t.surface_vehicle,
        surface_knot_start=t.surface_knot_start, surface_panel_start=t.surface_panel_start,
        surface_core_scale=t.surface_core_scale, panel_left_knot=t.panel_left_knot, panel_vehicle=t.panel_vehicle,
        control_b=t.control_b, normal_b=t.normal_b, aic_static=model.aic_static, eval_b=model.eval_b,
        grad_w=model.grad_w, vehicle_panel_start=t.vehicle_panel_start, cutoff_m=float(t.cutoff_m),
        core_mode=int(model.core_mode), aic_core_mode=int(model.core_mode if model.viscous_aic else CORE_NONE),
        kinematic_viscosity=float(model.kinematic_viscosity), overlap_core_m=float(model.overlap_core_m))


def wake_arrays(model, wing_origin_body) -> WakeArrays:
    """The struct of ``model`` (a WakeModel) with the wing origin relative to the CG (body axes, m)."""
    return WakeArrays(
        lattice=lattice_arrays(model), sheet=SHEET_ON if model.sheet else SHEET_OFF,
        wing_origin_body=np.ascontiguousarray(wing_origin_body, dtype=float), n_panels=int(model.n_panels),
        saving_scale=float(getattr(model, "saving_scale", 1.0)),
        residual=NO_TABLE if getattr(model, "residual", None) is None else model.residual)


@nb.njit(cache=True, error_model="numpy")
def evaluate_formation(w, pos, euler, airspeed, alpha, beta, gamma_out, vpts_out, wind_ned_out, wind_b_out, omega_b_out,
                       omega_ned_out, keep=None):
    """:func:`formation_env.wake.kernels.evaluate_one` (pose, joint solve, effective wind; Eqs. 4.4-4.7)
    of one formation with its lattice and switches as the struct ``w`` (:class:`WakeArrays`); ``keep`` as
    :func:`formation_env.wake.aic.assemble_and_solve`'s."""
    evaluate_one(w.lattice, pos, euler, airspeed, alpha, beta, gamma_out, vpts_out, wind_ned_out, wind_b_out,
                 omega_b_out, omega_ned_out, w.sheet, keep)
