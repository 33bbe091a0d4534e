"""The ELL of a chunk of formations solved together, the formations as the vector lanes (formation_env.wake.across,
issue 64), equals each formation's own solve (formation_env.wake.kernels.evaluate_one) bit for bit: the
circulation, the induced velocity at the evaluation points, the effective winds and the kept AIC, over formations
from coincident to spans apart, with and without tailplanes, the sheet law, the overlap core and the viscous core
in the solve, the field read off the solve or evaluated at other points, batches that do not fill the last chunk;
and the elimination across lanes equals the scalar one per lane, pivoting and zero pivots included.
"""

from __future__ import annotations

from functools import lru_cache

import numba as nb
import numpy as np
import pytest

from formation_env.geometry import aerosonde
from formation_env.wake import WakeModel
from formation_env.wake.across import LANES, chunk_scratch, evaluate_batch_lanes_serial, evaluate_chunk, lanes_apply
from formation_env.wake.aic import lu_solve_inplace, lu_solve_lanes
from formation_env.wake.arrays import wake_arrays
from formation_env.wake.kernels import SHEET_ON, evaluate_batch_serial, evaluate_one

B = 2.9  # Aerosonde span, m


@lru_cache(maxsize=None)
def _model(n: int, tail: bool, sheet: bool, overlap: bool, viscous: bool, eval_points: str = "control"):
    return WakeModel([aerosonde(tailplane=tail)] * n, sheet=sheet, overlap_core=1.0 if overlap else 0.0,
                     viscous_aic=viscous, eval_points=eval_points)


def _bits(a):
    return np.ascontiguousarray(a).view(np.uint64)


