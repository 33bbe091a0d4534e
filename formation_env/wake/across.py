"""The ELL of a chunk of formations with the formations as the vector lanes (issue 64): pose, joint solve, field at
the evaluation points and effective wind of up to :data:`LANES` formations of one lattice at once, every branch law
evaluated for all formations of the chunk in one vector instruction.

Why across formations: every formation of a batch has the same lattice (the same vehicles, knots and panels), so
the loops over control points and knots are the same for all of them, and only the numbers differ. With the
formations innermost each instruction serves LANES formations with no gather and no partly filled vector, where the
lanes *within* one formation (:mod:`.lanes`) fill 11 knots of a 2-UAV pair into 8-wide vectors and pay the
per-control-point bookkeeping once per formation.

Layout: the lane rows of :mod:`.across_rows` (the knots' values per lane in one flat scratch array).

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

from typing import NamedTuple

import numba as nb
import numpy as np

from .across_rows import (LANES, N_ROWS, _N_HEAD, _STRIDE, X1X, X1Y, X1Z, X3X, X3Y, X3Z, CDX, CDY, CDZ, BDX, BDY, BDZ,
                          TX, TY, TZ, SW, SOK, PX, PY, PZ, N0, N1, N2, RW, _own_legs, _core_radius, _other_llines,
                          _fix_llines, _other_bounds, _fix_bounds, _own_row, _other_row)
from .aic import lu_solve_lanes
from .biot_savart import STRIP_OK, STRIP_W, sheet_on, strip_frames
from .kernels import _same_points, effective_wind
from .field import field_velocity
from .posing import bound_length, branch_directions, place_lattice, to_ned
from .structs import LatticeArrays, PosedLattice

__all__ = ["LANES", "MAX_PANELS", "N_ROWS", "chunk_pays", "ChunkScratch", "chunk_scratch", "other_vehicles_rows",
           "solve_chunk_lanes",
           "field_chunk", "evaluate_chunk", "lanes_apply", "evaluate_batch_lanes_serial",
           "evaluate_batch_lanes_parallel"]

_jit = nb.njit(cache=True, fastmath=False, error_model="numpy")
_jit_inline = nb.njit(cache=True, fastmath=False, error_model="numpy", inline="always")

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
    return lat.aic_core_mode == lat.core_mode and _same_points(lat.eval_b, lat.control_b)


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
def _field_from_solve(pv, g, vcross, b0, nl, vpts_out):
    """The other vehicles' induced velocity at the control points (the evaluation points) from the solve's
    horseshoe vectors and circulations ``g`` (N, LANES), summed in panel order as
    :func:`formation_env.wake.kernels.evaluate_one` sums them."""
    n_panels = pv.shape[0]
    lanes = g.shape[1]  # LANES as a run-time count: aic.lu_solve_lanes says why
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
                # indexed in place, no row views: a view in this loop takes and releases a reference count per pair
                for l in range(lanes):
                    wx[l] += g[p, l] * vcross[j, p, 0, l]
                    wy[l] += g[p, l] * vcross[j, p, 1, l]
                    wz[l] += g[p, l] * vcross[j, p, 2, l]
        for l in range(nl):
            vpts_out[b0 + l, j, 0] = wx[l]
            vpts_out[b0 + l, j, 1] = wy[l]
            vpts_out[b0 + l, j, 2] = wz[l]


@_jit_inline
def other_vehicles_rows(lat, sheet, airspeed, b0, nl, c, vj, a, b):
    """The knots of every vehicle but vj (its knots a..b-1) seen from the point in the head rows of the chunk
    scratch ``c``, every lane: their core radius and L-line rows by the field law (fast form, the flagged lanes by
    the scalar laws) and their bound branch rows in the fast form (a surface's flagged bound lanes are the caller's:
    :func:`~formation_env.wake.across_rows._fix_bounds`, right before the rows read them); ``airspeed`` (B, V) the
    formations' (lane l: formation b0 + min(l, nl - 1)). Inlined at numba IR level: a call of its own in the solve's
    loop over the control points measured 8 % slower."""
    s, pt = c.s, c.p
    kv, ksk = lat.knot_vehicle, lat.surface_knot_start
    n_knots = kv.shape[0]
    cutoff, overlap_core = lat.cutoff_m, lat.overlap_core_m
    ro2 = overlap_core * overlap_core if overlap_core > 0.0 else np.inf
    sheet_law = sheet_on(sheet)
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
    cutoff = lat.cutoff_m
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
        other_vehicles_rows(lat, sheet, airspeed, b0, nl, c, vj, a, b)
        for srf in range(ksk.shape[0] - 1):
            k0 = ksk[srf]
            npan = ksk[srf + 1] - k0 - 1
            p0 = k0 - srf
            if kv[k0] == vj:
                _own_row(s, aic, lat.aic_static, j, p0, k0, npan)
            else:
                _fix_bounds(s, k0, k0 + npan, c, lat.cutoff_m, lat.overlap_core_m)
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
