"""The named structs the compiled ELL kernels take (NamedTuples of arrays and scalars, as the engine's other
parameter structs): :class:`LatticeArrays`, one formation's body-axis lattice and the solve's settings;
:class:`PosedLattice`, that lattice posed in NED at one instant; :class:`WakeArrays`, the lattice with the
model's switches and corrections, as the simulator's decision step carries it. Declarations only: they are
built by :func:`formation_env.wake.arrays.lattice_arrays`, :func:`~formation_env.wake.arrays.wake_arrays` and
:func:`formation_env.wake.posing.posed_lattice`.

A kernel unpacks the fields it reads once, at its top, into locals: the loops below read the same arrays as
with positional arguments (the same operations in the same order)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["LatticeArrays", "PosedLattice", "WakeArrays"]


class LatticeArrays(NamedTuple):
    """The ELL lattice of the formation (:class:`formation_env.wake.WakeModel`) in body axes, with the settings of
    its joint solve and field. K knots, S surfaces, N panels, V vehicles; arrays C-contiguous."""

    knot_x1_b: np.ndarray  # (K, 3) quarter-chord knots, m body
    knot_x3_b: np.ndarray  # (K, 3) three-quarter-chord knots, m body
    knot_vehicle: np.ndarray  # (K,)
    knot_surface: np.ndarray  # (K,)
    surface_origin_b: np.ndarray  # (S, 3) m body
    surface_vehicle: np.ndarray  # (S,)
    surface_knot_start: np.ndarray  # (S + 1,)
    surface_panel_start: np.ndarray  # (S + 1,)
    surface_core_scale: np.ndarray  # (S,) 1 / cos^2(sweep) for the Kurylowich radius
    panel_left_knot: np.ndarray  # (N,)
    panel_vehicle: np.ndarray  # (N,)
    control_b: np.ndarray  # (N, 3) control points, m body
    normal_b: np.ndarray  # (N, 3) panel normals, body
    aic_static: np.ndarray  # (N, N) the own vehicles' constant part of the AIC (formation_env.wake.aic.static_aic)
    eval_b: np.ndarray  # (N, 3) evaluation points of the effective wind, m body
    grad_w: np.ndarray  # (N, 3) weights of the rotational wind's linear fit
    vehicle_panel_start: np.ndarray  # (V + 1,)
    cutoff_m: float  # the Eq. 4.31 cutoff, m
    core_mode: int  # the field's viscous core (formation_env.wake.kernels CORE_*)
    aic_core_mode: int  # the other vehicles' trailing legs' core in the solve (CORE_NONE: the thesis)
    kinematic_viscosity: float  # m^2/s
    overlap_core_m: float  # minimum core of the other vehicles' branches, m (WakeModel.overlap_core_m; 0: none)


class PosedLattice(NamedTuple):
    """One formation's lattice posed in NED (:func:`formation_env.wake.posing.posed_lattice`): what the solve and
    the field read besides the body-axis :class:`LatticeArrays`. V vehicles, K knots, S surfaces."""

    pos: np.ndarray  # (V, 3) body origins, m NED (the pose it was posed at)
    airspeed: np.ndarray  # (V,) true airspeed, m/s
    rot: np.ndarray  # (V, 3, 3) NED -> body DCMs
    vel: np.ndarray  # (V, 3) air-relative velocities, m/s NED
    trail: np.ndarray  # (V, 3) unit downstream direction of the trailing legs
    x1: np.ndarray  # (K, 3) quarter-chord knots, m NED
    x3: np.ndarray  # (K, 3) three-quarter-chord knots, m NED
    origin: np.ndarray  # (S, 3) surface origins, m NED
    bound_dir: np.ndarray  # (K, 3) unit bound-vortex directions
    chord_dir: np.ndarray  # (K, 3) unit chordwise-branch directions
    r1: np.ndarray  # (K, 3) scratch: vectors from a point to the x1 knots ...
    inv1: np.ndarray  # (K,) ... and their inverse lengths
    r3: np.ndarray  # (K, 3) scratch: the same for the x3 knots
    inv3: np.ndarray  # (K,)


class WakeArrays(NamedTuple):
    """The ELL of the formation (:class:`formation_env.wake.WakeModel`) as the compiled step carries it: its
    lattice and the switches and corrections the solve, the coupling and the saving read."""

    lattice: LatticeArrays
    sheet: float  # SHEET_ON: the other vehicles' trailing legs take the sheet law (WakeModel.sheet); SHEET_OFF: the
    #               thesis (a value, not a type: the thesis and the energy tasks share one compiled decision step)
    wing_origin_body: np.ndarray  # (3,) wing root quarter chord relative to the CG, body axes, m
    n_panels: int
    saving_scale: float  # factor on the induced-drag saving (WakeModel.saving_scale; 1.0: the thesis)
    residual: object  # the residual table of pairs (formation_env.wake.residual.ResidualTable; WakeModel.residual), or
    #                   formation_env.wake.residual.NO_TABLE (none; the same type, so the same compiled kernels)
