"""The AIC assembled over vector lanes (formation_env.wake.lanes, issue 26) equals the scalar assembly bit for bit.

``assemble_and_solve`` takes each control point's knots as vector lanes (fast forms where every core factor is
exactly 1, the scalar laws elsewhere); ``assemble_and_solve_scalar`` evaluates every branch with the scalar laws
of ``biot_savart``. Their AIC, right-hand side, circulation and branch vectors (``vcross``) must be identical to the
last bit over formations from coincident to spans apart, with and without tailplanes, the sheet law, the overlap
core and the viscous core in the solve, so that seeded episodes are unchanged.
"""

from __future__ import annotations

from functools import lru_cache

import numba as nb
import numpy as np
import pytest

from formation_env.geometry import aerosonde
from formation_env.wake import WakeModel
from formation_env.wake.aic import assemble_and_solve, assemble_and_solve_scalar
from formation_env.wake.arrays import wake_arrays
from formation_env.wake.lanes import KMAX
from formation_env.wake.posing import posed_lattice

B = 2.9  # Aerosonde span, m


def _solve_with(fn):
    @nb.njit
    def run(w, pos, euler, speed, alpha, beta, store):
        posed = posed_lattice(w.lattice, pos, euler, speed, alpha, beta)
        n = w.n_panels
        aic = np.empty((n, n))
        gamma = np.empty(n)
        vcross = np.zeros((n, n, 3) if store else (0, 0, 3))
        keep = np.empty((n, n + 1))
        fn(w.lattice, posed, aic, gamma, vcross, w.sheet, keep)
        return keep, gamma, vcross
    return run


_lanes = _solve_with(assemble_and_solve)
_scalar = _solve_with(assemble_and_solve_scalar)


@lru_cache(maxsize=None)
def _arrays(n: int, tail: bool, sheet: bool, overlap: bool, viscous: bool, nseg: int = 10):
    vehicle = aerosonde(tailplane=tail)
    if nseg != 10:
        from formation_env.wake.converged import refined_vehicle
        vehicle = refined_vehicle(vehicle, nseg)
    model = WakeModel([vehicle] * n, sheet=sheet, overlap_core=1.0 if overlap else 0.0, viscous_aic=viscous)
    return wake_arrays(model, np.zeros(3))


def _bits(a):
    return np.ascontiguousarray(a).view(np.uint64)


def _poses(rng, n, scale):
    """A formation of n: the vee slots (2 spans back, 0.9 across per rank) displaced by ``scale`` spans at random,
    random attitudes within +-10 deg, alpha 0-8 deg, beta +-4 deg, 20-30 m/s."""
    slots = np.array([[-2.0 * ((i + 1) // 2), 0.9 * ((i + 1) // 2) * (1 if i % 2 else -1), 0.1 * ((i + 1) // 2)]
                      for i in range(n)]) * B
    pos = slots + rng.normal(size=(n, 3)) * scale * B
    euler = np.radians(rng.uniform(-10, 10, (n, 3)))
    alpha = np.radians(rng.uniform(0, 8, n))
    euler[:, 1] += alpha
    return pos, euler, rng.uniform(20, 30, n), alpha, np.radians(rng.uniform(-4, 4, n))


CASES = [(n, tail, sheet, overlap, viscous)
         for n, tail in ((2, False), (2, True), (3, False), (5, False))
         for sheet in (False, True) for overlap in (True, False) for viscous in (True, False)]


@pytest.mark.parametrize("n,tail,sheet,overlap,viscous", CASES)
def test_lanes_equal_the_scalar_assembly_bit_for_bit(n, tail, sheet, overlap, viscous):
    w = _arrays(n, tail, sheet, overlap, viscous)
    assert w.lattice.knot_x1_b.shape[0] <= KMAX  # the lanes path is the one under test
    rng = np.random.default_rng(1000 * n + 100 * tail + 10 * sheet + 2 * overlap + viscous)
    for trial in range(12):
        # from the slots (wake planes, the sheet region) to overlapping, coincident and 1 um apart
        pos, euler, speed, alpha, beta = _poses(rng, n, (0.0, 0.02, 0.1, 0.5, 1.5, 3.0)[trial % 6])
        if trial % 4 == 3:
            pos[1] = pos[0] + (0.0 if trial % 8 == 3 else 1e-6)
            euler[1] = euler[0]
        for store in (True, False):
            got = _lanes(w, pos, euler, speed, alpha, beta, store)
            want = _scalar(w, pos, euler, speed, alpha, beta, store)
            for g, e, name in zip(got, want, ("AIC and right-hand side", "circulation", "vcross")):
                assert np.array_equal(_bits(g), _bits(e)), (name, trial, store)


def test_a_lattice_beyond_the_lanes_takes_the_scalar_assembly():
    """Two Aerosondes of 80 horseshoes (162 knots > KMAX): the scalar assembly, the same circulation."""
    w = _arrays(2, False, False, True, True, nseg=80)
    assert w.lattice.knot_x1_b.shape[0] > KMAX
    pos, euler, speed, alpha, beta = _poses(np.random.default_rng(5), 2, 0.1)
    got = _lanes(w, pos, euler, speed, alpha, beta, True)
    want = _scalar(w, pos, euler, speed, alpha, beta, True)
    assert all(np.array_equal(_bits(g), _bits(e)) for g, e in zip(got, want))
    assert np.all(np.isfinite(got[1]))


@pytest.mark.parametrize("n,tail,sheet,overlap,viscous", [c for c in CASES if c[4]])
def test_loads_over_lanes_equal_the_scalar_field_bit_for_bit(n, tail, sheet, overlap, viscous):
    """The saving's Kutta-Joukowski loads take the field at the bound midpoints over the same lanes
    (benefit.induced_drags_one); they must equal the formation's drag from the scalar field (induced_drag_one) and
    each vehicle's drag from its separate lone solve (isolated_induced_drag_one), bit for bit."""
    from formation_env.wake.benefit import induced_drag_one, induced_drags_one, isolated_induced_drag_one
    from formation_env.wake.kernels import evaluate_one

    w = _arrays(n, tail, sheet, overlap, viscous)
    vehicle = aerosonde(tailplane=tail)
    alone = wake_arrays(WakeModel([vehicle], sheet=sheet, overlap_core=1.0 if overlap else 0.0, viscous_aic=viscous),
                        np.zeros(3))
    rng = np.random.default_rng(77 + n + 10 * tail + 100 * sheet + 1000 * overlap)
    for trial in range(6):
        pos, euler, speed, alpha, beta = _poses(rng, n, (0.0, 0.02, 0.1, 0.5, 1.5, 3.0)[trial])
        npn = w.n_panels
        gamma = np.empty(npn)
        evaluate_one(w.lattice, pos, euler, speed, alpha, beta, gamma, np.empty((npn, 3)),
                     *[np.empty((n, 3)) for _ in range(4)], w.sheet)
        both_form, both_alone = np.empty(n), np.empty(n)
        induced_drags_one(w, alone, pos, euler, speed, alpha, beta, gamma, both_form, both_alone)
        d_form = np.empty(n)
        induced_drag_one(w, gamma, pos, euler, speed, alpha, beta, d_form)
        assert np.array_equal(_bits(both_form), _bits(d_form)), trial
        for v in range(n):
            assert both_alone[v] == isolated_induced_drag_one(alone, v, pos, euler, speed, alpha, beta), (trial, v)
