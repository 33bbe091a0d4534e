"""The AIC's rows over the knots as vector lanes (issue 26): the other vehicles' L-lines (chordwise branch and
trailing leg) and bound branches, and a vehicle's own trailing legs, evaluated for all knots of a control point in
loops that LLVM vectorises (AVX2 / AVX-512 here), bit for bit the scalar laws of :mod:`.biot_savart`.

Why the layout: numba gives LLVM no no-alias information about array arguments, so a loop writing several arrays
is either not vectorised or guarded by runtime overlap checks between every pair of arrays (measured: ~600
comparisons for the L-line pass, more than the 11-44-lane loop of one control point costs). Here every value lives
in one flat scratch array at compile-time-constant row offsets (:data:`KMAX` knots a row) indexed by an unsigned
lane (numba wraps a negative signed index, which hides the address from LLVM): the distances between rows are
constants, so LLVM vectorises with no runtime check.

Exactness: each lane performs the scalar law's operations in the same order (IEEE division and square root are
correctly rounded in vector form too; nothing is reassociated or contracted: no fastmath), and takes the *fast
form* only where the scalar law's own tests select it: every core factor exactly 1.0 (the viscous core's and the
overlap core's exponent beyond 40, tested as the laws test it), the sheet law, when on, falling back to the
discrete leg. Any other lane is flagged and recomputed by the scalar law (:func:`fix_llines`, and the bound
branches in the assembly), so the AIC, the circulation and the branch vectors equal the scalar assembly's bit for
bit (``tests/wake/test_aic_lanes.py`` holds them to :func:`formation_env.wake.aic.assemble_and_solve_scalar`).

Frames and units: NED earth, metres, per unit circulation.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from .biot_savart import (_TINY_H, CORE_NONE, FOUR_PI, SHEET_BLEND_OUTER, STRIP_OK, STRIP_W, branch_cored, core_radius,
                          leg_cored, leg_sheet_framed, sheet_on)

__all__ = ["KMAX", "N_ROWS", "lane_scratch", "load_knots", "vehicle_knot_ranges", "own_legs", "other_llines",
           "fix_llines", "other_bounds", "fix_bounds", "fill_core_radius", "own_panel_row", "other_panel_row",
           "own_field_lanes", "own_field_bounds"]

_jit = nb.njit(cache=True, fastmath=False, error_model="numpy")
# the per-control-point scalar parts, inlined into the assembly's loop (a call passing their ~10 arrays was a sizeable
# part of a 2-UAV solve); the lane loops stay functions of their own, where LLVM vectorises them. Inlined by LLVM
# (forceinline), not at numba IR level: see formation_env.wake.biot_savart's _jit_inline
_jit_inline = nb.njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
_TINY2 = _TINY_H * _TINY_H  # the laws' "point on the branch line" test, h^2 < _TINY_H^2

#: knots per formation a row of the scratch holds (vee9: 99); a lattice with more takes the scalar assembly
KMAX = 128
_ROWS = ("X1X", "X1Y", "X1Z", "X3X", "X3Y", "X3Z", "CDX", "CDY", "CDZ", "BDX", "BDY", "BDZ", "TX", "TY", "TZ", "SW",
         "SOK", "RC", "I1", "LW", "CW", "LCX", "LCY", "LCZ", "LM", "BX", "BY", "BZ", "BM", "OI1", "OLX", "OLY", "OLZ",
         "OBX", "OBY", "OBZ")
N_ROWS = len(_ROWS)
# row offsets: signed for the scalar code, unsigned for the lane loops (an unsigned index is never wrapped)
(X1X, X1Y, X1Z, X3X, X3Y, X3Z, CDX, CDY, CDZ, BDX, BDY, BDZ, TX, TY, TZ, SW, SOK, RC, I1, LW, CW, LCX, LCY, LCZ, LM,
 BX, BY, BZ, BM, OI1, OLX, OLY, OLZ, OBX, OBY, OBZ) = [i * KMAX for i in range(N_ROWS)]
(U_X1X, U_X1Y, U_X1Z, U_X3X, U_X3Y, U_X3Z, U_CDX, U_CDY, U_CDZ, U_BDX, U_BDY, U_BDZ, U_TX, U_TY, U_TZ, U_SW, U_SOK,
 U_RC, U_I1, U_LW, U_CW, U_LCX, U_LCY, U_LCZ, U_LM, U_BX, U_BY, U_BZ, U_BM, U_OI1, U_OLX, U_OLY, U_OLZ, U_OBX, U_OBY,
 U_OBZ) = [np.uint64(i * KMAX) for i in range(N_ROWS)]
_U1 = np.uint64(1)


@_jit
def lane_scratch():
    """The flat scratch of one solve: N_ROWS rows of KMAX knots."""
    return np.empty(N_ROWS * KMAX)


@_jit
def load_knots(s, x1, x3, chord_dir, bound_dir, trail, knot_vehicle, frames, sheet):
    """The posed knots (NED), their chordwise and bound directions, their vehicle's trailing-leg direction and, with
    the sheet law, their strip's width and existence into the scratch rows."""
    for k in range(x1.shape[0]):
        v = knot_vehicle[k]
        s[X1X + k], s[X1Y + k], s[X1Z + k] = x1[k, 0], x1[k, 1], x1[k, 2]
        s[X3X + k], s[X3Y + k], s[X3Z + k] = x3[k, 0], x3[k, 1], x3[k, 2]
        s[CDX + k], s[CDY + k], s[CDZ + k] = chord_dir[k, 0], chord_dir[k, 1], chord_dir[k, 2]
        s[BDX + k], s[BDY + k], s[BDZ + k] = bound_dir[k, 0], bound_dir[k, 1], bound_dir[k, 2]
        s[TX + k], s[TY + k], s[TZ + k] = trail[v, 0], trail[v, 1], trail[v, 2]
        if sheet_on(sheet):
            s[SW + k] = frames[k, STRIP_W]
            s[SOK + k] = frames[k, STRIP_OK]
        else:
            s[SW + k] = 0.0
            s[SOK + k] = 0.0


