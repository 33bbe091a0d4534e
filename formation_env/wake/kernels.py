"""Compiled ELL kernels: Biot-Savart branches, the joint AIC solve, field velocities and the
effective wind (thesis 4.2.2-4.3.7). Pure functions over arrays with a leading batch axis.

Unit conventions: metres, m/s, radians; positions and velocities in NED unless the name says
``_b`` (body axes of the vehicle concerned).

Horseshoe bookkeeping. Horseshoe k of a surface runs inf -> X3[k] -> X1[k] -> X1[k+1] -> X3[k+1]
-> inf. Writing L[i] for the "L-line" inf -> X3[i] -> X1[i] (trailing leg plus chordwise branch
at knot i), horseshoe k = L[k] + bound(X1[k] -> X1[k+1]) - L[k+1]. Each knot's L-line is
therefore evaluated once and shared by its two neighbouring horseshoes, which halves the work
and is exactly the thesis's 5-branch sum.

Circulation sign: positive circulation about the bound vortex directed port -> starboard lifts
(Kutta-Joukowski F = rho Gamma V_rel x l). The thesis prints the opposite sign (its G of Table 5.2
is negative for a lifting wing); only the sign convention differs.

The kernels live in :mod:`.biot_savart` (branch, leg, core radius), :mod:`.posing` (the lattice in
NED), :mod:`.aic` (the joint solve) and :mod:`.field` (field velocity); this module fuses them into
:func:`evaluate_one` (pose, solve, effective wind; Eqs. 4.4-4.7) and its batched forms, and
re-exports every kernel name.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from .aic import assemble_and_solve, lu_solve_inplace, static_aic
from .biot_savart import (_MIN_CORE_M, _TINY_H, CORE_KURYLOWICH, CORE_LAMB_OSEEN, CORE_NONE, CORE_PEAK,  # noqa: F401
                          FOUR_PI, KURYLOWICH_C, LAMB_OSEEN_C, OVERLAP_CORE_CHORD_FRACTION, branch, branch_cored,
                          core_radius, sheet_on, sheet_strip_frames, leg, leg_velocity, point_to_knots,
                          segment_velocity, SHEET_ON)
from .field import field_velocity, field_velocity_batch
from .posing import bound_length, branch_directions, dcm_ned_to_body_1, place_lattice, posed_lattice, to_ned
from .structs import LatticeArrays

__all__ = ["evaluate_one", "effective_wind", "evaluate_batch_range", "evaluate_batch_serial", "field_velocity_batch",
           "field_velocity", "assemble_and_solve", "static_aic", "lu_solve_inplace", "posed_lattice", "place_lattice",
           "dcm_ned_to_body_1", "to_ned", "branch_directions", "point_to_knots", "branch", "branch_cored", "leg",
           "core_radius", "CORE_PEAK", "OVERLAP_CORE_CHORD_FRACTION", "default_overlap_core",
           "segment_velocity", "leg_velocity", "FOUR_PI", "CORE_NONE", "CORE_LAMB_OSEEN", "CORE_KURYLOWICH",
           "LAMB_OSEEN_C", "KURYLOWICH_C", "SHEET_ON"]

_jit = nb.njit(cache=True, fastmath=False, error_model="numpy")


@_jit
def evaluate_one(lat, pos, euler, airspeed, alpha, beta, gamma_out, vpts_out, wind_ned_out, wind_b_out, omega_b_out,
                 omega_ned_out, sheet=None, keep=None):
    """One formation: pose, joint solve, induced velocity at the evaluation points (other
    vehicles only) and the effective translational and rotational wind per vehicle.
    ``lat``: the body-axis lattice and the solve's settings (a :class:`~formation_env.wake.structs.LatticeArrays`;
    its ``overlap_core_m``, m, 0 = off: the minimum core of the other vehicles' branches in the solve and the field,
    see :func:`formation_env.wake.field.field_velocity`). Poses and air data (V, ...) as
    :func:`~formation_env.wake.posing.posed_lattice`'s; the outputs: circulation (N,), induced velocity at the
    evaluation points (N, 3) NED, and per vehicle (V, 3) the wind NED and body and the rotational wind body and NED.
    ``sheet`` (:data:`SHEET_ON`; :data:`~formation_env.wake.biot_savart.SHEET_OFF` or None: the thesis): the other
    vehicles' trailing legs take the sheet law near their wake plane in the solve and the field
    (``WakeModel.sheet``). ``keep``: see :func:`formation_env.wake.aic.assemble_and_solve`."""
    panel_left_knot, panel_vehicle, control_b, eval_b = lat.panel_left_knot, lat.panel_vehicle, lat.control_b, lat.eval_b
    core_mode, aic_core_mode, overlap_core = lat.core_mode, lat.aic_core_mode, lat.overlap_core_m
    n_panels = panel_left_knot.shape[0]
    posed = posed_lattice(lat, pos, euler, airspeed, alpha, beta)
    rot, x1 = posed.rot, posed.x1
    aic = np.empty((n_panels, n_panels))
    # Where the field's law at the evaluation points is the solve's at the control points (the same points,
    # the viscous core in both), every other-vehicle branch the field needs was already evaluated for the
    # AIC: keep those vectors and the field is a sum over them (issue 26: each segment-point interaction
    # evaluated once); otherwise evaluate the field's branches separately.
    shared = aic_core_mode == core_mode and _same_points(eval_b, control_b)
    vcross = np.empty((n_panels, n_panels, 3) if shared else (0, 0, 3))
    assemble_and_solve(lat, posed, aic, gamma_out, vcross, sheet, keep)
    if shared:
        for j in range(n_panels):
            v = panel_vehicle[j]
            wx = 0.0
            wy = 0.0
            wz = 0.0
            for p in range(n_panels):
                if panel_vehicle[p] != v:
                    g = gamma_out[p]
                    wx += g * vcross[j, p, 0]
                    wy += g * vcross[j, p, 1]
                    wz += g * vcross[j, p, 2]
            vpts_out[j, 0] = wx
            vpts_out[j, 1] = wy
            vpts_out[j, 2] = wz
    else:
        pt = np.empty(3)
        frames = sheet_strip_frames(sheet, posed.trail, posed.x3, lat.knot_vehicle, lat.knot_surface)
        for j in range(n_panels):
            v = panel_vehicle[j]
            to_ned(rot[v], pos[v], eval_b[j], pt)
            recv_w = 0.0
            if sheet_on(sheet):
                recv_w = bound_length(x1, panel_left_knot[j])
            wx, wy, wz = field_velocity(pt[0], pt[1], pt[2], v, False, lat, posed, gamma_out, core_mode, overlap_core,
                                        sheet, recv_w, frames)
            vpts_out[j, 0] = wx
            vpts_out[j, 1] = wy
            vpts_out[j, 2] = wz
    effective_wind(rot, vpts_out, lat.grad_w, lat.vehicle_panel_start, wind_ned_out, wind_b_out, omega_b_out,
                   omega_ned_out)


@_jit
def _same_points(a, b):
    """Whether the (N, 3) point sets ``a`` and ``b`` are equal element by element."""
    if a.shape[0] != b.shape[0]:
        return False
    for j in range(a.shape[0]):
        for i in range(3):
            if a[j, i] != b[j, i]:
                return False
    return True


@_jit
def default_overlap_core(knot_x1_b, knot_x3_b, surface_knot_start):
    """The default overlap core r_o = OVERLAP_CORE_CHORD_FRACTION x the largest mean chord of any
    surface of the lattice, m. A surface's mean chord is the length-weighted mean of its panels'
    chords (2 |X3 - X1| at the knots, trapezoidal): S / b = b / AR for the linear planforms of
    :mod:`formation_env.geometry` (0.1933 m for the Aerosonde's wing, so r_o = 0.1933 m)."""
    best = 0.0
    for s in range(surface_knot_start.shape[0] - 1):
        num = 0.0
        den = 0.0
        for k in range(surface_knot_start[s], surface_knot_start[s + 1] - 1):
            c0 = 0.0
            c1 = 0.0
            ln = 0.0
            for i in range(3):
                c0 += (knot_x3_b[k, i] - knot_x1_b[k, i]) ** 2
                c1 += (knot_x3_b[k + 1, i] - knot_x1_b[k + 1, i]) ** 2
                ln += (knot_x1_b[k + 1, i] - knot_x1_b[k, i]) ** 2
            ln = np.sqrt(ln)
            num += (np.sqrt(c0) + np.sqrt(c1)) * ln  # mean of the two chords 2|X3 - X1|, times the length
            den += ln
        if den > 0.0:
            best = max(best, num / den)
    return OVERLAP_CORE_CHORD_FRACTION * best


@_jit
def effective_wind(rot, vpts, grad_w, vehicle_panel_start, wind_ned_out, wind_b_out, omega_b_out, omega_ned_out):
    """Effective induced wind of each vehicle (thesis Eqs. 4.4-4.7, Dogan's method): translational
    wind = the mean of the induced velocities at its evaluation points (NED, and body axes); rotational
    wind = the curl of a linear fit of them, whose weights ``grad_w`` (least squares or the thesis's
    finite differences) were precomputed per vehicle. rot (V, 3, 3) NED -> body; vpts (N, 3) NED."""
    nv = rot.shape[0]
    grad = np.empty((3, 3))
    for v in range(nv):
        j0 = vehicle_panel_start[v]
        j1 = vehicle_panel_start[v + 1]
        m0 = 0.0
        m1 = 0.0
        m2 = 0.0
        for a in range(3):
            for c in range(3):
                grad[a, c] = 0.0
        for j in range(j0, j1):
            m0 += vpts[j, 0]
            m1 += vpts[j, 1]
            m2 += vpts[j, 2]
            for a in range(3):
                vb = rot[v, a, 0] * vpts[j, 0] + rot[v, a, 1] * vpts[j, 1] + rot[v, a, 2] * vpts[j, 2]
                for c in range(3):
                    grad[a, c] += grad_w[j, c] * vb
        inv = 1.0 / (j1 - j0)
        wind_ned_out[v, 0] = m0 * inv
        wind_ned_out[v, 1] = m1 * inv
        wind_ned_out[v, 2] = m2 * inv
        for a in range(3):
            wind_b_out[v, a] = rot[v, a, 0] * wind_ned_out[v, 0] + rot[v, a, 1] * wind_ned_out[v, 1] + rot[v, a, 2] * wind_ned_out[v, 2]
        # Eq. 4.7 with grad[a, c] = d V_a / d x_c in body axes.
        omega_b_out[v, 0] = grad[2, 1] - grad[1, 2]
        omega_b_out[v, 1] = grad[0, 2] - grad[2, 0]
        omega_b_out[v, 2] = grad[1, 0] - grad[0, 1]
        for i in range(3):
            omega_ned_out[v, i] = rot[v, 0, i] * omega_b_out[v, 0] + rot[v, 1, i] * omega_b_out[v, 1] + rot[v, 2, i] * omega_b_out[v, 2]


@nb.njit(cache=True, nogil=True, error_model="numpy")
def evaluate_batch_range(lattice, pos, euler, airspeed, alpha, beta, gamma_out, vpts_out, wind_ned_out, wind_b_out,
                         omega_b_out, omega_ned_out, sheet, start, stop):
    """:func:`evaluate_one` of formations start..stop-1 of a batch (poses, air data and outputs with the batch axis
    first) of the lattice ``lattice``: a :class:`~formation_env.wake.structs.LatticeArrays` or the plain tuple of its
    fields (what :meth:`formation_env.wake.WakeModel.evaluate` passes: numba types a plain tuple argument in C, a
    named tuple through Python). Releases the GIL: threads run ranges of one batch
    (:func:`formation_env.threads.run_parallel`)."""
    lat = LatticeArrays(*lattice)
    for b in range(start, stop):
        evaluate_one(lat, pos[b], euler[b], airspeed[b], alpha[b], beta[b], gamma_out[b], vpts_out[b],
                     wind_ned_out[b], wind_b_out[b], omega_b_out[b], omega_ned_out[b], sheet)


def evaluate_batch_serial(lattice, pos, euler, airspeed, alpha, beta, gamma_out, vpts_out, wind_ned_out, wind_b_out,
                          omega_b_out, omega_ned_out, sheet=None):
    """:func:`evaluate_batch_range` of the whole batch, on the calling thread."""
    evaluate_batch_range(lattice, pos, euler, airspeed, alpha, beta, gamma_out, vpts_out, wind_ned_out, wind_b_out,
                         omega_b_out, omega_ned_out, sheet, 0, pos.shape[0])
