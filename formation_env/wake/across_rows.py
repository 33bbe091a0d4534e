"""The lane rows of a chunk of formations (:mod:`.across`) and the kernels that fill its AIC rows from them: the
branch laws of every knot for all LANES formations of the chunk at once.

Layout: one flat scratch array per chunk (:func:`.across.chunk_scratch`), knot-major: the value of row ``r`` at knot ``k``
and lane ``l`` is at ``HEAD + (k * N_ROWS + r) * LANES + l``; the control point's own values (its position and
normal in NED, the receiving width) sit in the head at ``r * LANES + l``. Every distance between two rows is a
compile-time constant, so LLVM vectorises the lane loops without runtime alias checks (numba passes arrays without
no-alias information; see :mod:`.lanes`).

Each kernel performs, per lane, the operations of its per-formation counterpart in :mod:`.lanes` in the same order
(no fastmath), so every lane's numbers are that formation's own, bit for bit. Frames and units: NED earth, metres,
m/s, per unit circulation.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from .biot_savart import (_MIN_CORE_M, _TINY_H, CORE_LAMB_OSEEN, CORE_NONE, FOUR_PI, KURYLOWICH_C, LAMB_OSEEN_C,
                          SHEET_BLEND_OUTER, branch_cored, leg_cored, leg_sheet_framed, sheet_on)

__all__ = ["LANES", "N_ROWS"]

_jit = nb.njit(cache=True, fastmath=False, error_model="numpy")
_TINY2 = _TINY_H * _TINY_H

#: formations per chunk: the vector width the lane loops are written for (8 float64 lanes of AVX-512, two AVX2
#: vectors)
LANES = 16
_ROWS = ("X1X", "X1Y", "X1Z", "X3X", "X3Y", "X3Z", "CDX", "CDY", "CDZ", "BDX", "BDY", "BDZ", "TX", "TY", "TZ", "SW",
         "SOK", "RC", "I1", "LW", "CW", "LCX", "LCY", "LCZ", "LM", "BX", "BY", "BZ", "BM")
N_ROWS = len(_ROWS)
_HEAD_ROWS = ("PX", "PY", "PZ", "N0", "N1", "N2", "RW")
_N_HEAD = len(_HEAD_ROWS)
_STRIDE = N_ROWS * LANES  # from one knot to the next
# row offsets within a knot's block (unsigned: an unsigned index is never wrapped, which keeps the address visible)
(X1X, X1Y, X1Z, X3X, X3Y, X3Z, CDX, CDY, CDZ, BDX, BDY, BDZ, TX, TY, TZ, SW, SOK, RC, I1, LW, CW, LCX, LCY, LCZ, LM,
 BX, BY, BZ, BM) = [np.uint64(i * LANES) for i in range(N_ROWS)]
PX, PY, PZ, N0, N1, N2, RW = [np.uint64(i * LANES) for i in range(len(_HEAD_ROWS))]
_U_STRIDE = np.uint64(_STRIDE)


@_jit
def _own_legs(s, pt, k0, k1, cutoff):
    """Row LW at the receiving vehicle's own knots k0..k1-1: its trailing legs' normal velocity at the control
    point, the plain law with the Eq. 4.31 cutoff in every lane (:func:`formation_env.wake.lanes.own_legs`)."""
    c2 = cutoff * cutoff
    for k in range(np.uint64(k0), np.uint64(k1)):
        q = k * _U_STRIDE
        for l in range(np.uint64(LANES)):
            ax = pt[PX + l] - s[q + X3X + l]
            ay = pt[PY + l] - s[q + X3Y + l]
            az = pt[PZ + l] - s[q + X3Z + l]
            nrm = math.sqrt(ax * ax + ay * ay + az * az)
            inv = 1.0 / nrm if nrm > 0.0 else 0.0
            tx, ty, tz = s[q + TX + l], s[q + TY + l], s[q + TZ + l]
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
            s[q + LW + l] = lx * pt[N0 + l] + ly * pt[N1 + l] + lz * pt[N2 + l]


@_jit
def _core_radius(s, k0, k1, c, srf, src, lat, airspeed, b0, nl):
    """Row RC at surface srf's knots k0..k1-1: the viscous core radius of its legs at the control point
    (:func:`formation_env.wake.biot_savart.core_radius`'s operations; 0 without the core in the solve)."""
    mode = lat.aic_core_mode
    cc = LAMB_OSEEN_C if mode == CORE_LAMB_OSEEN else KURYLOWICH_C * lat.surface_core_scale[srf]
    nu = lat.kinematic_viscosity
    pt = c.p
    rc = np.empty(LANES)
    for l in range(LANES):
        rc[l] = 0.0
        if mode != CORE_NONE:
            ox = pt[PX + l] - c.origin[l, srf, 0]
            oy = pt[PY + l] - c.origin[l, srf, 1]
            oz = pt[PZ + l] - c.origin[l, srf, 2]
            tau = math.sqrt(ox * ox + oy * oy + oz * oz) / airspeed[b0 + min(l, nl - 1), src]
            rc[l] = max(cc * math.sqrt(nu * tau), _MIN_CORE_M)
    for k in range(k0, k1):
        q = k * _STRIDE
        for l in range(LANES):
            s[q + RC + l] = rc[l]


@_jit
def _other_llines(s, pt, k0, k1, cutoff, ro2, sheet_law):
    """Another vehicle's knots k0..k1-1 seen from the control point, every lane: I1, LW, CW, LCX..LCZ in the fast
    form and LM 1.0 where that is not the law's (:func:`formation_env.wake.lanes.other_llines`'s operations)."""
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
            a2 = ax * ax + ay * ay + az * az
            na = math.sqrt(a2)
            inv_a = 1.0 / na if na > 0.0 else 0.0
            t0, t1, t2 = s[q + TX + l], s[q + TY + l], s[q + TZ + l]
            cx = t1 * az - t2 * ay
            cy = t2 * ax - t0 * az
            cz = t0 * ay - t1 * ax
            h2 = cx * cx + cy * cy + cz * cz
            ta = t0 * ax + t1 * ay + t2 * az
            crad = max(s[q + RC + l], cutoff)
            xcore = 1.26 * h2 / (crad * crad)
            f = (ta * inv_a + 1.0) / (FOUR_PI * h2)
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
            sa = d0 * ax + d1 * ay + d2 * az
            sb = d0 * bx + d1 * by + d2 * bz
            ma = min(sa, 0.0)
            mb = max(sb, 0.0)
            rho2 = g2 + ma * ma + mb * mb
            fc = (sa * inv_a - sb * inv_b) / (FOUR_PI * g2)
            sx = fc * ex
            sy = fc * ey
            sz = fc * ez
            if g2 < _TINY2:
                sx = 0.0
                sy = 0.0
                sz = 0.0
            n0, n1, n2 = pt[N0 + l], pt[N1 + l], pt[N2 + l]
            s[q + I1 + l] = inv_b
            s[q + LW + l] = lx * n0 + ly * n1 + lz * n2
            s[q + CW + l] = sx * n0 + sy * n1 + sz * n2
            s[q + LCX + l] = sx - lx
            s[q + LCY + l] = sy - ly
            s[q + LCZ + l] = sz - lz
            outer = SHEET_BLEND_OUTER * max(s[q + SW + l], pt[RW + l])
            rp2 = max(a2 - ta * ta, 0.0)
            in_sheet = sheet_law & (s[q + SOK + l] != 0.0) & (rp2 < outer * outer)
            fast = (((xcore > 40.0) | (h2 < _TINY2)) & (1.26 * a2 > 40.0 * ro2)
                    & ((1.26 * rho2 > 40.0 * ro2) | (g2 < _TINY2)))
            s[q + LM + l] = 0.0 if (fast & ~in_sheet) else 1.0


@_jit
def _fix_llines(s, k0, k1, c, cutoff, overlap_core, sheet):
    """The flagged lanes of :func:`_other_llines` by the scalar laws (:func:`formation_env.wake.lanes.fix_llines`)."""
    for k in range(k0, k1):
        q = k * _STRIDE
        for l in range(LANES):
            if s[q + LM + l] == 0.0:
                continue
            pt = c.p
            px, py, pz = pt[PX + l], pt[PY + l], pt[PZ + l]
            n0, n1, n2 = pt[N0 + l], pt[N1 + l], pt[N2 + l]
            x1, x3, cd = c.x1[l], c.x3[l], c.chord_dir[l]
            tx, ty, tz = s[q + TX + l], s[q + TY + l], s[q + TZ + l]
            ax, ay, az = px - x3[k, 0], py - x3[k, 1], pz - x3[k, 2]
            na = math.sqrt(ax * ax + ay * ay + az * az)
            ia = 1.0 / na if na > 0.0 else 0.0
            if sheet_on(sheet):
                lx, ly, lz = leg_sheet_framed(tx, ty, tz, ax, ay, az, ia, cutoff, s[q + RC + l], overlap_core,
                                              c.frames[l, k], pt[RW + l])
            else:
                lx, ly, lz = leg_cored(tx, ty, tz, ax, ay, az, ia, cutoff, s[q + RC + l], overlap_core)
            sx, sy, sz = branch_cored(cd[k, 0], cd[k, 1], cd[k, 2], ax, ay, az, ia, px - x1[k, 0], py - x1[k, 1],
                                      pz - x1[k, 2], s[q + I1 + l], cutoff, overlap_core)
            s[q + LW + l] = lx * n0 + ly * n1 + lz * n2
            s[q + CW + l] = sx * n0 + sy * n1 + sz * n2
            s[q + LCX + l] = sx - lx
            s[q + LCY + l] = sy - ly
            s[q + LCZ + l] = sz - lz


@_jit
def _other_bounds(s, pt, k0, k1, ro2):
    """The bound branch X1[k] -> X1[k + 1] seen from the control point for k in k0..k1-1, every lane, into BX..BZ in
    its fast form, BM 1.0 where that is not the law's (:func:`formation_env.wake.lanes.other_bounds`)."""
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
            sa = d0 * ax + d1 * ay + d2 * az
            sb = d0 * bx + d1 * by + d2 * bz
            ma = min(sa, 0.0)
            mb = max(sb, 0.0)
            rho2 = h2 + ma * ma + mb * mb
            f = (sa * s[q + I1 + l] - sb * s[qn + I1 + l]) / (FOUR_PI * h2)
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
            s[q + BM + l] = 0.0 if ((1.26 * rho2 > 40.0 * ro2) | (h2 < _TINY2)) else 1.0


@_jit
def _fix_bounds(s, k0, k1, c, cutoff, overlap_core):
    """The flagged lanes of :func:`_other_bounds` (k0..k1-1, a surface's bound branches) by the scalar law."""
    for k in range(k0, k1):
        q = k * _STRIDE
        for l in range(LANES):
            if s[q + BM + l] == 0.0:
                continue
            pt = c.p
            px, py, pz = pt[PX + l], pt[PY + l], pt[PZ + l]
            x1, bd = c.x1[l], c.bound_dir[l]
            s[q + BX + l], s[q + BY + l], s[q + BZ + l] = branch_cored(
                bd[k, 0], bd[k, 1], bd[k, 2], px - x1[k, 0], py - x1[k, 1], pz - x1[k, 2], s[q + I1 + l],
                px - x1[k + 1, 0], py - x1[k + 1, 1], pz - x1[k + 1, 2], s[q + _STRIDE + I1 + l], cutoff,
                overlap_core)


@_jit
def _own_row(s, aic, aic_static, j, p0, k0, npan):
    """AIC row j at the receiving vehicle's own panels p0..p0+npan-1 (left knots k0..), every lane."""
    for i in range(npan):
        q = np.uint64(k0 + i) * _U_STRIDE
        a = aic_static[j, p0 + i]
        row = aic[j, p0 + i]
        for l in range(np.uint64(row.shape[0])):  # LANES as a run-time count: aic.lu_solve_lanes says why
            row[l] = a - s[q + LW + l] + s[q + _U_STRIDE + LW + l]


@_jit
def _other_row(s, pt, aic, vcross, j, p0, k0, npan):
    """AIC row j at another vehicle's panels p0..p0+npan-1 (left knots k0..) and the horseshoes' vectors into
    ``vcross[j, p]``, every lane (:func:`formation_env.wake.lanes.other_panel_row`'s expressions)."""
    for i in range(npan):
        q = np.uint64(k0 + i) * _U_STRIDE
        qn = q + _U_STRIDE
        row = aic[j, p0 + i]
        vc = vcross[j, p0 + i]
        for l in range(np.uint64(row.shape[0])):  # LANES as a run-time count: aic.lu_solve_lanes says why
            bx, by, bz = s[q + BX + l], s[q + BY + l], s[q + BZ + l]
            row[l] = ((s[q + CW + l] - s[q + LW + l]) + bx * pt[N0 + l] + by * pt[N1 + l] + bz * pt[N2 + l]
                      - (s[qn + CW + l] - s[qn + LW + l]))
            vc[0, l] = s[q + LCX + l] + bx - s[qn + LCX + l]
            vc[1, l] = s[q + LCY + l] + by - s[qn + LCY + l]
            vc[2, l] = s[q + LCZ + l] + bz - s[qn + LCZ + l]
