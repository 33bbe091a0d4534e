"""Compiled joint solve of the ELL (thesis section 4.3.6, Eqs. 4.23-4.69): the aerodynamic influence
coefficient (AIC) matrix of every panel of every vehicle and the circulations from the flow-tangency
condition, by Gaussian elimination with partial pivoting."""

from __future__ import annotations

import numba as nb
import numpy as np

from .biot_savart import (CORE_NONE, branch, branch_cored, core_radius, leg, leg_cored, leg_sheet_framed, point_to_knots,
                          point_to_knots3, sheet_on, sheet_strip_frames)
from . import lanes
from .lanes import KMAX
from .posing import bound_length, branch_directions, to_ned

__all__ = ["lu_solve_inplace", "lu_solve_lanes", "static_aic", "assemble_and_solve", "assemble_and_solve_scalar",
           "assemble_scalar", "assemble_lanes"]

_jit = nb.njit(cache=True, fastmath=False, error_model="numpy")


@_jit
def lu_solve_inplace(a, rhs, row=None):
    """Solve a x = rhs by Gaussian elimination with partial pivoting (a and rhs are overwritten;
    x is returned in rhs). The AIC is small and dense, so this beats a LAPACK call's overhead.

    Each elimination step copies the pivot row's remaining part into ``row`` (scratch of n floats; None:
    allocated here) before updating the rows below it: the update loop then reads one array and writes
    another, which LLVM vectorises (without the copy it must assume the two rows alias). Every element
    gets the same operations in the same order, so the result is bit for bit the plain loop's."""
    n = a.shape[0]
    if row is None:
        row = np.empty(n)
    for k in range(n):
        p = k
        best = abs(a[k, k])
        for i in range(k + 1, n):
            v = abs(a[i, k])
            if v > best:
                best = v
                p = i
        if p != k:
            for j in range(n):
                tmp = a[k, j]
                a[k, j] = a[p, j]
                a[p, j] = tmp
            tmp = rhs[k]
            rhs[k] = rhs[p]
            rhs[p] = tmp
        piv = a[k, k]
        if piv == 0.0:
            piv = 1e-300  # singular (degenerate geometry): stay finite rather than divide by zero
            a[k, k] = piv
        rest = n - k - 1
        for j in range(rest):
            row[j] = a[k, k + 1 + j]
        for i in range(k + 1, n):
            m = a[i, k] / piv
            if m != 0.0:
                for j in range(rest):
                    a[i, k + 1 + j] -= m * row[j]
                rhs[i] -= m * rhs[k]
    for k in range(n - 1, -1, -1):
        s = rhs[k]
        for j in range(k + 1, n):
            s -= a[k, j] * rhs[j]
        rhs[k] = s / a[k, k]


@_jit
def static_aic(knot_x1_b, knot_x3_b, knot_vehicle, knot_surface, surface_knot_start, panel_left_knot, panel_vehicle,
               control_b, normal_b, cutoff):
    """The part of the AIC that a rigid vehicle's own bound and chordwise branches contribute to its
    own control points: constant in body axes (only the trailing legs follow alpha and beta), so
    it is computed once per make-up. Entries between different vehicles are zero."""
    n_panels = panel_left_knot.shape[0]
    n_knots = knot_x1_b.shape[0]
    out = np.zeros((n_panels, n_panels))
    bound_dir = np.empty((n_knots, 3))
    chord_dir = np.empty((n_knots, 3))
    branch_directions(knot_x1_b, knot_x3_b, knot_surface, surface_knot_start, bound_dir, chord_dir)
    r1 = np.empty((n_knots, 3))
    r3 = np.empty((n_knots, 3))
    inv1 = np.empty(n_knots)
    inv3 = np.empty(n_knots)
    cw = np.empty(n_knots)
    for j in range(n_panels):
        vj = panel_vehicle[j]
        c = control_b[j]
        n = normal_b[j]
        point_to_knots(c[0], c[1], c[2], knot_x1_b, knot_x3_b, 0, n_knots, r1, inv1, r3, inv3)
        for k in range(n_knots):
            sx, sy, sz = branch(chord_dir[k, 0], chord_dir[k, 1], chord_dir[k, 2], r3[k, 0], r3[k, 1], r3[k, 2], inv3[k],
                                r1[k, 0], r1[k, 1], r1[k, 2], inv1[k], cutoff)
            cw[k] = sx * n[0] + sy * n[1] + sz * n[2]
        for p in range(n_panels):
            if panel_vehicle[p] != vj:
                continue
            k = panel_left_knot[p]
            bx, by, bz = branch(bound_dir[k, 0], bound_dir[k, 1], bound_dir[k, 2], r1[k, 0], r1[k, 1], r1[k, 2], inv1[k],
                                r1[k + 1, 0], r1[k + 1, 1], r1[k + 1, 2], inv1[k + 1], cutoff)
            out[j, p] = cw[k] + bx * n[0] + by * n[1] + bz * n[2] - cw[k + 1]
    return out


