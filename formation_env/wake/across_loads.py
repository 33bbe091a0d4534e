"""The induced drags of a chunk of formations with the formations as the vector lanes: the Kutta-Joukowski pass of
:func:`formation_env.wake.benefit.induced_drags_one` (each vehicle in formation and alone) for up to
:data:`~formation_env.wake.across_rows.LANES` formations at once, read off the chunk scratch that
:func:`formation_env.wake.across.solve_chunk_lanes` left (its poses, branch directions and strips).

Why across formations: the pass evaluates every horseshoe of the formation at every bound midpoint, the same loops
for every formation of a lattice; with the formations innermost each branch law serves LANES formations in one vector
instruction, as the solve's rows do (:mod:`.across`).

Layout: the lane rows of :mod:`.across_rows`, the midpoint in the control point's head rows (its normal zero, its
receiving width the bound's length with the sheet law). The own vehicle's knots reuse rows I1, LCX..LCZ and BX..BZ
for the own horseshoes' law (plain Biot-Savart with the Eq. 4.31 cutoff); the other vehicles' knots hold the field
law's as the solve fills them.

Exactness: each lane performs the operations of ``induced_drags_one`` (its vector-lane branch,
:func:`formation_env.wake.lanes.own_field_lanes` and the rest) in the same order, no fastmath: every lane's drags are
that formation's own, bit for bit (``tests/wake/test_across_loads.py``). Frames and units: NED earth, metres, m/s,
newtons.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from .across_rows import (LANES, _STRIDE, X1X, X1Y, X1Z, X3X, X3Y, X3Z, CDX, CDY, CDZ, BDX, BDY, BDZ, TX, TY, TZ, I1,
                          LCX, LCY, LCZ, BX, BY, BZ, PX, PY, PZ, N0, N1, N2, RW, _U_STRIDE, _fix_bounds)
from .across import other_vehicles_rows
from .aic import lu_solve_lanes
from .benefit import _add_kutta_joukowski, _wind_axis_drag
from .biot_savart import _TINY_H, FOUR_PI, sheet_on
from .lanes import vehicle_knot_ranges

__all__ = ["induced_drags_chunk"]

_jit = nb.njit(cache=True, fastmath=False, error_model="numpy")
_TINY2 = _TINY_H * _TINY_H


@_jit
def _own_field(s, pt, k0, k1, cutoff):
    """The own knots k0..k1-1 seen from the midpoint with the solve's law, every lane: I1 = 1 / |P - X1| and
    LCX..LCZ the L-line vector (chordwise - leg) (:func:`formation_env.wake.lanes.own_field_lanes`'s operations)."""
    c2 = cutoff * cutoff
    for k in range(np.uint64(k0), np.uint64(k1)):
        q = k * _U_STRIDE
        for l in range(np.uint64(LANES)):
            px, py, pz = pt[PX + l], pt[PY + l], pt[PZ + l]
            bx = px - s[q + X1X + l]
            by = py - s[q + X1Y + l]
            bz = pz - s[q + X1Z + l]
            nb_ = math.sqrt(bx * bx + by * by + bz * bz)
            inv_b = 1.0 / nb_ if nb_ > 0.0 else 0.0
            ax = px - s[q + X3X + l]
            ay = py - s[q + X3Y + l]
            az = pz - s[q + X3Z + l]
            na = math.sqrt(ax * ax + ay * ay + az * az)
            inv_a = 1.0 / na if na > 0.0 else 0.0
            tx, ty, tz = s[q + TX + l], s[q + TY + l], s[q + TZ + l]
            cx = ty * az - tz * ay
            cy = tz * ax - tx * az
            cz = tx * ay - ty * ax
            h2 = cx * cx + cy * cy + cz * cz
            cos_g = (tx * ax + ty * ay + tz * az) * inv_a
            denom = h2 if h2 >= c2 else math.sqrt(h2) * cutoff
            f = (cos_g + 1.0) / (FOUR_PI * denom)
            lx = f * cx
            ly = f * cy
            lz = f * cz
            if h2 < _TINY2:
                lx = 0.0
                ly = 0.0
                lz = 0.0
            d0, d1, d2 = s[q + CDX + l], s[q + CDY + l], s[q + CDZ + l]
            ex = d1 * az - d2 * ay
            ey = d2 * ax - d0 * az
            ez = d0 * ay - d1 * ax
            g2 = ex * ex + ey * ey + ez * ez
            cg = (d0 * ax + d1 * ay + d2 * az) * inv_a
            cd = (d0 * bx + d1 * by + d2 * bz) * inv_b
            denom = g2 if g2 >= c2 else math.sqrt(g2) * cutoff
            fc = (cg - cd) / (FOUR_PI * denom)
            sx = fc * ex
            sy = fc * ey
            sz = fc * ez
            if g2 < _TINY2:
                sx = 0.0
                sy = 0.0
                sz = 0.0
            s[q + I1 + l] = inv_b
            s[q + LCX + l] = sx - lx
            s[q + LCY + l] = sy - ly
            s[q + LCZ + l] = sz - lz


@_jit
def _own_bounds(s, pt, k0, k1, cutoff):
    """The own bound branches X1[k] -> X1[k + 1], k in k0..k1-1, seen from the midpoint with the plain law and the
    cutoff into BX..BZ, every lane (:func:`formation_env.wake.lanes.own_field_bounds`'s operations; :func:`_own_field`
    filled I1). The lane of a surface's last knot is junk, never read."""
    c2 = cutoff * cutoff
    for k in range(np.uint64(k0), np.uint64(k1)):
        q = k * _U_STRIDE
        qn = q + _U_STRIDE
        for l in range(np.uint64(LANES)):
            px, py, pz = pt[PX + l], pt[PY + l], pt[PZ + l]
            d0, d1, d2 = s[q + BDX + l], s[q + BDY + l], s[q + BDZ + l]
            ax, ay, az = px - s[q + X1X + l], py - s[q + X1Y + l], pz - s[q + X1Z + l]
            bx, by, bz = px - s[qn + X1X + l], py - s[qn + X1Y + l], pz - s[qn + X1Z + l]
            cx = d1 * az - d2 * ay
            cy = d2 * ax - d0 * az
            cz = d0 * ay - d1 * ax
            h2 = cx * cx + cy * cy + cz * cz
            cg = (d0 * ax + d1 * ay + d2 * az) * s[q + I1 + l]
            cd = (d0 * bx + d1 * by + d2 * bz) * s[qn + I1 + l]
            denom = h2 if h2 >= c2 else math.sqrt(h2) * cutoff
            f = (cg - cd) / (FOUR_PI * denom)
            ux = f * cx
            uy = f * cy
            uz = f * cz
            if h2 < _TINY2:
                ux = 0.0
                uy = 0.0
                uz = 0.0
            s[q + BX + l] = ux
            s[q + BY + l] = uy
            s[q + BZ + l] = uz


@_jit
def _own_pair_sums(s, v, gf, ga, lat, out):
    """The own horseshoes' velocity at the midpoint for the circulations ``gf`` (N, LANES) into ``out[0:3]`` and
    ``ga`` into ``out[3:6]`` (6, LANES): :func:`formation_env.wake.benefit._own_pair_sum`'s sums in its order, a
    term skipped where its circulation is zero."""
    out[:, :] = 0.0
    sv, ksk, psk = lat.surface_vehicle, lat.surface_knot_start, lat.surface_panel_start
    for srf in range(sv.shape[0]):
        if sv[srf] != v:
            continue
        k0 = ksk[srf]
        k1 = ksk[srf + 1]
        p0 = psk[srf]
        for k in range(k0, k1):
            q = k * _STRIDE
            nxt = k < k1 - 1
            prv = k > k0
            i = p0 + (k - k0)
            for l in range(LANES):
                g = 0.0
                g2 = 0.0
                if nxt:
                    g += gf[i, l]
                    g2 += ga[i, l]
                if prv:
                    g -= gf[i - 1, l]
                    g2 -= ga[i - 1, l]
                dx, dy, dz = s[q + LCX + l], s[q + LCY + l], s[q + LCZ + l]
                if g != 0.0:
                    out[0, l] += g * dx
                    out[1, l] += g * dy
                    out[2, l] += g * dz
                if g2 != 0.0:
                    out[3, l] += g2 * dx
                    out[4, l] += g2 * dy
                    out[5, l] += g2 * dz
                if nxt:
                    bx, by, bz = s[q + BX + l], s[q + BY + l], s[q + BZ + l]
                    gp = gf[i, l]
                    out[0, l] += gp * bx
                    out[1, l] += gp * by
                    out[2, l] += gp * bz
                    gp2 = ga[i, l]
                    out[3, l] += gp2 * bx
                    out[4, l] += gp2 * by
                    out[5, l] += gp2 * bz


@_jit
def _other_sums(s, v, gf, lat, out):
    """The other vehicles' velocity at the midpoint for the circulations ``gf`` (N, LANES) into ``out`` (3, LANES):
    :func:`formation_env.wake.benefit._other_field_sum`'s sum in its order."""
    out[:, :] = 0.0
    sv, ksk, psk = lat.surface_vehicle, lat.surface_knot_start, lat.surface_panel_start
    for srf in range(sv.shape[0]):
        if sv[srf] == v:
            continue
        k0 = ksk[srf]
        k1 = ksk[srf + 1]
        p0 = psk[srf]
        for k in range(k0, k1):
            q = k * _STRIDE
            nxt = k < k1 - 1
            prv = k > k0
            i = p0 + (k - k0)
            for l in range(LANES):
                g = 0.0
                if nxt:
                    g += gf[i, l]
                if prv:
                    g -= gf[i - 1, l]
                if g != 0.0:
                    out[0, l] += g * s[q + LCX + l]
                    out[1, l] += g * s[q + LCY + l]
                    out[2, l] += g * s[q + LCZ + l]
                if nxt:
                    gp = gf[i, l]
                    out[0, l] += gp * s[q + BX + l]
                    out[1, l] += gp * s[q + BY + l]
                    out[2, l] += gp * s[q + BZ + l]


@_jit
def _alone_circulations(lat, n_alone, keep, ga):
    """Each vehicle's circulation flying alone into ``ga`` (N, LANES): its diagonal block of the kept AIC and
    right-hand side ``keep`` (LANES, N, N + 1) solved, every lane (``induced_drags_one``'s reuse of the kept solve;
    :func:`formation_env.wake.aic.lu_solve_lanes` is the scalar elimination per lane)."""
    n_panels = lat.panel_vehicle.shape[0]
    blk = np.empty((n_alone, n_alone, LANES))
    rhs = np.empty((n_alone, LANES))
    piv = np.empty(LANES, np.int64)
    for v in range(lat.vehicle_panel_start.shape[0] - 1):
        p0 = lat.vehicle_panel_start[v]
        for i in range(n_alone):
            for c in range(n_alone):
                for l in range(LANES):
                    blk[i, c, l] = keep[l, p0 + i, p0 + c]
            for l in range(LANES):
                rhs[i, l] = keep[l, p0 + i, n_panels]
        lu_solve_lanes(blk, rhs, piv)
        for i in range(n_alone):
            for l in range(LANES):
                ga[p0 + i, l] = rhs[i, l]


@_jit
def induced_drags_chunk(wake, n_alone, c, speed, alpha, beta, gamma, keep, air_density, out_formation, out_alone):
    """Induced drag (N, wind axes) of each of the V vehicles of LANES formations in formation (``out_formation``
    (LANES, V)) and alone at the same pose and air data (``out_alone``): per lane, bit for bit
    :func:`formation_env.wake.benefit.induced_drags_one` with the kept solve.

    ``c`` the chunk scratch as :func:`formation_env.wake.across.solve_chunk_lanes` left it for these formations'
    poses (``speed``, ``alpha``, ``beta`` (LANES, V) their air data); ``gamma`` (LANES, N) their circulations;
    ``keep`` (LANES, N, N + 1) the AIC and right-hand side of that solve before elimination; ``n_alone`` the panels of
    one vehicle (every vehicle of the lattice of that make-up). The lattice is one that solves across lanes
    (:func:`formation_env.wake.across.chunk_pays`: the field's core that of the solve). The midpoint rows of the
    scratch are overwritten; its poses are kept."""
    lat = wake.lattice
    s, pt = c.s, c.p
    kv, ksk, pv = lat.knot_vehicle, lat.surface_knot_start, lat.panel_vehicle
    n_panels = pv.shape[0]
    n_knots = kv.shape[0]
    nv = c.rot.shape[1]
    cutoff = lat.cutoff_m
    sheet_law = sheet_on(wake.sheet)
    for v in range(nv):
        if lat.vehicle_panel_start[v + 1] - lat.vehicle_panel_start[v] != n_alone:
            raise ValueError("induced_drags_chunk: n_alone differs from a vehicle's panel count (every vehicle must "
                             "be of the make-up of the lone lattice)")
    gf = np.empty((n_panels, LANES))
    for l in range(LANES):
        for j in range(n_panels):
            gf[j, l] = gamma[l, j]
    ga = np.empty((n_panels, LANES))
    _alone_circulations(lat, n_alone, keep, ga)
    vk0, vk1 = vehicle_knot_ranges(kv, nv)
    f = np.zeros((LANES, nv, 3))  # summed Kutta-Joukowski force per vehicle, NED: in formation
    fa = np.zeros((LANES, nv, 3))  # and alone
    seg = np.empty((3, LANES))
    own = np.empty((6, LANES))
    ext = np.empty((3, LANES))
    for j in range(n_panels):
        v = pv[j]
        k = lat.panel_left_knot[j]
        a, b = vk0[v], vk1[v]
        for l in range(LANES):
            x1 = c.x1[l]
            lx, ly, lz = x1[k + 1, 0] - x1[k, 0], x1[k + 1, 1] - x1[k, 1], x1[k + 1, 2] - x1[k, 2]
            seg[0, l], seg[1, l], seg[2, l] = lx, ly, lz
            pt[PX + l] = 0.5 * (x1[k, 0] + x1[k + 1, 0])
            pt[PY + l] = 0.5 * (x1[k, 1] + x1[k + 1, 1])
            pt[PZ + l] = 0.5 * (x1[k, 2] + x1[k + 1, 2])
            pt[N0 + l] = 0.0
            pt[N1 + l] = 0.0
            pt[N2 + l] = 0.0
            pt[RW + l] = np.sqrt(lx * lx + ly * ly + lz * lz) if sheet_law else 0.0
        _own_field(s, pt, a, b, cutoff)
        if b - 1 > a:
            _own_bounds(s, pt, a, b - 1, cutoff)
        _own_pair_sums(s, v, gf, ga, lat, own)
        other_vehicles_rows(lat, wake.sheet, speed, 0, LANES, c, v, a, b)
        for srf in range(ksk.shape[0] - 1):
            if kv[ksk[srf]] != v:
                _fix_bounds(s, ksk[srf], ksk[srf + 1] - 1, c, lat.cutoff_m, lat.overlap_core_m)
        _other_sums(s, v, gf, lat, ext)
        for l in range(LANES):
            w0, w1, w2 = c.vel[l, v, 0], c.vel[l, v, 1], c.vel[l, v, 2]
            lx, ly, lz = seg[0, l], seg[1, l], seg[2, l]
            _add_kutta_joukowski(f[l], v, air_density * gf[j, l], w0, w1, w2, own[0, l], own[1, l], own[2, l],
                                 ext[0, l], ext[1, l], ext[2, l], lx, ly, lz)
            _add_kutta_joukowski(fa[l], v, air_density * ga[j, l], w0, w1, w2, own[3, l], own[4, l], own[5, l], 0.0,
                                 0.0, 0.0, lx, ly, lz)
    for l in range(LANES):
        for v in range(nv):
            out_formation[l, v] = _wind_axis_drag(c.rot[l, v], f[l, v], alpha[l, v], beta[l, v])
            out_alone[l, v] = _wind_axis_drag(c.rot[l, v], fa[l, v], alpha[l, v], beta[l, v])
