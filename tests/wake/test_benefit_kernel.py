"""The compiled per-formation induced drag / saving (formation_env.wake.benefit) equals the numpy
loads (formation_env.wake.loads) and reproduces the documented close-formation saving."""

from __future__ import annotations

import json
from functools import lru_cache

import numpy as np
import pytest

from formation_env.geometry import aerosonde, verification_wing
from formation_env.wake import FormationState, WakeModel, formation_benefit, vehicle_loads
from formation_env.wake.benefit import induced_drag_one, induced_drag_saving, induced_drag_saving_one
from formation_env.wake.kernels import evaluate_one

SPAN_M = 2.9
TRIM_ALPHA = 0.056357  # Aerosonde trim at 25 m/s, 1000 m (close_formation_map.json parameters)
TOL = 1e-9


@lru_cache(maxsize=None)
def _model(n: int, kind: str = "aerosonde") -> WakeModel:
    v = aerosonde(nseg=10)
    vehicles = [v] * n if kind == "aerosonde" else [v, verification_wing()]
    # The simulator's WakeConfig defaults.
    return WakeModel(vehicles, core="kurylowich", eval_points="control", rotational="lstsq", viscous_aic=True)


def _state(offsets_b, batch: int, seed: int, jitter: bool = True) -> FormationState:
    """B formations: vehicle i at offsets_b[i] spans (NED, leader flying north) about the trim,
    with small random attitude / alpha / beta / airspeed / position perturbations."""
    rng = np.random.default_rng(seed)
    off = np.asarray(offsets_b, float) * SPAN_M
    nv = off.shape[0]
    s = 1.0 if jitter else 0.0
    pos = off[None] + s * rng.uniform(-0.05, 0.05, (batch, nv, 3))
    euler = np.array([0.0, TRIM_ALPHA, 0.0]) + s * np.radians(rng.uniform(-2.0, 2.0, (batch, nv, 3)))
    speed = 25.0 + s * rng.uniform(-1.0, 1.0, (batch, nv))
    alpha = TRIM_ALPHA + s * np.radians(rng.uniform(-1.5, 1.5, (batch, nv)))
    beta = s * np.radians(rng.uniform(-1.5, 1.5, (batch, nv)))
    return FormationState(pos, euler, speed, alpha, beta)


def _check(model, state):
    got = induced_drag_saving(model, state)
    ref = formation_benefit(model, state)["induced_drag_saving"]
    assert got.shape == ref.shape == (state.batch_size, model.n_vehicles)
    assert np.all(np.isfinite(got))
    np.testing.assert_allclose(got, ref, rtol=0.0, atol=TOL)
    return got


@pytest.mark.parametrize("slot_b", [(-2.0, 1.0, 0.3), (-2.0, 0.96, 0.1)], ids=["thesis_slot", "close_slot"])
def test_two_aerosondes_match_numpy(slot_b):
    got = _check(_model(2), _state([(0.0, 0.0, 0.0), slot_b], batch=4, seed=1))
    assert np.all(got[:, 1] > 0.05)  # the follower gains in either slot


def test_three_vehicle_echelon_matches_numpy():
    got = _check(_model(3), _state([(0.0, 0.0, 0.0), (-2.0, 0.96, 0.1), (-4.0, 1.92, 0.2)], batch=3, seed=2))
    assert np.all(got[:, 2] > 0.05)


def test_far_apart_saving_is_zero():
    got = _check(_model(2), _state([(0.0, 0.0, 0.0), (0.0, 400.0, 0.0)], batch=2, seed=3))
    assert np.all(np.abs(got) < 1e-4)


def test_mixed_vehicles_match_numpy():
    # Different make-ups: each vehicle's isolated drag from its own single-vehicle lattice.
    _check(_model(2, "mixed"), _state([(0.0, 0.0, 0.0), (-2.0, 0.8, 0.1)], batch=2, seed=4))


def test_induced_drag_one_equals_vehicle_loads():
    from formation_env.sim.params import wake_arrays  # re-export of formation_env.wake.arrays

    model = _model(2)
    state = _state([(0.0, 0.0, 0.0), (-2.0, 0.96, 0.1)], batch=2, seed=5)
    sol = model.evaluate(state)
    ref = vehicle_loads(model, state, sol, air_density=1.1).drag_n
    wake = wake_arrays(model, np.zeros(3))
    for b in range(state.batch_size):
        out = np.empty(2)
        induced_drag_one(wake, np.ascontiguousarray(sol.circulation[b]), np.ascontiguousarray(state.position_ned[b]),
                         np.ascontiguousarray(state.euler_rad[b]), np.ascontiguousarray(state.airspeed_mps[b]),
                         np.ascontiguousarray(state.alpha_rad[b]), np.ascontiguousarray(state.beta_rad[b]), out, 1.1)
        np.testing.assert_allclose(out, ref[b], rtol=1e-12, atol=1e-12)
        assert out[0] > 0  # the leader; the follower in the upwash may even see induced thrust