@_jit
def assemble_and_solve(lat, posed, aic, gamma, vcross, sheet=None, keep=None):
    """Build the AIC over every panel of every vehicle and solve for the circulations (4.25-4.69): the laws and
    arguments of :func:`assemble_and_solve_scalar`, with the knots of each control point evaluated as vector lanes
    (:func:`assemble_lanes`, :mod:`.lanes`; bit for bit the same AIC, circulation and ``vcross``) when the lattice
    has at most :data:`formation_env.wake.lanes.KMAX` knots, else the scalar assembly."""
    if posed.x1.shape[0] <= KMAX:
        assemble_lanes(lat, posed, aic, gamma, vcross, sheet)
    else:
        assemble_scalar(lat, posed, aic, gamma, vcross, sheet)
    _keep_and_solve(aic, gamma, keep)


@_jit
def assemble_and_solve_scalar(lat, posed, aic, gamma, vcross, sheet=None, keep=None):
    """Build the AIC over every panel of every vehicle and solve for the circulations (4.25-4.69).

    ``lat`` the body-axis lattice and the solve's settings (a :class:`~formation_env.wake.structs.LatticeArrays`:
    its ``cutoff_m``, ``aic_core_mode``, ``kinematic_viscosity`` and ``overlap_core_m`` below), ``posed`` the
    formation posed in NED (a :class:`~formation_env.wake.structs.PosedLattice`, whose scratch it uses); ``aic``
    (N, N) and ``gamma`` (N,) receive the matrix and the circulation.

    Boundary condition (V_induced + V_inf) . n = 0 with V_inf = -V_vehicle: A G = V_vehicle . n.
    All branches use the plain Biot-Savart law with the Eq. 4.31 cutoff (the thesis), except that
    ``aic_core_mode`` != CORE_NONE gives the *other* vehicles' trailing legs the viscous core of the
    field law, so that a leg passing a control point does not produce a near-singular response.
    ``overlap_core`` > 0 (m): the *other* vehicles' branches carry the overlap core of that radius
    (:func:`branch_cored`, :func:`leg_cored`: about their lifting surface; legs never thinner than the
    cutoff), so that overlapping or coincident vehicles keep a well-conditioned AIC; 0: without it.
    A vehicle's own bound and chordwise branches come from ``aic_static`` (see :func:`static_aic`),
    its own legs are plain with the cutoff: the own part is the thesis's exactly.

    ``vcross`` (N, N, 3) or empty (0, 0, 3): when not empty, ``vcross[j, p]`` receives the velocity (NED,
    per unit circulation) that horseshoe ``p`` of *another* vehicle induces at control point ``j`` (entries
    of a vehicle's own horseshoes are left unset): the vector whose normal component is the AIC entry, so
    that the other vehicles' field at the control points is ``sum_p vcross[j, p] gamma[p]`` without
    evaluating the branches again (:func:`formation_env.wake.kernels.evaluate_one`). The AIC itself is
    computed exactly as without it (the same dot products, bit for bit).

    ``keep`` (N, N + 1) or None: when given (and not empty), receives the assembled AIC (columns 0..N-1) and the
    right-hand side (column N) before the elimination overwrites them. A vehicle's diagonal block of it is that
    vehicle's AIC alone, bit for bit (its own branches only, the same operations in the same order), which the
    formation benefit solves for the isolated circulation instead of posing and assembling the lone vehicle again
    (:func:`formation_env.wake.benefit.induced_drags_one`; issue 26).
    """
    assemble_scalar(lat, posed, aic, gamma, vcross, sheet)
    _keep_and_solve(aic, gamma, keep)


@_jit
def _keep_and_solve(aic, gamma, keep):
    """``keep`` (N, N + 1; None or empty: not kept) <- the AIC and right-hand side; then the solve in place."""
    n_panels = aic.shape[0]
    if keep is not None and keep.shape[0] > 0:
        for j in range(n_panels):
            for p in range(n_panels):
                keep[j, p] = aic[j, p]
            keep[j, n_panels] = gamma[j]
    lu_solve_inplace(aic, gamma)


