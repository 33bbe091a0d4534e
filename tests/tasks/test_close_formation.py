"""The close_formation scenario: the ELL induced-drag optimum, its cached map and its Gym id."""

import gymnasium as gym
import numpy as np
import pytest

import formation_env  # noqa: F401  (registers the Gym ids)
from formation_env.envs import GYM_IDS, Randomisation
from formation_env.scenarios import get_scenario, scenario_names
from formation_env.tasks.close_formation import optimum as cfm


@pytest.fixture(scope="module")
def cache():
    return cfm.load_cache()


def _search(cache):
    return {k: tuple(v) if isinstance(v, list) else v for k, v in cache["parameters"]["search"].items()}


@pytest.fixture(scope="module")
def optimum(cache):
    return cfm.find_optimum(cache["parameters"]["x_b"], z_exclusion_b=cache["z_exclusion_b"], **_search(cache))


def test_cache_is_small_and_matches_the_module_defaults(cache):
    assert cfm.CACHE_PATH.stat().st_size < 100_000
    assert cache["z_exclusion_b"] == cfm.DEFAULT_Z_EXCLUSION_B
    assert cache["parameters"]["x_b"] == cfm.DEFAULT_X_B
    assert cache["parameters"]["wake"]["tailplane"] is False  # the simulator's default ELL model
    m = cfm.SavingMap.from_dict(cache["map"])
    assert m.follower.shape == (m.y_b.size, m.z_b.size) == m.leader.shape


def test_find_optimum_reproduces_the_cached_optimum(cache, optimum):
    c = cache["optimum"]
    np.testing.assert_allclose(optimum.offset_b, c["offset_b"], atol=2e-3)
    assert optimum.saving == pytest.approx(c["saving"], abs=5e-4)
    assert optimum.leader_saving == pytest.approx(c["leader_saving"], abs=5e-4)
    # the cached coarse map agrees with a fresh evaluation at a few of its points
    m = cfm.SavingMap.from_dict(cache["map"])
    iy, iz = [0, 12, 25, 30], [3, 12, 19, 20]
    fresh = cfm.slot_savings(np.stack([np.full(4, m.x_b), m.y_b[iy], m.z_b[iz]], -1))
    np.testing.assert_allclose(fresh[:, 1], m.follower[iy, iz], atol=1e-4)
    np.testing.assert_allclose(fresh[:, 0], m.leader[iy, iz], atol=1e-4)


def test_the_optimum_beats_the_thesis_slot(cache, optimum):
    thesis = cfm.slot_savings(np.array(cfm.THESIS_SLOT_B))[1]
    assert thesis == pytest.approx(cache["thesis_slot_saving"], abs=1e-4)
    assert optimum.saving >= 0.30
    assert optimum.saving > thesis + 0.15
    assert 0.9 < optimum.offset_b[1] < 1.0  # a little wing-tip overlap
    # it is a maximum: a step of 0.05 b along y or away from the wake plane loses saving
    x, y, z = optimum.offset_b
    around = cfm.slot_savings(np.array([[x, y - 0.05, z], [x, y + 0.05, z], [x, y, z + 0.05]]))[:, 1]
    assert np.all(around < optimum.saving)


def test_port_and_starboard_optima_mirror(optimum):
    port = cfm.find_optimum(z_exclusion_b=optimum.z_exclusion_b, side="port")
    # the optimum is flat laterally (0.05 b inboard loses 0.013): the trim's small heading and roll move the argmax
    # of the two sides apart by 0.007 b and their savings by 8e-4
    assert port.offset_b[1] == pytest.approx(-optimum.offset_b[1], abs=0.01)
    assert port.offset_b[2] == pytest.approx(optimum.offset_b[2], abs=1e-3)
    assert port.saving == pytest.approx(optimum.saving, abs=1.5e-3)
    # the map is mirror symmetric too (up to the trim's tiny heading, -0.0006 rad)
    m = cfm.saving_map(-2.0, [-1.2, -0.96, -0.5, 0.5, 0.96, 1.2], [-0.3, 0.1, 0.25])
    np.testing.assert_allclose(m.follower, m.follower[::-1], atol=1e-3)
    np.testing.assert_allclose(m.leader, m.leader[::-1], atol=1e-3)


