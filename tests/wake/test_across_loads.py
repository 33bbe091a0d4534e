"""The induced drags of a chunk of formations across the vector lanes (formation_env.wake.across_loads, issue 64)
equal each formation's own Kutta-Joukowski pass (formation_env.wake.benefit.induced_drags_one with the kept solve)
bit for bit, in formation and alone: over formations from coincident to spans apart, with and without tailplanes,
the sheet law and the overlap core, two and three vehicles; a circulation other than the solve's (a coupled one) is
taken as given."""

from __future__ import annotations

from functools import lru_cache

import numba as nb
import numpy as np
import pytest

from formation_env.geometry import aerosonde
from formation_env.wake import WakeModel
from formation_env.wake.across import LANES, chunk_scratch, lanes_apply, solve_chunk_lanes
from formation_env.wake.across_loads import induced_drags_chunk
from formation_env.wake.arrays import wake_arrays
from formation_env.wake.benefit import induced_drags_one
from formation_env.wake.loads import isolated_model

B = 2.9  # Aerosonde span, m


@lru_cache(maxsize=None)
def _wakes(n: int, tail: bool, sheet: bool, overlap: bool):
    model = WakeModel([aerosonde(tailplane=tail)] * n, sheet=sheet, overlap_core=1.0 if overlap else 0.0,
                      viscous_aic=True)
    alone = isolated_model(model.vehicles[0], model.core, model.eval_points, model.rotational,
                           model.kinematic_viscosity, model.viscous_aic)
    return wake_arrays(model, np.zeros(3)), wake_arrays(alone, np.zeros(3))


def _bits(a):
    return np.ascontiguousarray(a).view(np.uint64)


def _chunk(rng, n):
    """LANES formations of n: echelon slots (1.5 spans back, 0.9 across per rank) displaced by 0 to 3 spans, two
    with their first two vehicles coincident or 1 um apart; attitudes within +-10 deg, alpha 0-8 deg, beta +-4 deg,
    20-30 m/s."""
    slots = np.array([[-1.5 * i, 0.9 * i, 0.05 * i] for i in range(n)]) * B
    scale = np.array((0.0, 0.02, 0.1, 0.5, 1.5, 3.0))[np.arange(LANES) % 6]
    pos = slots + rng.normal(size=(LANES, n, 3)) * scale[:, None, None] * B
    euler = np.radians(rng.uniform(-10, 10, (LANES, n, 3)))
    alpha = np.radians(rng.uniform(0, 8, (LANES, n)))
    euler[..., 1] += alpha
    for b, gap in ((3, 0.0), (11, 1e-6)):
        pos[b, 1] = pos[b, 0] + gap
        euler[b, 1] = euler[b, 0]
    return pos, euler, rng.uniform(20, 30, (LANES, n)), alpha, np.radians(rng.uniform(-4, 4, (LANES, n)))


@nb.njit
def _drags(w, alone, pos, euler, speed, alpha, beta, perturb):
    """The chunk's drags and each formation's own (the circulation of the solve times ``perturb``)."""
    lat = w.lattice
    nl, nv = pos.shape[0], pos.shape[1]
    n = lat.panel_vehicle.shape[0]
    c = chunk_scratch(nv, lat.knot_x1_b.shape[0], lat.surface_origin_b.shape[0], n, bool(w.sheet))
    gamma, keep = np.empty((nl, n)), np.empty((nl, n, n + 1))
    solve_chunk_lanes(lat, w.sheet, pos, euler, speed, alpha, beta, 0, nl, c, gamma, keep)
    gamma *= perturb
    got_f, got_a = np.empty((nl, nv)), np.empty((nl, nv))
    n_alone = alone.lattice.panel_vehicle.shape[0]
    induced_drags_chunk(w, n_alone, c, speed, alpha, beta, gamma, keep, 1.225, got_f, got_a)
    want_f, want_a = np.empty((nl, nv)), np.empty((nl, nv))
    for b in range(nl):
        induced_drags_one(w, alone, pos[b], euler[b], speed[b], alpha[b], beta[b], gamma[b], want_f[b], want_a[b],
                          1.225, keep[b])
    return got_f, got_a, want_f, want_a


CASES = [(n, tail, sheet, overlap) for n, tail in ((2, False), (2, True), (3, False))
         for sheet in (False, True) for overlap in (True, False)]


@pytest.mark.parametrize("n,tail,sheet,overlap", CASES)
def test_the_chunks_drags_equal_each_formations_bit_for_bit(n, tail, sheet, overlap):
    w, alone = _wakes(n, tail, sheet, overlap)
    assert lanes_apply(w.lattice)
    rng = np.random.default_rng(1000 + 100 * n + 10 * tail + 2 * sheet + overlap)
    perturb = 1.0 + 0.01 * rng.normal(size=(LANES, w.n_panels))  # a coupled circulation: not the solve's
    perturb[:4] = 1.0
    perturb[5, :3] = 0.0  # zero circulations: the skipped terms
    got_f, got_a, want_f, want_a = _drags(w, alone, *_chunk(rng, n), perturb)
    assert np.all(np.isfinite(want_f)) and np.all(np.isfinite(want_a))
    assert np.all(want_a > 0.0)  # a real drag: the comparison is not of zeros
    assert np.array_equal(_bits(got_f), _bits(want_f))
    assert np.array_equal(_bits(got_a), _bits(want_a))


def test_a_changed_circulation_changes_the_chunks_drags():
    """The comparison can fail: one lane's circulation changed in its last bit moves its drag in formation only."""
    w, alone = _wakes(2, False, False, True)
    state = _chunk(np.random.default_rng(5), 2)
    base = _drags(w, alone, *state, np.ones((LANES, w.n_panels)))
    nudged = np.ones((LANES, w.n_panels))
    nudged[7, 4] = 1.0 + 2.0 ** -40
    moved = _drags(w, alone, *state, nudged)
    assert not np.array_equal(moved[0][7], base[0][7])
    assert np.array_equal(moved[1], base[1])
    assert np.array_equal(np.delete(moved[0], 7, 0), np.delete(base[0], 7, 0))


def test_a_lone_lattice_of_another_make_up_is_refused():
    """Every vehicle must have the lone lattice's panel count (as induced_drags_one demands)."""
    w, _ = _wakes(2, False, False, True)
    lat = w.lattice
    n = w.n_panels
    c = chunk_scratch(2, lat.knot_x1_b.shape[0], lat.surface_origin_b.shape[0], n, False)
    z = np.zeros((LANES, 2))
    with pytest.raises(ValueError, match="n_alone"):
        induced_drags_chunk(w, n // 2 + 1, c, z + 25.0, z, z, np.zeros((LANES, n)), np.zeros((LANES, n, n + 1)), 1.225,
                            z.copy(), z.copy())
