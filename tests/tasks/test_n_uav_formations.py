"""The N-UAV close formations (issue 25): their joint ELL optimum, the size-independent observation, the station
keeper on every follower and the per-follower and formation metrics of the evaluation."""

from __future__ import annotations

import numpy as np
import pytest

import formation_env
from formation_env.sim.config import EnvConfig, Randomisation
from formation_env.scenarios import get_scenario
from formation_env.sim import Simulation
from formation_env.envs.observations import observation_size
from formation_env.tasks import get_task
from formation_env.tasks.close_formation import optimum as two_ship
from formation_env.tasks.n_uav_formations import optimum as opt

NAMES = ("echelon3", "vee5", "vee9")


def test_the_cache_holds_what_the_ell_gives_at_its_slots():
    """The cached savings are the ELL's at the cached slots (the model the tasks fly), and the scenarios fly
    those slots."""
    cache = opt.load_cache()
    for name in NAMES:
        entry = cache["formations"][name]
        slots = np.asarray(entry["slots_b"])
        s = opt.formation_savings(slots)
        np.testing.assert_allclose(s, entry["slot_savings"], atol=2e-5)
        assert entry["slot_formation_saving"] == pytest.approx(s.mean(), abs=2e-5)
        sc = get_scenario(name)
        assert sc.n_vehicles == 1 + len(slots)
        for sched, slot in zip(sc.slots, slots):
            np.testing.assert_allclose(np.asarray(sched.keyframes[0][1]), slot, atol=0)


def test_two_ships_reduce_to_the_close_formation_map():
    """With one follower the formation saving is the 2-UAV map's (the same ELL, trims and poses)."""
    pts = np.array([[-2.0, 0.96, 0.1], [-2.0, 0.5, 0.3], [-3.0, -1.1, 0.2]])
    np.testing.assert_allclose(opt.formation_savings(pts[:, None, :]), two_ship.slot_savings(pts), atol=1e-12)


def test_the_joint_optimum_is_a_local_maximum_on_the_wake_planes():
    """No per-rank step moved by 0.02 b (one at a time, inside the bounds) raises the vee's formation saving, its
    vertical steps lie on the wake plane of the UAV ahead (within 0.005 b: the converged wake has no artefact band,
    as for 2 UAVs), inside the search's bounds, and the vee is symmetric (starboard and port followers save
    alike)."""
    o = opt.optimum("vee5")["optimum"]
    lay = opt.FORMATIONS["vee5"]
    steps = np.asarray(o["steps_b"])
    base = opt.formation_savings(opt.layout_offsets(lay, steps)).mean()
    assert base == pytest.approx(o["formation_saving"], abs=1e-5)
    trials = []
    for r in range(lay.ranks):
        for ax, (lo, hi) in ((0, opt.DY_RANGE_B), (1, opt.DZ_RANGE_B)):
            for d in (-0.02, 0.02):
                st = steps.copy()
                st[r, ax] += d
                if lo <= st[r, ax] <= hi:
                    trials.append(st)
    moved = opt.formation_savings(opt.layout_offsets(lay, np.asarray(trials))).mean(axis=-1)
    assert np.all(moved <= base + 5e-5)  # flat to 1e-5 of it: the residual table is smooth to its interpolation
    assert not any(o["on_band_edge"])
    assert np.all(np.abs(steps[:, 1]) < 0.005) and np.all(steps[:, 1] > opt.DZ_RANGE_B[0] + 0.1)
    s = np.asarray(o["savings"])
    # to 2.5e-3: the residual table's mirror (y < 0 read as y > 0 in the source's heading axes) ignores the trim's
    # 0.0006 rad sideslip, which skews the wake by 2 x 0.0006 rad x 2 b about it: 0.0017-0.0019 on the wake plane
    # (the nseg-80 lattice: 8e-5; a known 0.3 % of the peak, inside the table's 3 % target)
    np.testing.assert_allclose(s[1::2], s[2::2], atol=2.5e-3)
    # the followers save far more than the leader, and a rank further back more than the one ahead
    assert s[0] < 0.1 and np.all(s[3:] > s[1:3].max())


