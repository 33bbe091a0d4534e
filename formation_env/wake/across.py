"""The ELL of a chunk of formations with the formations as the vector lanes (issue 64): pose, joint solve, field at
the evaluation points and effective wind of up to :data:`LANES` formations of one lattice at once, every branch law
evaluated for all formations of the chunk in one vector instruction.

Why across formations: every formation of a batch has the same lattice (the same vehicles, knots and panels), so
the loops over control points and knots are the same for all of them, and only the numbers differ. With the
formations innermost each instruction serves LANES formations with no gather and no partly filled vector, where the
lanes *within* one formation (:mod:`.lanes`) fill 11 knots of a 2-UAV pair into 8-wide vectors and pay the
per-control-point bookkeeping once per formation.

Layout: one flat scratch array per chunk (:func:`chunk_scratch`), knot-major: the value of row ``r`` at knot ``k``
and lane ``l`` is at ``HEAD + (k * N_ROWS + r) * LANES + l``; the control point's own values (its position and
normal in NED, the receiving width) sit in the head at ``r * LANES + l``. Every distance between two rows is a
compile-time constant, so LLVM vectorises the lane loops without runtime alias checks (numba passes arrays without
no-alias information; see :mod:`.lanes`).

Exactness: each lane performs the operations of :func:`formation_env.wake.kernels.evaluate_one` in the same order
(no fastmath, nothing reassociated or contracted): the fast form of a law where the law's own tests select it, the
scalar law of :mod:`.biot_savart` for a flagged lane, the scalar elimination of
:func:`formation_env.wake.aic.lu_solve_inplace` per formation, the field summed over the other vehicles' horseshoes
in panel order, and :func:`formation_env.wake.kernels.effective_wind`. The results equal the per-formation kernel's
bit for bit (``tests/wake/test_across.py``). The path of lattices whose field is not read off the solve (evaluation
points other than the control points, or a field core other than the solve's) is the per-formation kernel's.

Frames and units: NED earth, metres, m/s, per unit circulation in the scratch.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np

from .biot_savart import (_MIN_CORE_M, _TINY_H, CORE_LAMB_OSEEN, CORE_NONE, FOUR_PI, KURYLOWICH_C, LAMB_OSEEN_C,
                          SHEET_BLEND_OUTER, STRIP_OK, STRIP_W, branch_cored, leg_cored, leg_sheet_framed,
                          sheet_on, strip_frames)
from .kernels import effective_wind
from .field import field_velocity
from .posing import bound_length, branch_directions, place_lattice, to_ned
from .structs import LatticeArrays, PosedLattice

__all__ = ["LANES", "MAX_PANELS", "N_ROWS", "chunk_pays", "ChunkScratch", "chunk_scratch", "solve_chunk_lanes",
           "field_chunk", "evaluate_chunk", "lanes_apply", "lu_solve_lanes", "evaluate_batch_lanes_serial",
           "evaluate_batch_lanes_parallel"]

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


class ChunkScratch(NamedTuple):
    """The working arrays of one chunk of up to LANES formations of a lattice of V vehicles, K knots, S surfaces and
    N panels (:func:`chunk_scratch`); reused from chunk to chunk."""

    s: np.ndarray  # (K N_ROWS LANES,) the knots' lane rows (module docstring)
    p: np.ndarray  # (N_HEAD LANES,) the control point's lane rows
    rot: np.ndarray  # (LANES, V, 3, 3) NED -> body DCMs
    vel: np.ndarray  # (LANES, V, 3) air-relative velocities, m/s NED
    trail: np.ndarray  # (LANES, V, 3) unit trailing-leg directions
    x1: np.ndarray  # (LANES, K, 3) quarter-chord knots, m NED
    x3: np.ndarray  # (LANES, K, 3) three-quarter-chord knots, m NED
    origin: np.ndarray  # (LANES, S, 3) surface origins, m NED
    bound_dir: np.ndarray  # (LANES, K, 3)
    chord_dir: np.ndarray  # (LANES, K, 3)
    frames: np.ndarray  # (LANES, K, STRIP_COLUMNS) the sheet law's strips; (LANES, 0, STRIP_COLUMNS) without it
    aic: np.ndarray  # (N, N, LANES)
    rhs: np.ndarray  # (N, LANES) the right-hand side, then the circulation
    vcross: np.ndarray  # (N, N, 3, LANES) the other vehicles' horseshoe vectors at the control points
    piv: np.ndarray  # (LANES,) int64 the elimination's pivot rows


@_jit
def chunk_scratch(n_vehicles, n_knots, n_surfaces, n_panels, sheet_law, lanes=LANES):
    """A :class:`ChunkScratch` for a lattice of that size (``sheet_law``: room for the sheet law's strips);
    ``lanes``: LANES, or 0 for an empty one of the same type (a caller that solves no chunk)."""
    n_strips = n_knots if sheet_law else 0
    return ChunkScratch(
        s=np.zeros(n_knots * N_ROWS * lanes), p=np.zeros(_N_HEAD * lanes), rot=np.empty((lanes, n_vehicles, 3, 3)),
        vel=np.empty((lanes, n_vehicles, 3)), trail=np.empty((lanes, n_vehicles, 3)),
        x1=np.empty((lanes, n_knots, 3)), x3=np.empty((lanes, n_knots, 3)), origin=np.empty((lanes, n_surfaces, 3)),
        bound_dir=np.empty((lanes, n_knots, 3)), chord_dir=np.empty((lanes, n_knots, 3)),
        frames=np.empty((lanes, n_strips, 11)), aic=np.empty((n_panels, n_panels, lanes)),
        rhs=np.empty((n_panels, lanes)), vcross=np.zeros((n_panels, n_panels, 3, lanes)),
        piv=np.empty(lanes, np.int64))


#: the most panels a chunk solves across lanes: its AIC and the other vehicles' horseshoe vectors at the control
#: points hold N^2 * 4 * LANES float64 (0.2 MB for two Aerosondes, 20 panels; 0.46 MB for three; 1.3 MB for five),
#: and past a core's L2 cache the per-formation solve, whose arrays are LANES times smaller, is the faster
MAX_PANELS = 30


@_jit
def chunk_pays(lat):
    """Whether the decision solves a chunk of formations of this lattice across lanes: :func:`lanes_apply`, and at
    most :data:`MAX_PANELS` panels."""
    return lat.panel_vehicle.shape[0] <= MAX_PANELS and lanes_apply(lat)


@_jit
def lanes_apply(lat):
    """Whether a lattice takes the chunked kernel: its field is read off the solve (evaluation at the control
    points, the field's viscous core that of the solve), as :func:`formation_env.wake.kernels.evaluate_one`
    decides it."""
    if lat.aic_core_mode != lat.core_mode:
        return False
    a, b = lat.eval_b, lat.control_b
    if a.shape[0] != b.shape[0]:
        return False
    for j in range(a.shape[0]):
        for i in range(3):
            if a[j, i] != b[j, i]:
                return False
    return True


@_jit
def _pose_chunk(lat, pos, euler, airspeed, alpha, beta, b0, nl, c, sheet):
    """Pose formations b0..b0+nl-1 (:func:`formation_env.wake.posing.posed_lattice`'s values) into the chunk's
    per-lane arrays and the knots' lane rows; lanes nl.. repeat the last formation (computed, never read)."""
    s = c.s
    kv = lat.knot_vehicle
    for l in range(LANES):
        b = b0 + min(l, nl - 1)
        place_lattice(pos[b], euler[b], airspeed[b], alpha[b], beta[b], lat.knot_x1_b, lat.knot_x3_b, kv,
                      lat.surface_origin_b, lat.surface_vehicle, c.rot[l], c.vel[l], c.trail[l], c.x1[l], c.x3[l],
                      c.origin[l])
        branch_directions(c.x1[l], c.x3[l], lat.knot_surface, lat.surface_knot_start, c.bound_dir[l], c.chord_dir[l])
        if sheet_on(sheet):
            strip_frames(c.trail[l], c.x3[l], kv, lat.knot_surface, c.frames[l])
        for k in range(kv.shape[0]):
            v = kv[k]
            q = k * _STRIDE + l
            s[q + X1X], s[q + X1Y], s[q + X1Z] = c.x1[l, k, 0], c.x1[l, k, 1], c.x1[l, k, 2]
            s[q + X3X], s[q + X3Y], s[q + X3Z] = c.x3[l, k, 0], c.x3[l, k, 1], c.x3[l, k, 2]
            s[q + CDX], s[q + CDY], s[q + CDZ] = c.chord_dir[l, k, 0], c.chord_dir[l, k, 1], c.chord_dir[l, k, 2]
            s[q + BDX], s[q + BDY], s[q + BDZ] = c.bound_dir[l, k, 0], c.bound_dir[l, k, 1], c.bound_dir[l, k, 2]
            s[q + TX], s[q + TY], s[q + TZ] = c.trail[l, v, 0], c.trail[l, v, 1], c.trail[l, v, 2]
            if sheet_on(sheet):
                s[q + SW] = c.frames[l, k, STRIP_W]
                s[q + SOK] = c.frames[l, k, STRIP_OK]
            else:
                s[q + SW] = 0.0
                s[q + SOK] = 0.0


@_jit
def _control_point(lat, pos, b0, nl, j, c, sheet):
    """The control point's rows of control point j: its position and normal in NED per lane (the per-formation
    kernel's expressions) and, with the sheet law, its panel's bound length (the receiving width)."""
    pt = c.p
    vj = lat.panel_vehicle[j]
    cb, nb_ = lat.control_b[j], lat.normal_b[j]
    k = lat.panel_left_knot[j]
    for l in range(LANES):
        b = b0 + min(l, nl - 1)
        r = c.rot[l, vj]
        p = pos[b, vj]
        pt[PX + l] = p[0] + r[0, 0] * cb[0] + r[1, 0] * cb[1] + r[2, 0] * cb[2]
        pt[PY + l] = p[1] + r[0, 1] * cb[0] + r[1, 1] * cb[1] + r[2, 1] * cb[2]
        pt[PZ + l] = p[2] + r[0, 2] * cb[0] + r[1, 2] * cb[1] + r[2, 2] * cb[2]
        pt[N0 + l] = r[0, 0] * nb_[0] + r[1, 0] * nb_[1] + r[2, 0] * nb_[2]
        pt[N1 + l] = r[0, 1] * nb_[0] + r[1, 1] * nb_[1] + r[2, 1] * nb_[2]
        pt[N2 + l] = r[0, 2] * nb_[0] + r[1, 2] * nb_[1] + r[2, 2] * nb_[2]
        w = 0.0
        if sheet_on(sheet):
            x1 = c.x1[l]
            w = np.sqrt((x1[k + 1, 0] - x1[k, 0]) ** 2 + (x1[k + 1, 1] - x1[k, 1]) ** 2 + (x1[k + 1, 2] - x1[k, 2]) ** 2)
        pt[RW + l] = w


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
        for l in range(np.uint64(row.shape[0])):  # LANES, as a run-time count: note in lu_solve_lanes
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
        for l in range(np.uint64(row.shape[0])):  # LANES, as a run-time count: note in lu_solve_lanes
            bx, by, bz = s[q + BX + l], s[q + BY + l], s[q + BZ + l]
            row[l] = ((s[q + CW + l] - s[q + LW + l]) + bx * pt[N0 + l] + by * pt[N1 + l] + bz * pt[N2 + l]
                      - (s[qn + CW + l] - s[qn + LW + l]))
            vc[0, l] = s[q + LCX + l] + bx - s[qn + LCX + l]
            vc[1, l] = s[q + LCY + l] + by - s[qn + LCY + l]
            vc[2, l] = s[q + LCZ + l] + bz - s[qn + LCZ + l]


@_jit
def lu_solve_lanes(a, rhs, piv):
    """:func:`formation_env.wake.aic.lu_solve_inplace` of LANES systems at once: ``a`` (N, N, LANES) and ``rhs``
    (N, LANES) overwritten, the solutions in ``rhs``; ``piv`` (LANES,) int64 scratch. Each lane chooses its own
    pivots (partial pivoting, the first largest magnitude), swaps its own rows and performs the scalar
    elimination's operations in the same order (a row whose multiplier is 0 left as it is, a zero pivot
    replaced by 1e-300), so every lane's solution is the scalar solve's bit for bit.

    The lane loops run to a run-time count (``a.shape[2]``, LANES) rather than the constant: LLVM unrolls a loop of
    a constant 16 and then cannot prove that a row it writes does not overlap another it reads (they lie a
    run-time distance apart in one array), so it keeps the unrolled loop scalar; a loop of a run-time count goes to
    the loop vectoriser, which checks the overlap once per loop and runs the vector body (the same operations per
    element: the results are the same bits)."""
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


@_jit
def _field_from_solve(pv, g, vcross, b0, nl, vpts_out):
    """The other vehicles' induced velocity at the control points (the evaluation points) from the solve's
    horseshoe vectors and circulations ``g`` (N, LANES), summed in panel order as
    :func:`formation_env.wake.kernels.evaluate_one` sums them."""
    n_panels = pv.shape[0]
    lanes = g.shape[1]  # LANES, as a run-time count: note in lu_solve_lanes
    wx = np.empty(lanes)
    wy = np.empty(lanes)
    wz = np.empty(lanes)
    for j in range(n_panels):
        v = pv[j]
        for l in range(lanes):
            wx[l] = 0.0
            wy[l] = 0.0
            wz[l] = 0.0
        for p in range(n_panels):
            if pv[p] != v:
                gp = g[p]
                vc = vcross[j, p]
                for l in range(lanes):
                    wx[l] += gp[l] * vc[0, l]
                    wy[l] += gp[l] * vc[1, l]
                    wz[l] += gp[l] * vc[2, l]
        for l in range(nl):
            vpts_out[b0 + l, j, 0] = wx[l]
            vpts_out[b0 + l, j, 1] = wy[l]
            vpts_out[b0 + l, j, 2] = wz[l]


@_jit
def solve_chunk_lanes(lat, sheet, pos, euler, airspeed, alpha, beta, b0, nl, c, gamma_out, keep):
    """The joint solve of formations b0..b0+nl-1 (nl <= LANES) of the batch: their poses into the chunk scratch
    ``c`` (a :func:`chunk_scratch`), each lane's AIC and right-hand side assembled, kept in ``keep`` (B, N, N + 1)
    when it has rows, eliminated, the circulation into ``gamma_out`` (B, N); the lanes' other vehicles' horseshoe
    vectors at the control points stay in ``c.vcross``. Arguments as :func:`evaluate_chunk`'s."""
    s, pt = c.s, c.p
    kv, ksk, pv = lat.knot_vehicle, lat.surface_knot_start, lat.panel_vehicle
    n_panels = pv.shape[0]
    n_knots = kv.shape[0]
    nv = pos.shape[1]
    cutoff, overlap_core = lat.cutoff_m, lat.overlap_core_m
    ro2 = overlap_core * overlap_core if overlap_core > 0.0 else np.inf
    sheet_law = sheet_on(sheet)
    _pose_chunk(lat, pos, euler, airspeed, alpha, beta, b0, nl, c, sheet)
    # each vehicle's knots (contiguous, the lattice's order)
    vk0 = np.full(nv, n_knots)
    vk1 = np.zeros(nv, np.int64)
    for k in range(n_knots):
        vk0[kv[k]] = min(vk0[kv[k]], k)
        vk1[kv[k]] = max(vk1[kv[k]], k + 1)
    aic, rhs, vcross = c.aic, c.rhs, c.vcross
    for j in range(n_panels):
        vj = pv[j]
        _control_point(lat, pos, b0, nl, j, c, sheet)
        a, b = vk0[vj], vk1[vj]
        _own_legs(s, pt, a, b, cutoff)
        for srf in range(ksk.shape[0] - 1):
            src = kv[ksk[srf]]
            if src != vj:
                _core_radius(s, ksk[srf], ksk[srf + 1], c, srf, src, lat, airspeed, b0, nl)
        _other_llines(s, pt, 0, a, cutoff, ro2, sheet_law)
        _other_llines(s, pt, b, n_knots, cutoff, ro2, sheet_law)
        _fix_llines(s, 0, a, c, cutoff, overlap_core, sheet)
        _fix_llines(s, b, n_knots, c, cutoff, overlap_core, sheet)
        if a > 1:
            _other_bounds(s, pt, 0, a - 1, ro2)
        if n_knots - b > 1:
            _other_bounds(s, pt, b, n_knots - 1, ro2)
        for srf in range(ksk.shape[0] - 1):
            k0 = ksk[srf]
            npan = ksk[srf + 1] - k0 - 1
            p0 = k0 - srf
            if kv[k0] == vj:
                _own_row(s, aic, lat.aic_static, j, p0, k0, npan)
                continue
            _fix_bounds(s, k0, k0 + npan, c, cutoff, overlap_core)
            _other_row(s, pt, aic, vcross, j, p0, k0, npan)
        for l in range(LANES):
            v = c.vel[l, vj]
            rhs[j, l] = v[0] * pt[N0 + l] + v[1] * pt[N1 + l] + v[2] * pt[N2 + l]
    if keep.shape[0] > 0:
        for l in range(nl):
            for j in range(n_panels):
                for p in range(n_panels):
                    keep[b0 + l, j, p] = aic[j, p, l]
                keep[b0 + l, j, n_panels] = rhs[j, l]
    lu_solve_lanes(aic, rhs, c.piv)
    for l in range(nl):
        for j in range(n_panels):
            gamma_out[b0 + l, j] = rhs[j, l]


@_jit
def field_chunk(lat, pos, b0, nl, c, vpts_out, wind_ned_out, wind_b_out, omega_b_out, omega_ned_out):
    """After :func:`solve_chunk_lanes`, for a lattice whose field is read off the solve (:func:`lanes_apply`): the
    other vehicles' induced velocity at the control points (B, N, 3) NED and each formation's effective wind
    (:func:`formation_env.wake.kernels.effective_wind`). Arguments as :func:`evaluate_chunk`'s."""
    _field_from_solve(lat.panel_vehicle, c.rhs, c.vcross, b0, nl, vpts_out)
    for l in range(nl):
        b = b0 + l
        effective_wind(c.rot[l], vpts_out[b], lat.grad_w, lat.vehicle_panel_start, wind_ned_out[b], wind_b_out[b],
                       omega_b_out[b], omega_ned_out[b])


@_jit
def evaluate_chunk(lat, sheet, pos, euler, airspeed, alpha, beta, b0, nl, c, gamma_out, vpts_out, wind_ned_out,
                   wind_b_out, omega_b_out, omega_ned_out, keep):
    """:func:`formation_env.wake.kernels.evaluate_one` of formations b0..b0+nl-1 (nl <= LANES) of the batch: poses
    and air data (B, V, ...) as ``evaluate_one``'s with the batch axis first, outputs likewise (circulation (B, N),
    the other vehicles' induced velocity at the evaluation points (B, N, 3) NED, the winds (B, V, 3)); ``lat`` a
    :class:`~formation_env.wake.structs.LatticeArrays` (the field read off the solve where :func:`lanes_apply`
    holds, else evaluated at the evaluation points formation by formation), ``sheet`` the kernels' switch (None or
    :data:`~formation_env.wake.biot_savart.SHEET_ON`), ``c`` a :func:`chunk_scratch` of its size; ``keep``
    (B, N, N + 1), or (0, N, N + 1) for none: each formation's AIC and right-hand side before the elimination (as
    :func:`formation_env.wake.aic.assemble_and_solve`'s). Bit for bit the per-formation kernel's results."""
    solve_chunk_lanes(lat, sheet, pos, euler, airspeed, alpha, beta, b0, nl, c, gamma_out, keep)
    if lanes_apply(lat):
        field_chunk(lat, pos, b0, nl, c, vpts_out, wind_ned_out, wind_b_out, omega_b_out, omega_ned_out)
        return
    # the field's own branches at the evaluation points (evaluate_one's other path), formation by formation
    n_panels = lat.panel_vehicle.shape[0]
    pv = lat.panel_vehicle
    overlap_core = lat.overlap_core_m
    n_knots_ = lat.knot_x1_b.shape[0]
    r1, inv1, r3, inv3 = np.empty((n_knots_, 3)), np.empty(n_knots_), np.empty((n_knots_, 3)), np.empty(n_knots_)
    pt3 = np.empty(3)
    for l in range(nl):
        b = b0 + l
        posed = PosedLattice(pos[b], airspeed[b], c.rot[l], c.vel[l], c.trail[l], c.x1[l], c.x3[l], c.origin[l],
                             c.bound_dir[l], c.chord_dir[l], r1, inv1, r3, inv3)
        for j in range(n_panels):
            v = pv[j]
            to_ned(c.rot[l, v], pos[b, v], lat.eval_b[j], pt3)
            recv_w = 0.0
            if sheet_on(sheet):
                recv_w = bound_length(c.x1[l], lat.panel_left_knot[j])
            wx_, wy_, wz_ = field_velocity(pt3[0], pt3[1], pt3[2], v, False, lat, posed, gamma_out[b], lat.core_mode,
                                           overlap_core, sheet, recv_w, c.frames[l])
            vpts_out[b, j, 0] = wx_
            vpts_out[b, j, 1] = wy_
            vpts_out[b, j, 2] = wz_
    for l in range(nl):
        b = b0 + l
        effective_wind(c.rot[l], vpts_out[b], lat.grad_w, lat.vehicle_panel_start, wind_ned_out[b], wind_b_out[b],
                       omega_b_out[b], omega_ned_out[b])


# blocks of chunks the batch kernels share among their threads (each block allocates its scratch once)
_BLOCKS = 32


def _make_batch(parallel: bool):
    @nb.njit(cache=True, parallel=parallel, error_model="numpy")
    def evaluate_batch_lanes(lattice, pos, euler, airspeed, alpha, beta, gamma_out, vpts_out, wind_ned_out,
                             wind_b_out, omega_b_out, omega_ned_out, sheet=None):
        """:func:`evaluate_chunk` over a batch of B formations, LANES at a time (arguments as
        :func:`formation_env.wake.kernels.evaluate_batch_serial`'s); the chunks are shared among the threads in
        blocks, each block with one scratch."""
        lat = LatticeArrays(*lattice)
        n = pos.shape[0]
        n_chunks = (n + LANES - 1) // LANES
        n_blocks = min(n_chunks, _BLOCKS)
        for blk in nb.prange(n_blocks):
            c = chunk_scratch(pos.shape[1], lat.knot_x1_b.shape[0], lat.surface_origin_b.shape[0],
                              lat.panel_vehicle.shape[0], sheet_on(sheet))
            no_keep = np.empty((0, lat.panel_vehicle.shape[0], lat.panel_vehicle.shape[0] + 1))
            for ci in range(blk * n_chunks // n_blocks, (blk + 1) * n_chunks // n_blocks):
                b0 = ci * LANES
                evaluate_chunk(lat, sheet, pos, euler, airspeed, alpha, beta, b0, min(LANES, n - b0), c, gamma_out,
                               vpts_out, wind_ned_out, wind_b_out, omega_b_out, omega_ned_out, no_keep)

    return evaluate_batch_lanes


evaluate_batch_lanes_serial = _make_batch(False)
evaluate_batch_lanes_parallel = _make_batch(True)