def _batch(rng, batch, n):
    """B formations of n: the vee slots (2 spans back, 0.9 across per rank) displaced by 0 to 3 spans, some with
    two vehicles coincident or 1 um apart; attitudes within +-10 deg, alpha 0-8 deg, beta +-4 deg, 20-30 m/s."""
    slots = np.array([[-2.0 * ((i + 1) // 2), 0.9 * ((i + 1) // 2) * (1 if i % 2 else -1), 0.1 * ((i + 1) // 2)]
                      for i in range(n)]) * B
    scale = np.array((0.0, 0.02, 0.1, 0.5, 1.5, 3.0))[np.arange(batch) % 6]
    pos = slots + rng.normal(size=(batch, n, 3)) * scale[:, None, None] * B
    euler = np.radians(rng.uniform(-10, 10, (batch, n, 3)))
    alpha = np.radians(rng.uniform(0, 8, (batch, n)))
    euler[..., 1] += alpha
    for b in range(3, batch, 4):
        pos[b, 1] = pos[b, 0] + (0.0 if b % 8 == 3 else 1e-6)
        euler[b, 1] = euler[b, 0]
    return pos, euler, rng.uniform(20, 30, (batch, n)), alpha, np.radians(rng.uniform(-4, 4, (batch, n)))


def _solve(kernel, model, state):
    b, v, n = state[0].shape[0], model.n_vehicles, model.n_panels
    out = [np.empty((b, n)), np.empty((b, n, 3))] + [np.empty((b, v, 3)) for _ in range(4)]
    kernel(model._lattice, *state, *out, SHEET_ON if model.sheet else None)
    return out


CASES = [(n, tail, sheet, overlap, viscous)
         for n, tail in ((2, False), (2, True), (5, False))
         for sheet in (False, True) for overlap in (True, False) for viscous in (True, False)]


@pytest.mark.parametrize("n,tail,sheet,overlap,viscous", CASES)
def test_chunks_equal_each_formations_solve_bit_for_bit(n, tail, sheet, overlap, viscous):
    model = _model(n, tail, sheet, overlap, viscous)
    assert lanes_apply(wake_arrays(model, np.zeros(3)).lattice) == viscous  # the field off the solve, or not
    state = _batch(np.random.default_rng(100 * n + 10 * tail + 4 * sheet + 2 * overlap + viscous), 2 * LANES + 5, n)
    got = _solve(evaluate_batch_lanes_serial, model, state)
    want = _solve(evaluate_batch_serial, model, state)
    for g, e, name in zip(got, want, ("circulation", "vpts", "wind ned", "wind body", "omega body", "omega ned")):
        assert np.array_equal(_bits(g), _bits(e)), name


def test_the_field_at_other_evaluation_points_equals_each_formations_bit_for_bit():
    model = _model(2, False, True, True, True, eval_points="quarter_chord")
    assert not lanes_apply(wake_arrays(model, np.zeros(3)).lattice)
    state = _batch(np.random.default_rng(8), LANES + 3, 2)
    for g, e in zip(_solve(evaluate_batch_lanes_serial, model, state), _solve(evaluate_batch_serial, model, state)):
        assert np.array_equal(_bits(g), _bits(e))


@nb.njit
def _kept(w, pos, euler, speed, alpha, beta):
    """Each formation's AIC and right-hand side before elimination, chunked and one by one."""
    nb_, nv = pos.shape[0], pos.shape[1]
    n = w.n_panels
    lat = w.lattice
    chunked = np.empty((nb_, n, n + 1))
    single = np.empty((nb_, n, n + 1))
    c = chunk_scratch(nv, lat.knot_x1_b.shape[0], lat.surface_origin_b.shape[0], n, bool(w.sheet))
    g, vp, o = np.empty((nb_, n)), np.empty((nb_, n, 3)), np.empty((nb_, nv, 3))
    for b0 in range(0, nb_, LANES):
        evaluate_chunk(lat, w.sheet, pos, euler, speed, alpha, beta, b0, min(LANES, nb_ - b0), c, g, vp, o, o.copy(),
                       o.copy(), o.copy(), chunked)
    for b in range(nb_):
        evaluate_one(lat, pos[b], euler[b], speed[b], alpha[b], beta[b], np.empty(n), np.empty((n, 3)),
                     np.empty((nv, 3)), np.empty((nv, 3)), np.empty((nv, 3)), np.empty((nv, 3)), w.sheet, single[b])
    return chunked, single


def test_the_kept_aic_equals_each_formations_bit_for_bit():
    """The formation benefit's AIC (the isolated circulations come from its diagonal blocks)."""
    w = wake_arrays(_model(2, False, True, True, True), np.zeros(3))
    chunked, single = _kept(w, *_batch(np.random.default_rng(9), LANES + 7, 2))
    assert np.array_equal(_bits(chunked), _bits(single))


def test_the_elimination_across_lanes_equals_the_scalar_one_lane_by_lane():
    rng = np.random.default_rng(3)
    n = 12
    a = rng.normal(size=(n, n, LANES))
    a[:, :, 1] += 5.0 * np.eye(n)  # no row swaps
    a[0, 0, 2] = 0.0  # a zero first pivot: a swap
    a[:, 0, 3] = 0.0  # a zero column: the pivot replaced, multipliers 0 (rows left as they are)
    a[4, :, 4] = -0.0
    a[:, :, 5] = np.round(a[:, :, 5])  # ties in the pivot search: the first largest
    rhs = rng.normal(size=(n, LANES))
    rhs[2, 4] = -0.0
    got_a, got_r = a.copy(), rhs.copy()
    lu_solve_lanes(got_a, got_r, np.empty(LANES, np.int64))
    for lane in range(LANES):
        m, r = np.ascontiguousarray(a[:, :, lane]), np.ascontiguousarray(rhs[:, lane])
        lu_solve_inplace(m, r)
        assert np.array_equal(_bits(got_r[:, lane]), _bits(r)), lane
        assert np.array_equal(_bits(got_a[:, :, lane]), _bits(m)), lane


def test_a_threaded_batch_equals_each_formation_solved_alone_bit_for_bit():
    """WakeModel.evaluate spreads a batch of 16 or more over threads (formation_env.threads.run_parallel: the
    serial kernel on ranges of the batch); every formation's numbers are its own solve's."""
    import numba

    model = _model(2, True, True, True, True)
    state = _batch(np.random.default_rng(11), 40, 2)
    n = numba.get_num_threads()
    numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
    try:
        from formation_env.wake import FormationState

        got = model.evaluate(FormationState(*state))
    finally:
        numba.set_num_threads(n)
    want = _solve(evaluate_batch_serial, model, state)
    for g, e in zip((got.circulation, got.point_velocity_ned, got.wind_ned, got.wind_body, got.omega_body,
                     got.omega_ned), want):
        assert np.array_equal(_bits(g), _bits(e))
