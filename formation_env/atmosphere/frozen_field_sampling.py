"""Reading the frozen turbulence field (see :mod:`.frozen_field`), compiled: each aircraft reads the
lanes delayed by its transport delay (linear interpolation in the ring buffer), mixes them with the
Cholesky factor of the correlation matrix of the aircraft's cross-track and vertical separations,
and rotates the gust to NED; plus the sample-then-advance rollout.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..frames import ned_to_track_xy, track_to_ned_xy
from .frozen_field_filters import advance_kernel

__all__ = ["sample_kernel", "sample_field_one", "rollout_kernel"]

_jit = nb.njit(cache=True, error_model="numpy")

_PIVOT_TOL = 1e-12  # a Cholesky pivot below this (relative to the diagonal) is clamped to zero
_SNAP_TOL = 1e-9  # a delay within this many steps of an integer is read exactly at that integer


@_jit
def _cholesky_rows(c, lo):
    """Lower Cholesky factor of the correlation matrix c (V, V) into lo, pivots <= _PIVOT_TOL
    clamped to zero (their column is dropped), each row renormalised to unit norm."""
    nveh = c.shape[0]
    for i in range(nveh):
        for j in range(nveh):
            lo[i, j] = 0.0
    for j in range(nveh):
        d = c[j, j]
        for m in range(j):
            d -= lo[j, m] * lo[j, m]
        if d > _PIVOT_TOL * c[j, j]:
            piv = math.sqrt(d)
            lo[j, j] = piv
            for i in range(j + 1, nveh):
                s = c[i, j]
                for m in range(j):
                    s -= lo[i, m] * lo[j, m]
                lo[i, j] = s / piv
        # else: column j stays zero (aircraft j's cross position duplicates earlier ones)
    for i in range(nveh):
        s = 0.0
        for m in range(i + 1):
            s += lo[i, m] * lo[i, m]
        if s > 0.0 and s != 1.0:
            s = math.sqrt(s)
            for m in range(i + 1):
                lo[i, m] /= s


@_jit
def sample_field_one(params, state, b, positions, chi, out, along, cross, down, slot0, slot1, frac,
                     corr, lo, gust):
    """Gusts of formation b at the current time into ``out[b]`` (V, 3) m/s NED: each aircraft reads
    the lanes delayed by its transport delay, mixed by the Cholesky factor of the correlation of the
    aircraft's cross-track and vertical separations, rotated from the track frame (u along, v
    starboard, w down) to NED. positions (B, V, 3) m NED (row b read), chi the track angle rad
    (0 north, positive east); along, cross, down, frac (V,) float64, slot0, slot1 (V,) int64,
    corr, lo (V, V), gust (V, 3): scratch. No checks. For compiled callers that fuse the field into
    their own per-formation loops (:func:`sample_kernel` is the batch form)."""
    nveh = state.x_u.shape[1]
    nslot = state.ring.shape[1]
    head = state.head[b]
    cs = math.cos(chi)
    sn = math.sin(chi)
    front = -np.inf
    for i in range(nveh):
        pn = positions[b, i, 0]
        pe = positions[b, i, 1]
        along[i], cross[i] = ned_to_track_xy(cs, sn, pn, pe)
        down[i] = positions[b, i, 2]
        if along[i] > front:
            front = along[i]
    max_d = float(nslot - 1)
    for i in range(nveh):
        d = (front - along[i]) / params.step_length_m
        if not (d > 0.0):  # also NaN
            d = 0.0
        rd = math.floor(d + 0.5)
        if abs(d - rd) < _SNAP_TOL:
            d = rd
        if d >= max_d:
            d = max_d
        d0 = int(math.floor(d))
        fr = d - d0
        if d0 >= nslot - 1:
            d0 = nslot - 1
            fr = 0.0
        s0 = (head - d0) % nslot
        slot0[i] = s0
        slot1[i] = (s0 - 1) % nslot
        frac[i] = fr
    for k in range(3):
        length = params.length_scale_m[k]
        for i in range(nveh):
            corr[i, i] = 1.0
            for j in range(i):
                dy = cross[i] - cross[j]
                dz = down[i] - down[j]
                r2 = dy * dy + dz * dz
                r = math.sqrt(r2)
                f = math.exp(-r / length)
                g = (1.0 - r / (2.0 * length)) * f
                if k == 0 or r2 == 0.0:
                    cij = g
                elif k == 1:
                    cij = (f - g) * dy * dy / r2 + g
                else:
                    cij = (f - g) * dz * dz / r2 + g
                corr[i, j] = cij
                corr[j, i] = cij
        _cholesky_rows(corr, lo)
        sig = params.sigma_mps[k]
        for i in range(nveh):
            s0 = slot0[i]
            s1 = slot1[i]
            fr = frac[i]
            acc = 0.0
            for j in range(i + 1):
                lane = (1.0 - fr) * state.ring[b, s0, k, j] + fr * state.ring[b, s1, k, j]
                acc += lo[i, j] * lane
            gust[i, k] = sig * acc
    for i in range(nveh):
        u = gust[i, 0]
        v = gust[i, 1]
        out[b, i, 0], out[b, i, 1] = track_to_ned_xy(cs, sn, u, v)
        out[b, i, 2] = gust[i, 2]


@_jit
def sample_kernel(params, state, positions_ned, track_angle_rad, out_gust_ned):
    """Gusts (B, V, 3) m/s NED at the current time into ``out_gust_ned``; positions (B, V, 3) m NED,
    track angles (B,) rad. No checks (see :func:`frozen_field_sample`)."""
    nveh = state.x_u.shape[1]
    along = np.empty(nveh)
    cross = np.empty(nveh)
    down = np.empty(nveh)
    slot0 = np.empty(nveh, dtype=np.int64)
    slot1 = np.empty(nveh, dtype=np.int64)
    frac = np.empty(nveh)
    corr = np.empty((nveh, nveh))
    lo = np.empty((nveh, nveh))
    gust = np.empty((nveh, 3))
    for b in range(state.x_u.shape[0]):
        sample_field_one(params, state, b, positions_ned, track_angle_rad[b], out_gust_ned, along, cross,
                    down, slot0, slot1, frac, corr, lo, gust)


@_jit
def rollout_kernel(params, state, positions_ned, track_angle_rad, out_gust_ned):
    """``n_steps = out_gust_ned.shape[0]`` times: sample into out_gust_ned[t] (B, V, 3), then
    advance; positions and track angles held fixed."""
    for t in range(out_gust_ned.shape[0]):
        sample_kernel(params, state, positions_ned, track_angle_rad, out_gust_ned[t])
        advance_kernel(params, state)
