"""ELL: the extended-lifting-line wake model of a formation (thesis chapter 4), batched.

>>> from formation_env.geometry import verification_wing
>>> from formation_env.wake import WakeModel, FormationState
>>> model = WakeModel([verification_wing(), verification_wing()])
>>> state = FormationState.from_degrees([[0, 0, 0], [-1, -1, 0]], [[0, 0, 0]] * 2, 25.0, 5.0)
>>> sol = model.evaluate(state)
>>> sol.wind_ned.shape      # (B, V, 3) effective induced translational wind, m/s
(1, 2, 3)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..geometry import Vehicle
from ..threads import run_parallel, threads
from . import kernels
from .arrays import lattice_arrays
from .biot_savart import SHEET_OFF, SHEET_ON
from .lattice import EVAL_POINTS, ROTATIONAL_METHODS, build_template, gradient_weights
from .state import FormationState

__all__ = ["WakeModel", "WakeSolution", "CORES", "AIR_KINEMATIC_VISCOSITY_SL"]

CORES = {"none": kernels.CORE_NONE, "lamb_oseen": kernels.CORE_LAMB_OSEEN, "kurylowich": kernels.CORE_KURYLOWICH}
AIR_KINEMATIC_VISCOSITY_SL = 1.4607e-5  # m^2/s, ISA sea level
# Above this many formations the batch is spread over threads; below it thread start-up costs more
# than it saves.
_PARALLEL_MIN_BATCH = 16


@dataclass(frozen=True)
class WakeSolution:
    """ELL output for B formations of V vehicles with N panels in all.

    circulation:       (B, N) horseshoe strengths Gamma, m^2/s (positive lifts; the thesis's G = -Gamma).
    point_velocity_ned:(B, N, 3) induced velocity at each panel's evaluation point from the *other*
                       vehicles, m/s (NED).
    wind_ned, wind_body:   (B, V, 3) effective induced translational wind (mean over the vehicle's
                       evaluation points), m/s, in NED and in the vehicle's body axes.
    omega_body, omega_ned: (B, V, 3) effective induced rotational wind (Eq. 4.7), rad/s.
    """

    circulation: np.ndarray
    point_velocity_ned: np.ndarray
    wind_ned: np.ndarray
    wind_body: np.ndarray
    omega_body: np.ndarray
    omega_ned: np.ndarray


class WakeModel:
    """The ELL model for a fixed formation make-up (a sequence of vehicles, any planforms).

    Parameters
    ----------
    vehicles:
        The vehicles of the formation, in order; every one sheds and feels wake (any can lead).
    core:
        Viscous core on the trailing legs for the field velocity: ``"kurylowich"`` (default,
        rc = 36.2 sqrt(nu tau) / cos^2 sweep), ``"lamb_oseen"`` (rc = 2.24 sqrt(nu tau)) or ``"none"``.
    eval_points:
        Where the induced velocity is sampled on each receiving vehicle: ``"control"`` (3/4-chord
        control points; reproduces Tables 5.3/5.4) or ``"quarter_chord"`` (1/4-chord panel
        midpoints, the text of section 4.3.7; reproduces the chapter 5.4 figures).
    rotational:
        How the rotational wind is derived from the point velocities: ``"lstsq"`` (default; a
        least-squares gradient over the directions the points span) or the thesis's finite
        differences ``"eq4_82"``, ``"eq5_10"``, ``"eq6_1"`` (see ``lattice.gradient_weights``).
    kinematic_viscosity:
        nu of the air, m^2/s, for the vortex core growth (default ISA sea level).
    span_tol:
        Relative extent below which a direction counts as not spanned by the points (lstsq only).
    viscous_aic:
        True (default): the *other* vehicles' trailing legs carry the viscous core in the joint
        solve too, so a follower's circulation (and its loads) vary smoothly as it crosses the
        leader's trailing legs instead of spiking when a leg passes a control point. False: the
        thesis's AIC exactly (every branch plain, Eq. 4.31 cutoff). Tables 5.2-5.4 are the same
        to 1e-9 either way.
    overlap_core:
        Radius r_o of the overlap core of the *other* vehicles' branches (bound, chordwise and the
        starts of the trailing legs; the legs also keep a viscous core >= the Eq. 4.31 cutoff), as a
        fraction of the largest mean chord b / AR of the make-up (default 1.0: 0.193 m for the
        Aerosonde); ``overlap_core_m`` is the radius (see docs/ell.md). Keeps overlapping or
        coincident vehicles physical (a well-conditioned joint solve; |v| <= CORE_PEAK / (2 pi
        min(r_o, eps)) per unit strength and branch); farther than ~3 r_o from another vehicle's
        lifting surface it changes nothing. 0 turns it off (the previous law, singular when vehicles
        overlap). A vehicle's own branches on its own points always keep the thesis's law (plain,
        Eq. 4.31 cutoff).
    sheet:
        The sheet law of the *other* vehicles' trailing legs (in the joint solve, the field and the
        loads): near another vehicle's wake plane (within 4-6 panel widths of a leg) each leg's strength
        is spread over its strip, so the wake is the continuous sheet of the piecewise-linear
        circulation rather than single legs (:func:`formation_env.wake.biot_savart.leg_sheet`), averaged
        over the receiving panel (docs/ell.md, "Converged saving"). Default False: the thesis's discrete legs.
    saving_scale:
        Factor on the induced-drag saving (``formation_benefit``'s ``induced_drag_saving``, the compiled
        :func:`formation_env.wake.benefit.induced_drag_saving_one`): 1.0 (the default, the thesis) leaves it
        as the lattice gives it; :func:`formation_env.wake.converged.span_efficiency_scale` is the ratio of
        the coarse to a converged lattice's isolated induced drag per unit lift squared, which removes the
        coarse lattice's 1/nseg bias of the ratio (docs/ell.md, "Converged saving"). Nothing else changes.
    residual:
        None (default): the lattice as it is. A :class:`~formation_env.wake.residual.ResidualTable`: every ordered
        pair's tabulated residual (a fine lattice minus this one) is added to the induced-drag saving and to the
        ``load_weighted`` coupling's winds of the compiled paths (:func:`formation_env.wake.coupling.coupled_wind`,
        :func:`formation_env.wake.benefit.induced_drag_saving_one`, ``formation_benefit``); built for the
        lift-matched Aerosonde with the sheet law and span correction (``WakeConfig(residual_table=True)``).
        :meth:`evaluate` (the thesis's effective wind) is not corrected.
    """

    def __init__(
        self,
        vehicles: Sequence[Vehicle],
        *,
        core: str = "kurylowich",
        eval_points: str = "control",
        rotational: str = "lstsq",
        kinematic_viscosity: float = AIR_KINEMATIC_VISCOSITY_SL,
        span_tol: float = 0.1,
        viscous_aic: bool = True,
        overlap_core: float = kernels.OVERLAP_CORE_CHORD_FRACTION,
        saving_scale: float = 1.0,
        sheet: bool = False,
        residual=None,
    ) -> None:
        vehicles = tuple(vehicles)
        if not vehicles:
            raise ValueError("WakeModel: vehicles must contain at least one Vehicle")
        for v in vehicles:
            if not isinstance(v, Vehicle):
                raise ValueError(f"WakeModel: vehicles must be Vehicle objects, got {v!r}")
        if core not in CORES:
            raise ValueError(f"WakeModel: core must be one of {tuple(CORES)}, got {core!r}")
        if eval_points not in EVAL_POINTS:
            raise ValueError(f"WakeModel: eval_points must be one of {EVAL_POINTS}, got {eval_points!r}")
        if rotational not in ROTATIONAL_METHODS:
            raise ValueError(f"WakeModel: rotational must be one of {ROTATIONAL_METHODS}, got {rotational!r}")
        if not (np.isfinite(kinematic_viscosity) and kinematic_viscosity > 0):
            raise ValueError(f"WakeModel: kinematic_viscosity must be finite and > 0, got {kinematic_viscosity!r}")
        if not (np.isfinite(span_tol) and 0 < span_tol < 1):
            raise ValueError(f"WakeModel: span_tol must be in (0, 1), got {span_tol!r}")
        if not (np.isfinite(overlap_core) and overlap_core >= 0):
            raise ValueError(f"WakeModel: overlap_core must be finite and >= 0, got {overlap_core!r}")
        if not isinstance(sheet, (bool, np.bool_)):
            raise ValueError(f"WakeModel: sheet must be True or False, got {sheet!r}")
        if not (np.isfinite(saving_scale) and saving_scale > 0):
            raise ValueError(f"WakeModel: saving_scale must be finite and > 0, got {saving_scale!r}")
        from .residual import ResidualTable

        if residual is not None and not isinstance(residual, ResidualTable):
            raise ValueError(f"WakeModel: residual must be None or a ResidualTable, got {type(residual).__name__}")
        self.residual = residual
        self.vehicles = vehicles
        self.overlap_core = float(overlap_core)
        self.saving_scale = float(saving_scale)
        self.core = core
        self.eval_points = eval_points
        self.rotational = rotational
        self.kinematic_viscosity = float(kinematic_viscosity)
        self.viscous_aic = bool(viscous_aic)
        self.template = build_template(vehicles)
        t = self.template
        # r_o = fraction x the largest mean chord (S / b = b / AR) of any surface, m; the default fraction
        # gives exactly kernels.default_overlap_core (what evaluate_one uses when not told)
        r_default = float(kernels.default_overlap_core(t.knot_x1_b, t.knot_x3_b, t.surface_knot_start))
        self.overlap_core_m = (r_default if self.overlap_core == kernels.OVERLAP_CORE_CHORD_FRACTION
                               else r_default * self.overlap_core / kernels.OVERLAP_CORE_CHORD_FRACTION)
        self.sheet = bool(sheet)
        self.eval_b = t.control_b if eval_points == "control" else t.quarter_chord_b
        self.grad_w = gradient_weights(t, self.eval_b, rotational, span_tol)
        self.aic_static = kernels.static_aic(t.knot_x1_b, t.knot_x3_b, t.knot_vehicle, t.knot_surface, t.surface_knot_start,
                                             t.panel_left_knot, t.panel_vehicle, t.control_b, t.normal_b, t.cutoff_m)
        self._core_mode = CORES[core]
        # the kernels' struct, passed as the plain tuple of its fields: numba types that in C, a named tuple in
        # Python (each call)
        self._lattice = tuple(lattice_arrays(self))

    @property
    def n_vehicles(self) -> int:
        return self.template.n_vehicles

    @property
    def core_mode(self) -> int:
        """The viscous-core law of the induced velocity as the kernels' integer code
        (:data:`formation_env.wake.kernels` ``CORE_*``, from the ``core`` name); read-only."""
        return self._core_mode

    @property
    def n_panels(self) -> int:
        return self.template.n_panels

    def _check_state(self, state: FormationState) -> FormationState:
        if not isinstance(state, FormationState):
            raise ValueError(f"WakeModel: state must be a FormationState, got {type(state).__name__}")
        if state.n_vehicles != self.n_vehicles:
            raise ValueError(f"WakeModel: state has {state.n_vehicles} vehicles, the model {self.n_vehicles}")
        return state

    def evaluate(self, state: FormationState) -> WakeSolution:
        """Joint solve of every vehicle's circulation and the effective induced wind on each."""
        state = self._check_state(state)
        b, v, n = state.batch_size, self.n_vehicles, self.n_panels
        gamma = np.empty((b, n))
        vpts = np.empty((b, n, 3))
        out = [np.empty((b, v, 3)) for _ in range(4)]
        args = (self._lattice, state.position_ned, state.euler_rad, state.airspeed_mps, state.alpha_rad,
                state.beta_rad, gamma, vpts, *out, SHEET_ON if self.sheet else SHEET_OFF)
        n_threads = threads()
        if b >= _PARALLEL_MIN_BATCH and n_threads > 1:
            run_parallel(kernels.evaluate_batch_range, b, args, min(n_threads, b))
        else:
            kernels.evaluate_batch_range(*args, 0, b)
        return WakeSolution(gamma, vpts, *out)

    def induced_velocity(
        self,
        state: FormationState,
        solution: WakeSolution,
        points_ned: np.ndarray,
        exclude_vehicle: int | np.ndarray | None = None,
        *,
        only_vehicle: int | np.ndarray | None = None,
        core: str | None = None,
        overlap: bool | None = None,
        receiving_width_m: np.ndarray | None = None,
    ) -> np.ndarray:
        """Induced velocity (m/s, NED) at arbitrary field points.

        points_ned: (B, P, 3) or (P, 3) (shared by all formations). exclude_vehicle: a vehicle
        index (or one per point) whose own horseshoes are left out; None includes all.
        only_vehicle: instead, keep only that vehicle's horseshoes. core: override the model's
        viscous core for this call (e.g. ``"none"`` for the AIC-consistent law). The overlap core
        (``overlap_core_m``) and the sheet law (``sheet``) apply to every branch unless
        ``only_vehicle`` is given (one vehicle's own field: the solve's law), or when ``overlap=False``.
        receiving_width_m (P,): with the sheet law, the width (m) of the receiving bound segment through
        each point over which the other vehicles' sheet is averaged (the loads pass their panels'; None: 0).
        """
        state = self._check_state(state)
        pts = np.asarray(points_ned, dtype=float)
        if pts.ndim == 2:
            pts = np.broadcast_to(pts, (state.batch_size,) + pts.shape)
        if pts.ndim != 3 or pts.shape[0] != state.batch_size or pts.shape[-1] != 3:
            raise ValueError(f"induced_velocity: points_ned must have shape (P, 3) or (B, P, 3), got {np.shape(points_ned)}")
        if not np.all(np.isfinite(pts)):
            raise ValueError("induced_velocity: points_ned must be finite")
        if exclude_vehicle is not None and only_vehicle is not None:
            raise ValueError("induced_velocity: give exclude_vehicle or only_vehicle, not both")
        chosen = only_vehicle if only_vehicle is not None else exclude_vehicle
        vf = np.full(pts.shape[1], -1, dtype=np.int64) if chosen is None else np.broadcast_to(
            np.asarray(chosen, dtype=np.int64), (pts.shape[1],))
        if np.any((vf < -1) | (vf >= self.n_vehicles)):
            raise ValueError(f"induced_velocity: vehicle index out of range 0..{self.n_vehicles - 1}: {chosen!r}")
        if core is not None and core not in CORES:
            raise ValueError(f"induced_velocity: core must be one of {tuple(CORES)}, got {core!r}")
        core_mode = self._core_mode if core is None else CORES[core]
        others = only_vehicle is None if overlap is None else overlap  # the other vehicles' law (cores)
        rw = None
        if receiving_width_m is not None:
            rw = np.ascontiguousarray(np.broadcast_to(np.asarray(receiving_width_m, dtype=float), (pts.shape[1],)))
            bad = ~(np.isfinite(rw) & (rw >= 0))
            if bad.any():
                raise ValueError(f"induced_velocity: receiving_width_m must be finite and >= 0 (m), got "
                                 f"{rw[bad][0]!r} at point {int(np.argmax(bad))}")
        out = np.empty(pts.shape)
        kernels.field_velocity_batch(
            np.ascontiguousarray(pts), np.ascontiguousarray(vf), only_vehicle is not None, self._lattice,
            state.position_ned, state.euler_rad, state.airspeed_mps, state.alpha_rad, state.beta_rad,
            np.ascontiguousarray(solution.circulation), core_mode, self.overlap_core_m if others else 0.0, out,
            SHEET_ON if (self.sheet and others) else SHEET_OFF, rw,
        )
        return out

    def points_ned(self, state: FormationState, which: str = "eval") -> np.ndarray:
        """NED positions (B, N, 3) of every panel's ``eval`` / ``control`` / ``quarter_chord`` point."""
        t = self.template
        pb = {"eval": self.eval_b, "control": t.control_b, "quarter_chord": t.quarter_chord_b}[which]
        return _body_points_to_ned(state, pb, t.panel_vehicle)

    def knots_ned(self, state: FormationState) -> tuple[np.ndarray, np.ndarray]:
        """NED quarter-chord and three-quarter-chord knots (B, K, 3) (for plots and loads)."""
        t = self.template
        return (_body_points_to_ned(state, t.knot_x1_b, t.knot_vehicle),
                _body_points_to_ned(state, t.knot_x3_b, t.knot_vehicle))


def _body_points_to_ned(state: FormationState, points_b: np.ndarray, owner: np.ndarray) -> np.ndarray:
    from ..frames import dcm_ned_to_body

    rot = dcm_ned_to_body(state.euler_rad)  # (B, V, 3, 3)
    r = rot[:, owner]  # (B, P, 3, 3)
    return state.position_ned[:, owner] + np.einsum("bpji,pj->bpi", r, points_b)