@_jit
def vehicle_knot_ranges(knot_vehicle, nveh):
    """Each vehicle's knots: (vk0, vk1), its knots vk0[v] .. vk1[v] - 1 (the lattice keeps a vehicle's knots
    contiguous)."""
    n_knots = knot_vehicle.shape[0]
    vk0 = np.full(nveh, n_knots)
    vk1 = np.zeros(nveh, np.int64)
    for k in range(n_knots):
        v = knot_vehicle[k]
        vk0[v] = min(vk0[v], k)
        vk1[v] = max(vk1[v], k + 1)
    return vk0, vk1


@_jit
def own_legs(s, k0, k1, px, py, pz, n0, n1, n2, cutoff):
    """Row LW at knots k0..k1-1 (the receiving vehicle's own): its trailing legs' normal velocity at P (normal n),
    the plain law with the Eq. 4.31 cutoff (:func:`formation_env.wake.biot_savart.leg` with no core) in every lane."""
    c2 = cutoff * cutoff
    for k in range(np.uint64(k0), np.uint64(k1)):
        ax = px - s[U_X3X + k]
        ay = py - s[U_X3Y + k]
        az = pz - s[U_X3Z + k]
        nrm = math.sqrt(ax * ax + ay * ay + az * az)
        inv = 1.0 / nrm if nrm > 0.0 else 0.0
        tx, ty, tz = s[U_TX + k], s[U_TY + k], s[U_TZ + k]
        cx = ty * az - tz * ay
        cy = tz * ax - tx * az
        cz = tx * ay - ty * ax
        h2 = cx * cx + cy * cy + cz * cz
        cos_g = (tx * ax + ty * ay + tz * az) * inv
        denom = h2 if h2 >= c2 else math.sqrt(h2) * cutoff
        f = (cos_g + 1.0) / (FOUR_PI * denom)
        lx = f * cx
        ly = f * cy
        lz = f * cz
        if h2 < _TINY2:
            lx = 0.0
            ly = 0.0
            lz = 0.0
        s[U_LW + k] = lx * n0 + ly * n1 + lz * n2


@_jit_inline
def fill_core_radius(s, px, py, pz, vj, origin, airspeed, knot_vehicle, surface_knot_start, surface_core_scale,
                     aic_core_mode, nu):
    """Row RC: the viscous core radius of each other vehicle's legs at P (one per surface, as the scalar assembly
    computes it; 0 without the viscous core in the solve)."""
    for srf in range(surface_knot_start.shape[0] - 1):
        k0 = surface_knot_start[srf]
        k1 = surface_knot_start[srf + 1]
        src = knot_vehicle[k0]
        if src == vj:
            continue
        rc = 0.0
        if aic_core_mode != CORE_NONE:
            rc = core_radius(px, py, pz, origin, srf, airspeed[src], surface_core_scale, aic_core_mode, nu)
        for k in range(k0, k1):
            s[RC + k] = rc