def test_close_formation_saving_from_aircraft_state():
    """The env's compiled chain (ell_inputs -> evaluate_one -> induced_drag_saving_one) on two
    trimmed Aerosondes in the scenario slot gives the documented ~0.36 saving."""
    from importlib import resources

    from formation_env.aircraft import trim
    from tests.oracles.physics_simulator import FormationSimulator
    from formation_env.sim.kernels import ell_inputs
    from formation_env.sim.params import wake_arrays  # re-export of formation_env.wake.arrays
    from formation_env.wake.loads import isolated_model

    data = json.loads(resources.files("formation_env").joinpath("data/close_formation_map.json").read_text())
    sim = FormationSimulator(2, 1)
    model = sim.wake_model
    tr = trim(25.0, 1000.0)
    x = np.repeat(tr.state, 2, axis=0)  # (2, 16)
    x[1, 10:13] += np.asarray(data["scenario_slot_b"]) * SPAN_M
    nv, n = 2, model.n_panels
    pos, euler = np.empty((nv, 3)), np.empty((nv, 3))
    speed, alpha, beta = np.empty(nv), np.empty(nv), np.empty(nv)
    ell_inputs(x, np.zeros((nv, 3)), np.asarray(sim.wing_origin_body, float), pos, euler, speed, alpha, beta)
    wake = wake_arrays(model, sim.wing_origin_body)
    alone = wake_arrays(isolated_model(model.vehicles[0], model.core, model.eval_points, model.rotational,
                                     model.kinematic_viscosity, model.viscous_aic), sim.wing_origin_body)
    gamma, vpts = np.empty(n), np.empty((n, 3))
    w = wake
    # the thesis's legs (no sheet switch), with the lattice's overlap core
    evaluate_one(w.lattice, pos, euler, speed, alpha, beta, gamma, vpts, *[np.empty((nv, 3)) for _ in range(4)])
    saving = np.empty(nv)
    induced_drag_saving_one(wake, alone, pos, euler, speed, alpha, beta, gamma, saving)
    assert saving[1] == pytest.approx(0.36, abs=0.01)
    # the oracle flies the thesis (flat Table 6.1) wing; the cache is the energy tasks' lift-matched wing, so
    # compare with the map's function on the flat wing
    from formation_env.sim.formation import WakeConfig
    from formation_env.tasks.close_formation.optimum import slot_savings

    flat = slot_savings(np.asarray(data["scenario_slot_b"]), wake=WakeConfig(coupling="effective_wind"))[1]
    assert saving[1] == pytest.approx(flat, abs=2e-5)
    # the lift-matched wing on the same lattice moves it by little (the cache itself is the converged wake's)
    from formation_env.tasks.close_formation.optimum import LATTICE_WAKE

    assert abs(slot_savings(np.asarray(data["scenario_slot_b"]), wake=LATTICE_WAKE)[1] - flat) < 0.005
    ref = formation_benefit(model, FormationState(pos, euler, speed, alpha, beta))["induced_drag_saving"][0]
    np.testing.assert_allclose(saving, ref, rtol=0.0, atol=TOL)


@pytest.mark.parametrize("n, offsets", [
    (2, [(0.0, 0.0, 0.0), (-2.0, 0.96, 0.1)]),
    (2, [(0.0, 0.0, 0.0), (-2.0, 0.93, 0.0)]),          # on the wake plane
    (3, [(0.0, 0.0, 0.0), (-2.0, 0.96, 0.1), (-4.0, 1.92, 0.2)]),
    (2, [(0.0, 0.0, 0.0), (-0.3, 0.2, 0.05)]),           # overlapping wings
], ids=["close_slot", "wake_plane", "echelon", "overlap"])
def test_fused_saving_is_bit_for_bit_the_separate_solves(n, offsets):
    """The saving takes the lone vehicles' drag from the formation's pass (issue 26: the own horseshoes'
    branches evaluated once for both circulations); it must equal, bit for bit, the formation's drag
    (induced_drag_one) over each vehicle's separately solved drag alone (isolated_induced_drag_one)."""
    from formation_env.sim.params import wake_arrays
    from formation_env.wake.benefit import induced_drags_one, isolated_induced_drag_one
    from formation_env.wake.loads import isolated_model

    model = _model(n)
    state = _state(offsets, batch=6, seed=11)
    sol = model.evaluate(state)
    wake = wake_arrays(model, np.zeros(3))
    v0 = model.vehicles[0]
    alone = wake_arrays(isolated_model(v0, model.core, model.eval_points, model.rotational, model.kinematic_viscosity,
                                       model.viscous_aic), np.zeros(3))
    for b in range(state.batch_size):
        args = [np.ascontiguousarray(x[b], dtype=float) for x in (state.position_ned, state.euler_rad,
                                                                 state.airspeed_mps, state.alpha_rad, state.beta_rad)]
        gamma = np.ascontiguousarray(sol.circulation[b])
        fused = np.empty(n)
        induced_drag_saving_one(wake, alone, *args, gamma, fused)
        d_form = np.empty(n)
        induced_drag_one(wake, gamma, *args, d_form)
        both_form, both_alone = np.empty(n), np.empty(n)
        induced_drags_one(wake, alone, *args, gamma, both_form, both_alone)
        assert np.array_equal(both_form, d_form)
        for v in range(n):
            d_alone = isolated_induced_drag_one(alone, v, *args)
            assert both_alone[v] == d_alone
            assert fused[v] == 1.0 - d_form[v] / d_alone  # exactly