@_jit
def assemble_scalar(lat, posed, aic, gamma, vcross, sheet=None):
    """The AIC into ``aic`` and the right-hand side into ``gamma`` (see :func:`assemble_and_solve_scalar`), branch by
    branch with the scalar laws: the reference :func:`assemble_lanes` equals bit for bit, and the path of lattices
    of more than :data:`formation_env.wake.lanes.KMAX` knots."""
    x1, x3, bound_dir, chord_dir, trail, vel, rot, pos, origin, airspeed = (
        posed.x1, posed.x3, posed.bound_dir, posed.chord_dir, posed.trail, posed.vel, posed.rot, posed.pos,
        posed.origin, posed.airspeed)
    r1, inv1, r3, inv3 = posed.r1, posed.inv1, posed.r3, posed.inv3
    knot_vehicle, knot_surface, surface_knot_start = lat.knot_vehicle, lat.knot_surface, lat.surface_knot_start
    surface_core_scale, panel_left_knot, panel_vehicle = lat.surface_core_scale, lat.panel_left_knot, lat.panel_vehicle
    control_b, normal_b, aic_static = lat.control_b, lat.normal_b, lat.aic_static
    cutoff, aic_core_mode, nu, overlap_core = lat.cutoff_m, lat.aic_core_mode, lat.kinematic_viscosity, lat.overlap_core_m
    n_panels = panel_left_knot.shape[0]
    n_knots = x1.shape[0]
    store = vcross.shape[0] > 0
    cp = np.empty(3)
    nrm = np.empty(3)
    lw = np.empty(n_knots)  # trailing leg . n
    cw = np.empty(n_knots)  # chordwise branch . n (other vehicles' knots only)
    lcv = np.empty((n_knots, 3) if store else (0, 3))  # chordwise branch - trailing leg (other vehicles' knots)
    # the sheet law's strip of each knot depends on the knot alone: once per solve, not per control point
    frames = sheet_strip_frames(sheet, trail, x3, knot_vehicle, knot_surface)
    for j in range(n_panels):
        vj = panel_vehicle[j]
        to_ned(rot[vj], pos[vj], control_b[j], cp)
        for i in range(3):
            nrm[i] = rot[vj, 0, i] * normal_b[j, 0] + rot[vj, 1, i] * normal_b[j, 1] + rot[vj, 2, i] * normal_b[j, 2]
        recv_w = 0.0
        if sheet_on(sheet):
            recv_w = bound_length(x1, panel_left_knot[j])
        # surface by surface (a surface's knots are contiguous): the own/other decision, the source's leg direction
        # and the core radius once per surface and control point, not per knot
        for srf in range(surface_knot_start.shape[0] - 1):
            k0 = surface_knot_start[srf]
            k1 = surface_knot_start[srf + 1]
            src = knot_vehicle[k0]
            tx, ty, tz = trail[src, 0], trail[src, 1], trail[src, 2]
            if src == vj:
                # own knots: only the trailing legs (the bound and chordwise branches are in aic_static), plain
                # with the cutoff; only the vectors from the 3/4-chord knots are needed
                point_to_knots3(cp[0], cp[1], cp[2], x3, k0, k1, r3, inv3)
                for k in range(k0, k1):
                    lx, ly, lz = leg(tx, ty, tz, r3[k, 0], r3[k, 1], r3[k, 2], inv3[k], cutoff, 0.0)
                    lw[k] = lx * nrm[0] + ly * nrm[1] + lz * nrm[2]
                continue
            point_to_knots(cp[0], cp[1], cp[2], x1, x3, k0, k1, r1, inv1, r3, inv3)
            rc = 0.0
            if aic_core_mode != CORE_NONE:
                rc = core_radius(cp[0], cp[1], cp[2], origin, srf, airspeed[src], surface_core_scale, aic_core_mode, nu)
            for k in range(k0, k1):
                if sheet_on(sheet):
                    lx, ly, lz = leg_sheet_framed(tx, ty, tz, r3[k, 0], r3[k, 1], r3[k, 2], inv3[k], cutoff, rc,
                                                  overlap_core, frames[k], recv_w)
                else:
                    lx, ly, lz = leg_cored(tx, ty, tz, r3[k, 0], r3[k, 1], r3[k, 2], inv3[k], cutoff, rc, overlap_core)
                lw[k] = lx * nrm[0] + ly * nrm[1] + lz * nrm[2]
                sx, sy, sz = branch_cored(chord_dir[k, 0], chord_dir[k, 1], chord_dir[k, 2], r3[k, 0], r3[k, 1], r3[k, 2],
                                          inv3[k], r1[k, 0], r1[k, 1], r1[k, 2], inv1[k], cutoff, overlap_core)
                cw[k] = sx * nrm[0] + sy * nrm[1] + sz * nrm[2]
                if store:
                    lcv[k, 0] = sx - lx
                    lcv[k, 1] = sy - ly
                    lcv[k, 2] = sz - lz
        for p in range(n_panels):
            k = panel_left_knot[p]
            if panel_vehicle[p] == vj:
                aic[j, p] = aic_static[j, p] - lw[k] + lw[k + 1]
            else:
                bx, by, bz = branch_cored(bound_dir[k, 0], bound_dir[k, 1], bound_dir[k, 2], r1[k, 0], r1[k, 1], r1[k, 2],
                                          inv1[k], r1[k + 1, 0], r1[k + 1, 1], r1[k + 1, 2], inv1[k + 1], cutoff,
                                          overlap_core)
                aic[j, p] = (cw[k] - lw[k]) + bx * nrm[0] + by * nrm[1] + bz * nrm[2] - (cw[k + 1] - lw[k + 1])
                if store:  # horseshoe p = L-line k + bound - L-line k + 1 (the field's decomposition)
                    vcross[j, p, 0] = lcv[k, 0] + bx - lcv[k + 1, 0]
                    vcross[j, p, 1] = lcv[k, 1] + by - lcv[k + 1, 1]
                    vcross[j, p, 2] = lcv[k, 2] + bz - lcv[k + 1, 2]
        gamma[j] = vel[vj, 0] * nrm[0] + vel[vj, 1] * nrm[1] + vel[vj, 2] * nrm[2]


