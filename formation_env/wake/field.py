"""Compiled field velocity of the ELL (thesis section 4.3.7, Eqs. 4.70-4.75): the velocity the solved
horseshoes induce at a field point (trailing legs with the viscous core), for one point and for
batches of arbitrary points."""

from __future__ import annotations

import numba as nb

from .biot_savart import (CORE_NONE, branch_cored, core_radius, leg_cored, leg_sheet, leg_sheet_framed, point_to_knots,
                          sheet_on, sheet_strip_frames)
from .posing import posed_lattice
from .structs import LatticeArrays

__all__ = ["field_velocity", "field_velocity_batch"]

_jit = nb.njit(cache=True, fastmath=False, error_model="numpy")


@_jit
def field_velocity(px, py, pz, vehicle_filter, keep_only, lat, posed, gamma, core_mode, overlap_core, sheet=None,
                   recv_w=0.0, frames=None):
    """Velocity induced at one field point by the horseshoes of every vehicle except
    ``vehicle_filter`` (-1 excludes none) or, with ``keep_only``, of that vehicle alone, for the circulation
    ``gamma`` (N,) of the lattice ``lat`` (a :class:`~formation_env.wake.structs.LatticeArrays`: its ``cutoff_m``
    and ``kinematic_viscosity``) posed as ``posed`` (a :class:`~formation_env.wake.structs.PosedLattice`, whose
    scratch it uses) (Eqs. 4.70-4.75): bound and chordwise branches plain Biot-Savart (clipped at ``cutoff`` so
    that overlapping vehicles stay finite), trailing legs with the viscous core of age
    tau = |P - source surface origin| / V_source (``core_mode`` 0 plain, 1 Lamb-Oseen,
    2 Kurylowich). ``overlap_core`` > 0 (m): every branch carries the overlap core of that radius
    about the source's lifting surface and the legs a core of at least the cutoff
    (:func:`branch_cored`, :func:`leg_cored`), so |v| <= CORE_PEAK / (2 pi min(overlap_core, cutoff))
    per unit strength and branch at any point; callers pass it for the *other* vehicles' field and 0
    for a vehicle's own field (the solve's law). ``sheet`` the switch of
    :func:`formation_env.wake.aic.assemble_and_solve` (:func:`~formation_env.wake.biot_savart.sheet_on`): on, the
    trailing legs take the sheet law
    near their wake plane (:func:`leg_sheet`), averaged over a receiving segment of width ``recv_w``
    (m; 0: at the point); passed, like ``overlap_core``, for the other vehicles' field. ``frames`` (K,
    STRIP_COLUMNS) or None: the knots' strips (:func:`~formation_env.wake.biot_savart.strip_frames` of this
    posed lattice), for a caller that evaluates many points (None: each leg computes its own; the same values)."""
    x1, x3, bound_dir, chord_dir, trail, origin, airspeed = (posed.x1, posed.x3, posed.bound_dir, posed.chord_dir,
                                                             posed.trail, posed.origin, posed.airspeed)
    r1, inv1, r3, inv3 = posed.r1, posed.inv1, posed.r3, posed.inv3
    surface_knot_start, surface_panel_start = lat.surface_knot_start, lat.surface_panel_start
    surface_vehicle, surface_core_scale = lat.surface_vehicle, lat.surface_core_scale
    cutoff, nu = lat.cutoff_m, lat.kinematic_viscosity
    vx = 0.0
    vy = 0.0
    vz = 0.0
    n_surf = surface_vehicle.shape[0]
    for s in range(n_surf):
        src = surface_vehicle[s]
        if (src == vehicle_filter) != keep_only:
            continue
        rc = 0.0
        if core_mode != CORE_NONE:
            rc = core_radius(px, py, pz, origin, s, airspeed[src], surface_core_scale, core_mode, nu)
        t = trail[src]
        k0 = surface_knot_start[s]
        k1 = surface_knot_start[s + 1]
        p0 = surface_panel_start[s]
        point_to_knots(px, py, pz, x1, x3, k0, k1, r1, inv1, r3, inv3)
        for k in range(k0, k1):
            # Net strength of knot k's L-line: +Gamma of the panel on its right, -Gamma of the left one.
            g = 0.0
            if k < k1 - 1:
                g += gamma[p0 + (k - k0)]
            if k > k0:
                g -= gamma[p0 + (k - k0) - 1]
            if g != 0.0:
                if sheet_on(sheet) and frames is not None:
                    lx, ly, lz = leg_sheet_framed(t[0], t[1], t[2], r3[k, 0], r3[k, 1], r3[k, 2], inv3[k], cutoff, rc,
                                                  overlap_core, frames[k], recv_w)
                elif sheet_on(sheet):
                    lx, ly, lz = leg_sheet(t[0], t[1], t[2], r3[k, 0], r3[k, 1], r3[k, 2], inv3[k], cutoff, rc, overlap_core,
                                           x3, k, k > k0, k < k1 - 1, recv_w)
                else:
                    lx, ly, lz = leg_cored(t[0], t[1], t[2], r3[k, 0], r3[k, 1], r3[k, 2], inv3[k], cutoff, rc, overlap_core)
                sx, sy, sz = branch_cored(chord_dir[k, 0], chord_dir[k, 1], chord_dir[k, 2], r3[k, 0], r3[k, 1], r3[k, 2],
                                          inv3[k], r1[k, 0], r1[k, 1], r1[k, 2], inv1[k], cutoff, overlap_core)
                vx += g * (sx - lx)
                vy += g * (sy - ly)
                vz += g * (sz - lz)
            if k < k1 - 1:
                gp = gamma[p0 + (k - k0)]
                bx, by, bz = branch_cored(bound_dir[k, 0], bound_dir[k, 1], bound_dir[k, 2], r1[k, 0], r1[k, 1], r1[k, 2],
                                          inv1[k], r1[k + 1, 0], r1[k + 1, 1], r1[k + 1, 2], inv1[k + 1], cutoff,
                                          overlap_core)
                vx += gp * bx
                vy += gp * by
                vz += gp * bz
    return vx, vy, vz


@nb.njit(cache=True, parallel=True, error_model="numpy")
def field_velocity_batch(points, vehicle_filter, keep_only, lattice, pos, euler, airspeed, alpha, beta, gamma,
                         core_mode, overlap_core, out, sheet=None, recv_w=None):
    """Induced velocity (NED) at arbitrary points (B, P, 3) for solved circulations (B, N) of the lattice ``lattice``
    (a :class:`~formation_env.wake.structs.LatticeArrays`, or the plain tuple of its fields) at the poses (B, V, ...);
    ``vehicle_filter`` (P,), ``keep_only``, ``core_mode``, ``overlap_core`` and ``sheet`` as in
    :func:`field_velocity` (they override the lattice's), ``recv_w`` (P,) its receiving width per point (None: 0)."""
    lat = LatticeArrays(*lattice)
    for b in nb.prange(pos.shape[0]):
        posed = posed_lattice(lat, pos[b], euler[b], airspeed[b], alpha[b], beta[b])
        frames = sheet_strip_frames(sheet, posed.trail, posed.x3, lat.knot_vehicle, lat.knot_surface)
        for p in range(points.shape[1]):
            rw = 0.0 if recv_w is None else recv_w[p]
            wx, wy, wz = field_velocity(points[b, p, 0], points[b, p, 1], points[b, p, 2], vehicle_filter[p], keep_only,
                                        lat, posed, gamma[b], core_mode, overlap_core, sheet, rw, frames)
            out[b, p, 0] = wx
            out[b, p, 1] = wy
            out[b, p, 2] = wz