def test_a_lone_lattice_of_another_make_up_is_refused():
    """induced_drags_one indexes each vehicle's lone circulation by the formation's panels: a wake_alone with
    another panel count (another make-up) is refused, never read out of bounds."""
    from formation_env.sim.params import wake_arrays
    from formation_env.wake.benefit import induced_drags_one
    from formation_env.wake.loads import isolated_model

    model = _model(2)
    state = _state([(0.0, 0.0, 0.0), (-2.0, 0.96, 0.1)], batch=1, seed=12)
    wake = wake_arrays(model, np.zeros(3))
    other = wake_arrays(isolated_model(aerosonde(nseg=12), model.core, model.eval_points, model.rotational,
                                       model.kinematic_viscosity, model.viscous_aic), np.zeros(3))
    args = [np.ascontiguousarray(x[0], dtype=float) for x in (state.position_ned, state.euler_rad,
                                                             state.airspeed_mps, state.alpha_rad, state.beta_rad)]
    with pytest.raises(ValueError, match="make-up"):
        induced_drags_one(wake, other, *args, np.zeros(20), np.empty(2), np.empty(2))


@pytest.mark.parametrize("n, offsets, kind, sheet", [
    (2, [(0.0, 0.0, 0.0), (-2.0, 0.96, 0.1)], "aerosonde", False),
    (2, [(0.0, 0.0, 0.0), (-2.0, 0.93, 0.0)], "aerosonde", True),    # on the wake plane, the sheet law
    (3, [(0.0, 0.0, 0.0), (-2.0, 0.96, 0.1), (-4.0, 1.92, 0.2)], "tail", False),
    (2, [(0.0, 0.0, 0.0), (-0.3, 0.2, 0.05)], "aerosonde", False),  # overlapping wings
], ids=["close_slot", "wake_plane_sheet", "echelon_tail", "overlap"])
def test_isolated_circulation_from_the_kept_aic_is_bit_for_bit_the_lone_solve(n, offsets, kind, sheet):
    """Issue 26: the formation solve keeps its AIC before elimination, and the benefit solves each vehicle's
    diagonal block instead of posing and assembling the vehicle alone. The block must be the lone AIC entry for
    entry, so the saving is bit for bit the one from the separate lone solves, for every configuration the envs
    use (the sheet law's other-vehicle legs do not enter a diagonal block; nor does the overlap core)."""
    from formation_env.geometry import aerosonde
    from formation_env.sim.params import wake_arrays
    from formation_env.wake.arrays import evaluate_formation
    from formation_env.wake.loads import isolated_model

    vehicles = [aerosonde(tailplane=True) if kind == "tail" else aerosonde() for _ in range(n)]
    model = WakeModel(vehicles, sheet=sheet) if sheet else WakeModel(vehicles)
    state = _state(offsets, batch=5, seed=17)
    wake = wake_arrays(model, np.zeros(3))
    alone = wake_arrays(isolated_model(vehicles[0], model.core, model.eval_points, model.rotational,
                                       model.kinematic_viscosity, model.viscous_aic), np.zeros(3))
    N = model.n_panels
    for b in range(state.batch_size):
        args = [np.ascontiguousarray(x[b], dtype=float) for x in (state.position_ned, state.euler_rad,
                                                                 state.airspeed_mps, state.alpha_rad, state.beta_rad)]
        gamma, keep = np.empty(N), np.full((N, N + 1), np.nan)
        evaluate_formation(wake, *args, gamma, np.empty((N, 3)), np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)),
                           np.empty((n, 3)), keep)
        gamma_plain = np.empty(N)
        evaluate_formation(wake, *args, gamma_plain, np.empty((N, 3)), np.empty((n, 3)), np.empty((n, 3)),
                           np.empty((n, 3)), np.empty((n, 3)))
        assert np.array_equal(gamma, gamma_plain) and np.all(np.isfinite(keep))  # keeping changes nothing
        reused, separate = np.empty(n), np.empty(n)
        induced_drag_saving_one(wake, alone, *args, gamma, reused, 1.225, keep)
        induced_drag_saving_one(wake, alone, *args, gamma, separate)
        assert np.array_equal(reused, separate)
        assert np.any(reused != 0.0)