@_jit
def other_llines(s, k0, k1, px, py, pz, n0, n1, n2, cutoff, ro2, recv_w, sheet_law):
    """Another vehicle's knots k0..k1-1 seen from P: I1 = 1 / |P - X1|, LW and CW the normal velocity of the trailing
    leg (from X3, :func:`~formation_env.wake.biot_savart.leg_cored`) and the chordwise branch X3 -> X1
    (:func:`~formation_env.wake.biot_savart.branch_cored`), LCX..LCZ their difference (chordwise - leg), in their
    fast form; LM 1.0 where that form is not the law's (a core factor below 1, the sheet region when ``sheet_law``), for
    :func:`fix_llines`. ``ro2`` the overlap core squared (inf: no overlap core, every lane flagged)."""
    for k in range(np.uint64(k0), np.uint64(k1)):
        bx = px - s[U_X1X + k]
        by = py - s[U_X1Y + k]
        bz = pz - s[U_X1Z + k]
        nb_ = math.sqrt(bx * bx + by * by + bz * bz)
        inv_b = 1.0 / nb_ if nb_ > 0.0 else 0.0
        ax = px - s[U_X3X + k]
        ay = py - s[U_X3Y + k]
        az = pz - s[U_X3Z + k]
        a2 = ax * ax + ay * ay + az * az
        na = math.sqrt(a2)
        inv_a = 1.0 / na if na > 0.0 else 0.0
        t0, t1, t2 = s[U_TX + k], s[U_TY + k], s[U_TZ + k]
        cx = t1 * az - t2 * ay
        cy = t2 * ax - t0 * az
        cz = t0 * ay - t1 * ax
        h2 = cx * cx + cy * cy + cz * cz
        ta = t0 * ax + t1 * ay + t2 * az
        crad = max(s[U_RC + k], cutoff)
        xcore = 1.26 * h2 / (crad * crad)
        f = (ta * inv_a + 1.0) / (FOUR_PI * h2)  # the leg's law with its core factor 1.0
        lx = f * cx
        ly = f * cy
        lz = f * cz
        if h2 < _TINY2:
            lx = 0.0
            ly = 0.0
            lz = 0.0
        d0, d1, d2 = s[U_CDX + k], s[U_CDY + k], s[U_CDZ + k]
        ex = d1 * az - d2 * ay
        ey = d2 * ax - d0 * az
        ez = d0 * ay - d1 * ax
        g2 = ex * ex + ey * ey + ez * ez
        sa = d0 * ax + d1 * ay + d2 * az
        sb = d0 * bx + d1 * by + d2 * bz
        ma = min(sa, 0.0)
        mb = max(sb, 0.0)
        rho2 = g2 + ma * ma + mb * mb
        fc = (sa * inv_a - sb * inv_b) / (FOUR_PI * g2)  # the branch's law with its overlap factor 1.0
        sx = fc * ex
        sy = fc * ey
        sz = fc * ez
        if g2 < _TINY2:
            sx = 0.0
            sy = 0.0
            sz = 0.0
        s[U_I1 + k] = inv_b
        s[U_LW + k] = lx * n0 + ly * n1 + lz * n2
        s[U_CW + k] = sx * n0 + sy * n1 + sz * n2
        s[U_LCX + k] = sx - lx
        s[U_LCY + k] = sy - ly
        s[U_LCZ + k] = sz - lz
        # the scalar laws' own tests, non-short-circuit so that the loop stays branch-free
        outer = SHEET_BLEND_OUTER * max(s[U_SW + k], recv_w)
        rp2 = max(a2 - ta * ta, 0.0)
        in_sheet = sheet_law & (s[U_SOK + k] != 0.0) & (rp2 < outer * outer)
        fast = ((xcore > 40.0) | (h2 < _TINY2)) & (1.26 * a2 > 40.0 * ro2) & ((1.26 * rho2 > 40.0 * ro2) | (g2 < _TINY2))
        s[U_LM + k] = 0.0 if (fast & ~in_sheet) else 1.0