@_jit
def assemble_lanes(lat, posed, aic, gamma, vcross, sheet=None):
    """:func:`assemble_scalar` with each control point's knots as vector lanes (:mod:`.lanes`: the other vehicles'
    L-lines, then their bound branches, and the own trailing legs; the lanes whose fast form is not the law's
    recomputed by the scalar laws): the same AIC, right-hand side and ``vcross``, bit for bit. At most
    :data:`~formation_env.wake.lanes.KMAX` knots; a vehicle's knots must be contiguous (the lattice's order)."""
    x1, x3, bound_dir, chord_dir, trail, vel, rot, pos, origin, airspeed = (
        posed.x1, posed.x3, posed.bound_dir, posed.chord_dir, posed.trail, posed.vel, posed.rot, posed.pos,
        posed.origin, posed.airspeed)
    knot_vehicle, knot_surface, surface_knot_start = lat.knot_vehicle, lat.knot_surface, lat.surface_knot_start
    surface_core_scale, panel_left_knot, panel_vehicle = lat.surface_core_scale, lat.panel_left_knot, lat.panel_vehicle
    control_b, normal_b, aic_static = lat.control_b, lat.normal_b, lat.aic_static
    cutoff, aic_core_mode, nu, overlap_core = lat.cutoff_m, lat.aic_core_mode, lat.kinematic_viscosity, lat.overlap_core_m
    n_panels = panel_left_knot.shape[0]
    n_knots = x1.shape[0]
    store = vcross.shape[0] > 0
    cp = np.empty(3)
    frames = sheet_strip_frames(sheet, trail, x3, knot_vehicle, knot_surface)
    s = lanes.lane_scratch()
    lanes.load_knots(s, x1, x3, chord_dir, bound_dir, trail, knot_vehicle, frames, sheet)
    on = sheet_on(sheet)
    # without the overlap core every lane takes the scalar law (its plain form is another law)
    ro2 = overlap_core * overlap_core if overlap_core > 0.0 else np.inf
    vk0, vk1 = lanes.vehicle_knot_ranges(knot_vehicle, pos.shape[0])
    for j in range(n_panels):
        vj = panel_vehicle[j]
        to_ned(rot[vj], pos[vj], control_b[j], cp)
        px, py, pz = cp[0], cp[1], cp[2]
        n0 = rot[vj, 0, 0] * normal_b[j, 0] + rot[vj, 1, 0] * normal_b[j, 1] + rot[vj, 2, 0] * normal_b[j, 2]
        n1 = rot[vj, 0, 1] * normal_b[j, 0] + rot[vj, 1, 1] * normal_b[j, 1] + rot[vj, 2, 1] * normal_b[j, 2]
        n2 = rot[vj, 0, 2] * normal_b[j, 0] + rot[vj, 1, 2] * normal_b[j, 1] + rot[vj, 2, 2] * normal_b[j, 2]
        recv_w = 0.0
        if sheet_on(sheet):
            recv_w = bound_length(x1, panel_left_knot[j])
        a, b = vk0[vj], vk1[vj]
        lanes.own_legs(s, a, b, px, py, pz, n0, n1, n2, cutoff)
        lanes.fill_core_radius(s, px, py, pz, vj, origin, airspeed, knot_vehicle, surface_knot_start,
                               surface_core_scale, aic_core_mode, nu)
        lanes.other_llines(s, 0, a, px, py, pz, n0, n1, n2, cutoff, ro2, recv_w, on)
        lanes.other_llines(s, b, n_knots, px, py, pz, n0, n1, n2, cutoff, ro2, recv_w, on)
        lanes.fix_llines(s, 0, a, px, py, pz, n0, n1, n2, x1, x3, chord_dir, trail, knot_vehicle, cutoff,
                         overlap_core, frames, recv_w, sheet)
        lanes.fix_llines(s, b, n_knots, px, py, pz, n0, n1, n2, x1, x3, chord_dir, trail, knot_vehicle, cutoff,
                         overlap_core, frames, recv_w, sheet)
        if a > 1:
            lanes.other_bounds(s, 0, a - 1, px, py, pz, ro2)
        if n_knots - b > 1:
            lanes.other_bounds(s, b, n_knots - 1, px, py, pz, ro2)
        # the row surface by surface (a surface of n knots has n - 1 panels, numbered from its first knot's index
        # less the surface's: the lattice's order)
        for srf in range(surface_knot_start.shape[0] - 1):
            k0 = surface_knot_start[srf]
            npan = surface_knot_start[srf + 1] - k0 - 1
            p0 = k0 - srf
            if knot_vehicle[k0] == vj:
                lanes.own_panel_row(s, aic, aic_static, j, p0, k0, npan)
                continue
            lanes.fix_bounds(s, k0, k0 + npan, px, py, pz, x1, bound_dir, cutoff, overlap_core)
            lanes.other_panel_row(s, aic, vcross, j, p0, k0, npan, n0, n1, n2, store)
        gamma[j] = vel[vj, 0] * n0 + vel[vj, 1] * n1 + vel[vj, 2] * n2