def test_every_formation_observes_one_size_and_the_nearest_slots():
    """With the tasks' two neighbours, echelon3, vee5 and vee9 observe alike (one policy flies all three), and the
    neighbours are the nearest by slot: in a vee the inner followers see each other first (1.8 b abeam)."""
    sizes = {Simulation(EnvConfig(scenario=n, learning="followers"), batch_size=1).obs_size for n in NAMES}
    assert sizes == {observation_size(3)}
    from formation_env.sim.observe import _neighbour

    pd = np.array(get_scenario("vee5").start_position_ned())
    assert [_neighbour(pd, 1, m, 2) for m in range(2)] == [2, 0]  # inner starboard: inner port, then the leader
    assert [_neighbour(pd, 3, m, 2) for m in range(2)] == [1, 2]  # outer starboard: the inner ahead, then across
    assert [_neighbour(pd, 1, m, 0) for m in range(4)] == [0, 2, 3, 4]  # 0: every other, index order
    assert _neighbour(pd, 1, 4, 5) == -1  # more asked than the formation has


@pytest.mark.parametrize("k,wind,att", [(0, False, False), (2, False, False), (6, False, False), (0, True, False),
                                        (2, True, False), (6, True, False), (0, False, True), (2, True, True),
                                        (6, False, True)])
def test_compiled_neighbours_equal_the_numpy_definition(k, wind, att):
    """The compiled observation with ``neighbour_count`` k equals the numpy definition (tests/oracles), along a
    randomised vee episode: every other UAV (0), the nearest two by slot, and more than the vee has (6: two
    absent, 1 km behind); with and without the neighbours' winds and attitudes."""
    from tests.oracles.env_step import build_observations_reference, slot_schedule_features

    env = formation_env.parallel_env("vee5", action_mode="setpoints", neighbour_count=k, neighbour_wind=wind,
                                     neighbour_attitude=att,
                                     randomisation=Randomisation(initial_offset_m=3.0, turbulence_sigma_mps=1.0))
    env.reset(seed=11)
    rng = np.random.default_rng(2)
    for _ in range(15):
        obs, *_ = env.step({a: rng.uniform(-1, 1, 4) for a in env.agents})
        e = env.sim
        sched = slot_schedule_features(e.scenario, e.time_s, e.state.slot_jitter)
        ref = build_observations_reference(e.aircraft, e.induced, e.omega, e.ambient_wind(), np.zeros_like(e.induced),
                                           e.position_demand, e.velocity_demand, e.state.previous_action, sched,
                                           e.state.controller, e.scenario.airspeed_mps, e.scenario.altitude_m,
                                           neighbour_count=k, neighbour_wind=wind, neighbour_attitude=att)
        assert ref.shape[-1] == observation_size(5, k, wind, att) == env.observation_space("uav_1").shape[0]
        np.testing.assert_allclose(e.output.observation, ref, rtol=0, atol=1e-12)


def test_neighbour_wind_is_the_gust_difference_and_changes_nothing_else():
    """With ``neighbour_wind`` the observation is the one without it plus the neighbours' ambient winds minus the
    agent's (in turbulence not zero, in calm air zero), and the flight is the same bit for bit."""
    from formation_env.envs.observations import to_dict

    for sigma in (1.0, 0.0):
        envs = [formation_env.parallel_env("echelon3", action_mode="setpoints", neighbour_wind=w,
                                           randomisation=Randomisation(turbulence_sigma_mps=sigma)) for w in (False, True)]
        for env in envs:
            env.reset(seed=5)
        size = observation_size(3, 2)
        assert envs[1].observation_space("uav_1").shape[0] == size + 6
        rng = np.random.default_rng(0)
        spread = 0.0
        for _ in range(20):
            act = {a: rng.uniform(-1, 1, 4) for a in envs[0].agents}
            (o0, *_), (o1, *_) = (env.step(act) for env in envs)
            for a in o0:
                np.testing.assert_array_equal(o1[a][:size], o0[a])
                d = to_dict(o1[a], 3, 2, True)
                assert d["neighbour_wind"].shape == (6,)
                spread = max(spread, float(np.abs(d["neighbour_wind"]).max()))
        if sigma > 0:
            assert spread > 1e-3
        else:
            assert spread == 0.0