@_jit_inline
def fix_llines(s, k0, k1, px, py, pz, n0, n1, n2, x1, x3, chord_dir, trail, knot_vehicle, cutoff, overlap_core,
               frames, recv_w, sheet):
    """The flagged lanes of :func:`other_llines` (k0..k1-1) by the scalar laws, exactly as the scalar assembly
    evaluates them (``sheet`` the kernels' switch, :func:`formation_env.wake.biot_savart.sheet_on`)."""
    for k in range(k0, k1):
        if s[LM + k] == 0.0:
            continue
        src = knot_vehicle[k]
        tx, ty, tz = trail[src, 0], trail[src, 1], trail[src, 2]
        ax, ay, az = px - x3[k, 0], py - x3[k, 1], pz - x3[k, 2]
        na = math.sqrt(ax * ax + ay * ay + az * az)
        ia = 1.0 / na if na > 0.0 else 0.0
        if sheet_on(sheet):
            lx, ly, lz = leg_sheet_framed(tx, ty, tz, ax, ay, az, ia, cutoff, s[RC + k], overlap_core, frames[k],
                                          recv_w)
        else:
            lx, ly, lz = leg_cored(tx, ty, tz, ax, ay, az, ia, cutoff, s[RC + k], overlap_core)
        sx, sy, sz = branch_cored(chord_dir[k, 0], chord_dir[k, 1], chord_dir[k, 2], ax, ay, az, ia,
                                  px - x1[k, 0], py - x1[k, 1], pz - x1[k, 2], s[I1 + k], cutoff, overlap_core)
        s[LW + k] = lx * n0 + ly * n1 + lz * n2
        s[CW + k] = sx * n0 + sy * n1 + sz * n2
        s[LCX + k] = sx - lx
        s[LCY + k] = sy - ly
        s[LCZ + k] = sz - lz


@_jit
def other_bounds(s, k0, k1, px, py, pz, ro2):
    """The bound branch X1[k] -> X1[k + 1] seen from P for k in k0..k1-1 (the lane of a surface's last knot is
    junk, never read) into BX..BZ in its fast form (overlap factor 1.0; :func:`other_llines` must have filled I1),
    BM 1.0 where that is not the law's."""
    for k in range(np.uint64(k0), np.uint64(k1)):
        d0, d1, d2 = s[U_BDX + k], s[U_BDY + k], s[U_BDZ + k]
        ax, ay, az = px - s[U_X1X + k], py - s[U_X1Y + k], pz - s[U_X1Z + k]
        bx, by, bz = px - s[U_X1X + k + _U1], py - s[U_X1Y + k + _U1], pz - s[U_X1Z + k + _U1]
        cx = d1 * az - d2 * ay
        cy = d2 * ax - d0 * az
        cz = d0 * ay - d1 * ax
        h2 = cx * cx + cy * cy + cz * cz
        sa = d0 * ax + d1 * ay + d2 * az
        sb = d0 * bx + d1 * by + d2 * bz
        ma = min(sa, 0.0)
        mb = max(sb, 0.0)
        rho2 = h2 + ma * ma + mb * mb
        f = (sa * s[U_I1 + k] - sb * s[U_I1 + k + _U1]) / (FOUR_PI * h2)
        ux = f * cx
        uy = f * cy
        uz = f * cz
        if h2 < _TINY2:
            ux = 0.0
            uy = 0.0
            uz = 0.0
        s[U_BX + k] = ux
        s[U_BY + k] = uy
        s[U_BZ + k] = uz
        s[U_BM + k] = 0.0 if ((1.26 * rho2 > 40.0 * ro2) | (h2 < _TINY2)) else 1.0


@_jit_inline
def fix_bounds(s, k0, k1, px, py, pz, x1, bound_dir, cutoff, overlap_core):
    """The flagged lanes of :func:`other_bounds` (k0..k1-1) by the scalar law
    (:func:`~formation_env.wake.biot_savart.branch_cored`), as the scalar assembly and field evaluate them."""
    for k in range(k0, k1):
        if s[BM + k] != 0.0:
            s[BX + k], s[BY + k], s[BZ + k] = branch_cored(
                bound_dir[k, 0], bound_dir[k, 1], bound_dir[k, 2], px - x1[k, 0], py - x1[k, 1], pz - x1[k, 2],
                s[I1 + k], px - x1[k + 1, 0], py - x1[k + 1, 1], pz - x1[k + 1, 2], s[I1 + k + 1], cutoff,
                overlap_core)


@_jit
def own_panel_row(s, aic, aic_static, j, p0, k0, npan):
    """AIC row j at a vehicle's own panels p0..p0+npan-1 (left knots k0..): the static own part plus the own
    trailing legs of row LW."""
    p0u = np.uint64(p0)
    k0u = np.uint64(k0)
    for i in range(np.uint64(npan)):
        k = k0u + i
        aic[j, p0u + i] = aic_static[j, p0u + i] - s[U_LW + k] + s[U_LW + k + _U1]