def test_the_converged_map_needs_no_band_where_the_lattice_did(cache, optimum):
    """The converged wake (the task's) is single-peaked sideways at every height down to the wake plane, so the
    task excludes no band and its optimum lies on the plane; the nseg-10 lattice ripples within 0.1 b of the plane
    (its discrete legs) and reads an unphysical ~100 % saving on it, which is why its band existed."""
    assert cache["z_exclusion_b"] == cache["z_exclusion_measured_b"] == 0.0
    assert abs(optimum.offset_b[2]) < 0.005 and not optimum.on_band_edge
    rp = cfm.ripple_profile([-0.05, 0.0, 0.05])
    assert rp["excess_variation"].max() <= cache["parameters"]["ripple"]["tol"] == 1e-3
    assert np.all(rp["n_local_maxima"] == 1)
    assert rp["peak_saving"][1] == pytest.approx(optimum.saving, abs=2e-3) and rp["peak_saving"][1] < 0.6
    wider = cfm.find_optimum(z_exclusion_b=0.2, grid_step_b=0.1)
    assert abs(wider.offset_b[2]) >= 0.2 - 1e-9
    assert wider.saving < optimum.saving - 0.2  # 0.1 b off the plane already loses 40 %
    lat = cfm.ripple_profile([-0.05, 0.0, 0.05, cfm.LATTICE_Z_EXCLUSION_B], wake=cfm.LATTICE_WAKE)
    assert lat["excess_variation"][:3].min() > 0.1 and np.all(lat["n_local_maxima"][:3] > 3)
    assert lat["peak_saving"][1] > 0.9  # the lattice on its own legs: near-zero induced drag
    assert lat["excess_variation"][3] <= 1e-4 and lat["n_local_maxima"][3] == 1
    with pytest.raises(ValueError, match="z_exclusion_b"):
        cfm.find_optimum(z_exclusion_b=0.6)
    with pytest.raises(ValueError, match="side"):
        cfm.find_optimum(side="left")


def test_scenario_and_gym_id(cache):
    assert "close_formation" in scenario_names()
    sc = get_scenario("close_formation")
    assert sc.n_vehicles == 2 and sc.duration_s == 60.0
    slot = np.array(sc.slots[0].offset_and_rate(0.0)[0]) / sc.slots[0].span_m
    np.testing.assert_allclose(slot, cache["scenario_slot_b"], atol=1e-12)
    np.testing.assert_allclose(slot, cache["optimum"]["offset_b"], atol=0.005 + 1e-9)
    assert "56 %" in sc.description and f"{100 * cache['scenario_slot_saving']:.0f} %" in sc.description
    assert GYM_IDS["formation_env/CloseFormation-v1"] == ("close_formation", 1)
    from formation_env.sim.config import Randomisation

    # the benchmark draws turbulence and a start jitter: calm air, on the slot, for the map's value
    env = gym.make("formation_env/CloseFormation-v1", duration_s=1.0, action_mode="residual", compute_benefit=True,
                   randomisation=Randomisation())
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    for _ in range(3):
        obs, reward, term, trunc, info = env.step(np.zeros(4, np.float32))
        assert np.isfinite(reward) and not term
    # the env's own ELL saving (same model, same poses) starts at the map's value
    assert info["induced_drag_saving"] == pytest.approx(cache["scenario_slot_saving"], abs=0.05)
    env.close()


def test_env_benefit_is_the_ell_saving_of_the_last_physics_step():
    """The compiled benefit of a decision is formation_benefit (numpy ELL loads) at the poses of the
    decision's last physics step (here one physics step per decision), to round-off."""
    from formation_env.sim.formation import ell_state_from_aircraft
    from formation_env.wake import formation_benefit

    env = formation_env.parallel_env("close_formation", action_mode="setpoints", control_hz=50.0, compute_benefit=True,
                                     randomisation=Randomisation(turbulence_sigma_mps=1.0))
    env.reset(seed=3)
    eng = env.sim
    rng = np.random.default_rng(0)
    seen = []
    for _ in range(30):
        before = eng.aircraft.copy(), eng.ambient_wind().copy()
        _, _, term, _, infos = env.step({a: rng.uniform(-0.01, 0.01, 4).astype(np.float32) for a in env.agents})
        ref = formation_benefit(eng.wake_model, ell_state_from_aircraft(before[0], before[1], eng.wing_origin_body))
        got = [infos[a]["induced_drag_saving"] for a in env.possible_agents]
        np.testing.assert_allclose(got, ref["induced_drag_saving"][0], rtol=0, atol=1e-9)
        seen.append(got[1])
    assert 0.45 < np.mean(seen) < 0.6  # the follower starts at the optimum (56 % there)