@_jit
def lu_solve_lanes(a, rhs, piv):
    """:func:`lu_solve_inplace` of L systems at once, one per vector lane (the ELL of a chunk of formations,
    :mod:`.across`): ``a`` (N, N, L) and ``rhs`` (N, L) overwritten, the solutions in ``rhs``; ``piv`` (L,) int64
    scratch. Each lane chooses its own pivots (partial pivoting, the first largest magnitude), swaps its own rows and
    performs the scalar elimination's operations in the same order (a row whose multiplier is 0 left as it is, a
    zero pivot replaced by 1e-300), so every lane's solution is the scalar solve's bit for bit.

    The lane loops run to a run-time count (``a.shape[2]``), not a constant: LLVM unrolls a loop of a constant 16 and
    then cannot prove that a row it writes does not overlap another it reads (they lie a run-time distance apart in
    one array), so it keeps the unrolled loop scalar; a loop of a run-time count goes to the loop vectoriser, which
    checks the overlap once per loop and runs the vector body (the same operations per element: the same bits)."""
    n = a.shape[0]
    lanes = a.shape[2]
    best = np.empty(lanes)
    m = np.empty(lanes)
    s = np.empty(lanes)
    for k in range(n):
        for l in range(lanes):
            piv[l] = k
            best[l] = abs(a[k, k, l])
        for i in range(k + 1, n):
            for l in range(lanes):
                v = abs(a[i, k, l])
                if v > best[l]:
                    best[l] = v
                    piv[l] = i
        for l in range(lanes):
            p = piv[l]
            if p != k:
                for j in range(n):
                    tmp = a[k, j, l]
                    a[k, j, l] = a[p, j, l]
                    a[p, j, l] = tmp
                tmp = rhs[k, l]
                rhs[k, l] = rhs[p, l]
                rhs[p, l] = tmp
        for l in range(lanes):
            if a[k, k, l] == 0.0:
                a[k, k, l] = 1e-300
        for i in range(k + 1, n):
            for l in range(lanes):
                m[l] = a[i, k, l] / a[k, k, l]
            for j in range(k + 1, n):
                for l in range(lanes):
                    x = a[i, j, l] - m[l] * a[k, j, l]
                    a[i, j, l] = x if m[l] != 0.0 else a[i, j, l]
            for l in range(lanes):
                x = rhs[i, l] - m[l] * rhs[k, l]
                rhs[i, l] = x if m[l] != 0.0 else rhs[i, l]
    for k in range(n - 1, -1, -1):
        for l in range(lanes):
            s[l] = rhs[k, l]
        for j in range(k + 1, n):
            for l in range(lanes):
                s[l] -= a[k, j, l] * rhs[j, l]
        for l in range(lanes):
            rhs[k, l] = s[l] / a[k, k, l]
