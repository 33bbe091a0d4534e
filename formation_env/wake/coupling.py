"""How the ELL's wake reaches the 6-DOF: the thesis's effective wind, or a load-weighted wind consistent
with the ELL's Kutta-Joukowski loads (docs/ell.md, "Coupling").

``effective_wind`` (the thesis, Dogan et al. 2005, Eqs. 4.4-4.7; the default): the translational wind is
the *uniform* mean of the other vehicles' induced velocity over the receiving vehicle's evaluation points,
the rotational wind the curl of a uniform least-squares fit of them
(:func:`formation_env.wake.kernels.effective_wind`).

``load_weighted`` (the energy tasks' coupling): the same point velocities, weighted by what the ELL's loads
are made of, so that the 6-DOF's lift, drag and rolling-moment increments are the ELL's to first order:

* the ELL wing is lift-matched (:func:`lift_matched_incidence_rad`: it carries the 6-DOF's zero-lift
  angle, so its circulation, and so the strength of the wake it sheds, is the aircraft's lift, not the
  lift of a flat plate at the body's angle of attack);
* translational wind W = sum_j |Gamma_j| l_j w_j / sum_j |Gamma_j| l_j (:func:`load_weighted_wind`): at
  fixed circulation the induced-drag change of a lifting line in an external upwash is
  -rho sum_j Gamma_j w_j l_j (Kutta-Joukowski on the bound vortex), which is the lift L tilted by the
  lift-weighted upwash, L W/V; and by Munk's reciprocity the lift response to the upwash weights it by
  the same spanwise loading, so one W carries both (the 6-DOF's own lift slope does the rest);
* roll: the ELL's first-order rolling moment dCl = (1/V) sum_j r_j (w_j . n_j) (r: the adjoint of the
  isolated vehicle's joint solve, :func:`roll_weights`), turned into the rotational wind omega_x that makes
  the 6-DOF's rolling-moment increment (Clp, Clr, and Clbeta of the sidewash W_y) equal to it; omega_y and
  omega_z stay the thesis's.

Frames: NED earth, body x forward / y starboard / z down; units SI.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import NamedTuple

import numba as nb
import numpy as np

from .arrays import evaluate_formation
from .posing import dcm_ned_to_body_1
from .residual import add_wind_residual

__all__ = ["COUPLINGS", "WAKE_FIDELITIES", "EFFECTIVE_WIND", "LOAD_WEIGHTED", "CouplingArrays", "coupling_arrays", "coupling_code",
           "lift_matched_incidence_rad", "lift_matched_vehicle", "roll_weights", "load_weighted_wind", "coupled_wind", "couple_solved"]

EFFECTIVE_WIND, LOAD_WEIGHTED = 0, 1
COUPLINGS = {"effective_wind": EFFECTIVE_WIND, "load_weighted": LOAD_WEIGHTED}
#: how finely the ELL resolves the wake another vehicle meets (a scenario's and EnvConfig's ``wake_fidelity``;
#: resolved into a WakeConfig by formation_env.sim.formation.resolve_wake): "lattice" the thesis's nseg-10
#: horseshoes with discrete trailing legs (the saving ripples with the leg spacing within ~0.1 b of a wake plane);
#: "sheet" the other vehicles' legs as a continuous sheet near their wake plane; "converged" the sheet law, the
#: span-efficiency correction and the residual table of pairs (the saving and load-weighted wind of an nseg-80
#: lattice at the nseg-10 cost: the energy tasks', docs/ell.md)
WAKE_FIDELITIES = ("lattice", "sheet", "converged")

_jit = nb.njit(cache=True, error_model="numpy")


class CouplingArrays(NamedTuple):
    """What the compiled coupling needs (N panels of the formation's lattice)."""

    mode: int  # EFFECTIVE_WIND | LOAD_WEIGHTED
    panel_length_m: np.ndarray  # (N,) length of each bound vortex X1[k] -> X1[k+1], m
    roll_weight: np.ndarray  # (N,) r_j: the ELL's rolling-moment coefficient times V per unit normal wash (m/s)
    normal_b: np.ndarray  # (N, 3) panel normals, body axes (the lattice's)
    cl_beta: float  # the 6-DOF's rolling-moment derivatives (per rad, per unit p b / 2V, r b / 2V)
    cl_p: float
    cl_r: float
    span_m: float  # the 6-DOF's reference span, m (its b / 2V)


def coupling_code(name: str) -> int:
    """The kernels' code of a coupling name (:data:`COUPLINGS`); ValueError naming the allowed ones."""
    if name not in COUPLINGS:
        raise ValueError(f"wake coupling must be one of {tuple(COUPLINGS)}, got {name!r}")
    return COUPLINGS[name]


def lift_matched_incidence_rad(params) -> float:
    """The ELL wing's incidence that makes its lift the 6-DOF's: the aircraft's zero-lift angle
    CL0 / CLa (rad; AeroSim Aerosonde 0.23 / 5.6106 = 0.0410 rad = 2.35 deg). The ELL wing's lift slope
    (5.61 /rad for Table 6.1's wing with 10 horseshoes, measured) equals CLa, so with this incidence the
    ELL lift follows CL0 + CLa alpha at every alpha (trim: 104.4 N against the 6-DOF's 103 N, where the
    flat Table 6.1 wing gives 60.4 N)."""
    return float(params.CL0 / params.CLa)


def lift_matched_vehicle(vehicle, params):
    """``vehicle`` with its first (main) lifting surface at :func:`lift_matched_incidence_rad` (added to
    the surface's own incidence); other surfaces unchanged."""
    wing = vehicle.surfaces[0]
    wing = dataclasses.replace(wing, incidence_rad=wing.incidence_rad + lift_matched_incidence_rad(params))
    return dataclasses.replace(vehicle, surfaces=(wing,) + tuple(vehicle.surfaces[1:]))


def _isolated_aic(alone, airspeed_mps: float) -> tuple[np.ndarray, np.ndarray]:
    """AIC (N, N) of a one-vehicle model ``alone`` at zero attitude, alpha and beta (trailing legs
    along body x), by unit circulations through its own field law (the solve's: plain, Eq. 4.31
    cutoff), and the panel normals; A[j, p] = velocity of unit horseshoe p at control point j, dot n_j."""
    from .model import WakeSolution
    from .state import FormationState

    t = alone.template
    n = t.n_panels
    state = FormationState(np.zeros((1, 1, 3)), np.zeros((1, 1, 3)), np.full((1, 1), airspeed_mps), np.zeros((1, 1)),
                           np.zeros((1, 1)))
    zeros = np.zeros((1, 1, 3))
    aic = np.empty((n, n))
    cp = t.control_b[None]  # at zero attitude and position, body axes = NED
    for p in range(n):
        g = np.zeros((1, n))
        g[0, p] = 1.0
        sol = WakeSolution(g, np.zeros((1, n, 3)), zeros, zeros, zeros, zeros)
        vel = alone.induced_velocity(state, sol, cp, only_vehicle=0, core="none")[0]
        aic[:, p] = np.sum(vel * t.normal_b, axis=1)
    return aic, t.normal_b


def roll_weights(vehicle, ref_area_m2: float, ref_span_m: float, airspeed_mps: float = 25.0) -> np.ndarray:
    """(n,) r_j of one vehicle (a frozen, hashable :class:`~formation_env.geometry.Vehicle`; built once per
    vehicle and reference geometry): see :func:`_roll_weights`."""
    return _roll_weights(vehicle, float(ref_area_m2), float(ref_span_m), float(airspeed_mps)).copy()


@functools.lru_cache(maxsize=32)
def _roll_weights(vehicle, ref_area_m2: float, ref_span_m: float, airspeed_mps: float) -> np.ndarray:
    """(n,) r_j of one vehicle: its first-order Kutta-Joukowski rolling-moment coefficient in an external
    wash w, dCl = (1/V) sum_j r_j (w_j . n_j) at the control points.

    The joint solve's response to the wash is dGamma = -A^-1 (w . n) (boundary condition
    (V_ind + V_inf + w) . n = 0); the bound vortex k carries rho V Gamma_k (0, l_z, -l_y) (body), so its
    moment about the origin is M_x = -rho V Gamma_k (l_y y_k + l_z z_k). Hence
    dM_x = rho V (l_y y + l_z z)^T A^-1 (w . n), i.e. r = (2 / (S b)) A^-T (l_y y + l_z z) with S, b the
    6-DOF's reference area and span. A is the isolated vehicle's (trailing legs along body x: r changes by
    0.1 % from alpha 0 to 6 deg, measured).
    The coefficient is V- and rho-independent."""
    from .model import WakeModel

    alone = WakeModel([vehicle])
    aic, _ = _isolated_aic(alone, airspeed_mps)
    t = alone.template
    left = t.panel_left_knot
    lvec = t.knot_x1_b[left + 1] - t.knot_x1_b[left]
    mid = 0.5 * (t.knot_x1_b[left + 1] + t.knot_x1_b[left])
    arm = lvec[:, 1] * mid[:, 1] + lvec[:, 2] * mid[:, 2]
    # dGamma = -A^-1 wn; dM_x = -rho V sum dGamma arm = rho V arm^T A^-1 wn; dCl V = 2 arm^T A^-1 wn / (S b)
    return 2.0 * np.linalg.solve(aic.T, arm) / (ref_area_m2 * ref_span_m)


def coupling_arrays(model, mode: str, params) -> CouplingArrays:
    """The :class:`CouplingArrays` of ``model`` (a :class:`~formation_env.wake.WakeModel`) for the coupling
    ``mode`` (a :data:`COUPLINGS` name), with the 6-DOF's rolling derivatives and reference geometry from
    ``params`` (:class:`~formation_env.aircraft.AerosondeParams`). The roll weights are computed for
    ``load_weighted`` only (zeros otherwise: unused)."""
    code = coupling_code(mode)
    t = model.template
    left = t.panel_left_knot
    length = np.linalg.norm(t.knot_x1_b[left + 1] - t.knot_x1_b[left], axis=1)
    roll = np.zeros(t.n_panels)
    if code == LOAD_WEIGHTED:
        cache: dict = {}
        vs = t.vehicle_panel_start
        for v, vehicle in enumerate(model.vehicles):
            if vehicle not in cache:
                cache[vehicle] = roll_weights(vehicle, params.area, params.span)
            roll[vs[v]:vs[v + 1]] = cache[vehicle]
    return CouplingArrays(mode=code, panel_length_m=np.ascontiguousarray(length),
                          roll_weight=np.ascontiguousarray(roll),
                          normal_b=np.ascontiguousarray(t.normal_b, dtype=float), cl_beta=float(params.Clbeta),
                          cl_p=float(params.Clp), cl_r=float(params.Clr), span_m=float(params.span))


@_jit
def load_weighted_wind(rot, vpts, gamma, c, vehicle_panel_start, wind_ned_out, wind_b_out, omega_b_out, omega_ned_out):
    """The load-weighted wind of every vehicle of one formation (see the module docstring), overwriting
    the translational wind (NED and body) and omega_x (body; omega_y, omega_z as given, then the NED
    rotational wind from the body one). rot (V, 3, 3) NED -> body; vpts (N, 3) the other vehicles'
    induced velocity at the evaluation points, m/s NED; gamma (N,) the solve's circulation, m^2/s;
    ``c`` a :class:`CouplingArrays`. A vehicle whose circulation is all zero gets the uniform mean."""
    nv = rot.shape[0]
    for v in range(nv):
        j0 = vehicle_panel_start[v]
        j1 = vehicle_panel_start[v + 1]
        wsum = 0.0
        for j in range(j0, j1):
            wsum += abs(gamma[j]) * c.panel_length_m[j]
        m0 = 0.0
        m1 = 0.0
        m2 = 0.0
        roll = 0.0  # sum_j r_j (w_j . n_j), body: the ELL's dCl times V, m/s
        for j in range(j0, j1):
            wj = abs(gamma[j]) * c.panel_length_m[j] / wsum if wsum > 0.0 else 1.0 / (j1 - j0)
            m0 += wj * vpts[j, 0]
            m1 += wj * vpts[j, 1]
            m2 += wj * vpts[j, 2]
            wn = 0.0
            for a in range(3):
                wb = rot[v, a, 0] * vpts[j, 0] + rot[v, a, 1] * vpts[j, 1] + rot[v, a, 2] * vpts[j, 2]
                wn += wb * c.normal_b[j, a]
            roll += c.roll_weight[j] * wn
        wind_ned_out[v, 0] = m0
        wind_ned_out[v, 1] = m1
        wind_ned_out[v, 2] = m2
        for a in range(3):
            wind_b_out[v, a] = rot[v, a, 0] * m0 + rot[v, a, 1] * m1 + rot[v, a, 2] * m2
        # 6-DOF: dCl = -Clbeta W_y / V - (b / 2V) (Clp omega_x + Clr omega_z); equal to roll / V:
        omega_b_out[v, 0] = -2.0 * (roll + c.cl_beta * wind_b_out[v, 1]
                                    + c.cl_r * omega_b_out[v, 2] * 0.5 * c.span_m) / (c.cl_p * c.span_m)
        for i in range(3):
            omega_ned_out[v, i] = (rot[v, 0, i] * omega_b_out[v, 0] + rot[v, 1, i] * omega_b_out[v, 1]
                                   + rot[v, 2, i] * omega_b_out[v, 2])


@_jit
def coupled_wind(wake, coupling, pos, euler, speed, alpha, beta, gamma_out, vpts_out, wind_ned_out, wind_b_out,
                 omega_b_out, omega_ned_out, keep=None):
    """The ELL solve of one formation (:func:`formation_env.wake.arrays.evaluate_formation`: pose, joint
    solve, the thesis's effective wind), then :func:`couple_solved`. Arguments as ``evaluate_formation``'s,
    ``coupling`` a :class:`CouplingArrays`."""
    evaluate_formation(wake, pos, euler, speed, alpha, beta, gamma_out, vpts_out, wind_ned_out, wind_b_out,
                       omega_b_out, omega_ned_out, keep)
    couple_solved(wake, coupling, pos, euler, gamma_out, vpts_out, wind_ned_out, wind_b_out, omega_b_out, omega_ned_out)


@_jit
def couple_solved(wake, coupling, pos, euler, gamma, vpts, wind_ned_out, wind_b_out, omega_b_out, omega_ned_out):
    """After one formation's solve (its circulation ``gamma``, the induced velocity ``vpts`` at the evaluation
    points and the thesis's effective wind in the outputs): with the ``load_weighted`` coupling the
    load-weighted wind in its place, plus, where ``wake.residual`` is a table, every ordered pair's residual
    (:func:`formation_env.wake.residual.add_wind_residual`); nothing with the thesis's effective wind."""
    if coupling.mode == LOAD_WEIGHTED:
        nv = pos.shape[0]
        rot = np.empty((nv, 3, 3))
        for v in range(nv):
            dcm_ned_to_body_1(euler[v, 0], euler[v, 1], euler[v, 2], rot[v])
        load_weighted_wind(rot, vpts, gamma, coupling, wake.lattice.vehicle_panel_start, wind_ned_out, wind_b_out,
                           omega_b_out, omega_ned_out)
        add_wind_residual(wake, wake.residual, pos, euler, gamma, rot, wind_ned_out, wind_b_out, omega_b_out,
                          omega_ned_out)