@_jit
def other_panel_row(s, aic, vcross, j, p0, k0, npan, n0, n1, n2, store):
    """AIC row j at another vehicle's panels p0..p0+npan-1 (left knots k0..): L-line k + bound - L-line k + 1 from
    rows CW, LW, BX..BZ (the bound lanes already exact), and with ``store`` the horseshoes' vectors into
    ``vcross[j, p]``; the scalar assembly's expressions."""
    p0u = np.uint64(p0)
    k0u = np.uint64(k0)
    for i in range(np.uint64(npan)):
        k = k0u + i
        p = p0u + i
        bx, by, bz = s[U_BX + k], s[U_BY + k], s[U_BZ + k]
        aic[j, p] = ((s[U_CW + k] - s[U_LW + k]) + bx * n0 + by * n1 + bz * n2
                     - (s[U_CW + k + _U1] - s[U_LW + k + _U1]))
        if store:
            vcross[j, p, 0] = s[U_LCX + k] + bx - s[U_LCX + k + _U1]
            vcross[j, p, 1] = s[U_LCY + k] + by - s[U_LCY + k + _U1]
            vcross[j, p, 2] = s[U_LCZ + k] + bz - s[U_LCZ + k + _U1]


@_jit
def own_field_lanes(s, k0, k1, px, py, pz, cutoff):
    """A vehicle's own knots k0..k1-1 seen from P with the solve's law (plain Biot-Savart, the Eq. 4.31 cutoff, no
    core; :func:`~formation_env.wake.biot_savart.leg` and :func:`~formation_env.wake.biot_savart.branch`): OI1 =
    1 / |P - X1| and OLX..OLZ the L-line vector (chordwise - leg), every lane exact (the laws' only other case, a
    point on the line, is a select); the bound branches are :func:`own_field_bounds`'s."""
    c2 = cutoff * cutoff
    for k in range(np.uint64(k0), np.uint64(k1)):
        bx = px - s[U_X1X + k]
        by = py - s[U_X1Y + k]
        bz = pz - s[U_X1Z + k]
        nb_ = math.sqrt(bx * bx + by * by + bz * bz)
        inv_b = 1.0 / nb_ if nb_ > 0.0 else 0.0
        ax = px - s[U_X3X + k]
        ay = py - s[U_X3Y + k]
        az = pz - s[U_X3Z + k]
        na = math.sqrt(ax * ax + ay * ay + az * az)
        inv_a = 1.0 / na if na > 0.0 else 0.0
        tx, ty, tz = s[U_TX + k], s[U_TY + k], s[U_TZ + k]
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
        d0, d1, d2 = s[U_CDX + k], s[U_CDY + k], s[U_CDZ + k]
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
        s[U_OI1 + k] = inv_b
        s[U_OLX + k] = sx - lx
        s[U_OLY + k] = sy - ly
        s[U_OLZ + k] = sz - lz


@_jit
def own_field_bounds(s, k0, k1, px, py, pz, cutoff):
    """The own bound branches X1[k] -> X1[k + 1], k in k0..k1-1, seen from P with the plain law and the cutoff
    (:func:`~formation_env.wake.biot_savart.branch`) into OBX..OBZ (:func:`own_field_lanes` must have filled OI1);
    the lane of a surface's last knot is junk."""
    c2 = cutoff * cutoff
    for k in range(np.uint64(k0), np.uint64(k1)):
        d0, d1, d2 = s[U_BDX + k], s[U_BDY + k], s[U_BDZ + k]
        ax, ay, az = px - s[U_X1X + k], py - s[U_X1Y + k], pz - s[U_X1Z + k]
        bx, by, bz = px - s[U_X1X + k + _U1], py - s[U_X1Y + k + _U1], pz - s[U_X1Z + k + _U1]
        cx = d1 * az - d2 * ay
        cy = d2 * ax - d0 * az
        cz = d0 * ay - d1 * ax
        h2 = cx * cx + cy * cy + cz * cz
        cg = (d0 * ax + d1 * ay + d2 * az) * s[U_OI1 + k]
        cd = (d0 * bx + d1 * by + d2 * bz) * s[U_OI1 + k + _U1]
        denom = h2 if h2 >= c2 else math.sqrt(h2) * cutoff
        f = (cg - cd) / (FOUR_PI * denom)
        ux = f * cx
        uy = f * cy
        uz = f * cz
        if h2 < _TINY2:
            ux = 0.0
            uy = 0.0
            uz = 0.0
        s[U_OBX + k] = ux
        s[U_OBY + k] = uy
        s[U_OBZ + k] = uz