def test_neighbour_attitude_is_the_neighbours_attitude_and_changes_nothing_else():
    """With ``neighbour_attitude`` the observation is the one without it plus each neighbour's roll / 0.5, roll rate
    and pitch minus the agent's / 0.5 (read back from the aircraft states), and the flight is the same bit for bit;
    with the winds too, the attitudes follow the winds."""
    from formation_env.aircraft.state import euler_angles
    from formation_env.envs.observations import to_dict

    cfgs = [(False, False), (False, True), (True, True)]
    envs = [formation_env.parallel_env("echelon3", action_mode="setpoints", neighbour_wind=w, neighbour_attitude=t,
                                       randomisation=Randomisation(turbulence_sigma_mps=1.0)) for w, t in cfgs]
    for env in envs:
        env.reset(seed=5)
    size = observation_size(3, 2)
    assert [e.observation_space("uav_1").shape[0] for e in envs] == [size, size + 6, size + 12]
    rng = np.random.default_rng(0)
    for _ in range(20):
        act = {a: rng.uniform(-1, 1, 4) for a in envs[0].agents}
        (o0, *_), (o1, *_), (o2, *_) = (env.step(act) for env in envs)
        np.testing.assert_array_equal(envs[1].sim.aircraft, envs[0].sim.aircraft)
        eul = euler_angles(envs[0].sim.aircraft[0])  # (V, 3)
        x = envs[0].sim.aircraft[0]
        for i, a in enumerate(o0):
            np.testing.assert_array_equal(o1[a][:size], o0[a])
            np.testing.assert_array_equal(o2[a][:size + 6], np.concatenate([o0[a], to_dict(o2[a], 3, 2, True, True)["neighbour_wind"]]))
            d = to_dict(o1[a], 3, 2, False, True)["neighbour_attitude"].reshape(2, 3)
            np.testing.assert_array_equal(d, to_dict(o2[a], 3, 2, True, True)["neighbour_attitude"].reshape(2, 3))
            # the two neighbours of each UAV of an echelon of 3 observing 2: the other two, nearest slot first
            for row, j in zip(d, sorted((j for j in range(3) if j != i),
                                        key=lambda j: (np.sum((envs[0].sim.position_demand[0, j]
                                                               - envs[0].sim.position_demand[0, i]) ** 2), j))):
                np.testing.assert_allclose(row, [eul[j, 0] / 0.5, x[j, 3], (eul[j, 1] - eul[i, 1]) / 0.5],
                                           rtol=1e-6, atol=1e-7)  # the env's observations are float32


def test_neighbour_count_is_checked():
    with pytest.raises(ValueError, match="neighbour_count"):
        EnvConfig(scenario="vee5", neighbour_count=-1)
    with pytest.raises(ValueError, match="neighbour_count"):
        EnvConfig(scenario="vee5", neighbour_count=True)
    with pytest.raises(ValueError, match="neighbour_wind must be True or False, got 1"):
        EnvConfig(scenario="vee5", neighbour_wind=1)
    with pytest.raises(ValueError, match="neighbour_attitude must be True or False, got 'yes'"):
        EnvConfig(scenario="vee5", neighbour_attitude="yes")


def test_the_tasks_are_registered_with_their_reference():
    for name in NAMES:
        t = get_task(name)
        assert t.baselines == ("pid", "station_keeper")
        entry = opt.optimum(name)
        assert t.optimum_saving() == pytest.approx(np.mean(entry["slot_savings"][1:]), abs=1e-5)
        assert t.reference.optimum_savings() == tuple(entry["slot_savings"][1:])
        assert get_scenario(name).wake_coupling == "load_weighted"


def test_station_keeper_holds_every_follower_of_a_calm_vee():
    """In calm air the station keeper holds each of the vee's followers within a few centimetres along the track
    (its separation guard brakes only for a UAV ahead of and in line with the slot, not for the follower abeam or
    behind: it did, and the vee's inner followers lagged 4.7 m) and a tenth of a span across it."""
    from train.evaluation.episodes import eval_env_config, run_episodes
    from train.evaluation.policy_loader import load_policy

    pol = load_policy("station_keeper")
    eps = run_episodes(pol, eval_env_config("vee5", pol.action_mode, turbulence_sigma_mps=0.0, duration_s=40.0),
                       [1001, 1002])
    for m in eps:
        assert not m["collision"] and m["rms_along_track_m"] < 0.3 and m["rms_lateral_m"] < 0.2
        # the per-follower and formation metrics of an N-UAV task
        per = [m[f"induced_drag_saving_uav{v}"] for v in range(1, 5)]
        assert m["induced_drag_saving"] == pytest.approx(np.mean(per), abs=1e-12)
        assert 0.0 < m["formation_saving"] < max(per)
        assert 0.5 < m["harvest_ratio"] <= 1.0
