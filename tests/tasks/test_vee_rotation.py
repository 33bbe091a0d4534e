"""Task ``vee_rotation`` (issue 25): vee5's leader hands the apex to vehicle 1 and drops back to a trailing slot.
The schedule starts and ends in vee5's joint-optimum vee, never brings two slots closer than the vee's own
rank spacing, and the task is a registered, flyable unit judged by the reconfiguration success."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import formation_env
from formation_env.constants import AEROSONDE_SPAN_M as SPAN
from formation_env.scenarios import SlotSchedule, get_scenario
from formation_env.sim.config import EnvConfig
from formation_env.sim.params import hold_remaining_decisions
from formation_env.tasks import get_task
from formation_env.tasks.n_uav_formations import optimum as opt
from formation_env.tasks.n_uav_formations.rotation import PHASES_S, rotation_keyframes


def _positions(t):
    """(5, T, 3) every UAV's nominal slot, m from vehicle 0 (vehicle 0 at the origin)."""
    sc = get_scenario("vee_rotation")
    return np.stack([np.zeros((len(t), 3))] + [s.offset_and_rate(t)[0] for s in sc.slots])


def test_starts_and_ends_in_the_vee5_optimum_with_vehicle_1_at_the_apex():
    """At t = 0 the followers fly vee5's slots; after the last keyframe the five UAVs form the same vee (every
    offset from the apex equal to one of vee5's slots, each used once) with vehicle 1 at the apex and vehicle 0
    at the end of the starboard side (vee5's starboard rank 2)."""
    slots = np.asarray(opt.optimum("vee5")["slots_b"]) * SPAN
    p = _positions(np.array([0.0, PHASES_S[-2], PHASES_S[-1]]))
    np.testing.assert_allclose(p[1:, 0], slots, atol=1e-9)
    np.testing.assert_allclose(p[:, 1], p[:, 2], atol=1e-12)  # held after the last keyframe
    rel = p[:, -1] - p[1, -1]  # from the new apex
    assert np.allclose(rel[0], slots[2])  # vehicle 0: starboard rank 2
    others = sorted(map(tuple, np.round(np.delete(rel, 1, axis=0), 9)))
    assert others == sorted(map(tuple, np.round(slots, 9)))


def test_no_two_slots_ever_closer_than_the_vees_rank_spacing():
    """Over the whole schedule (10 ms samples) every pair of nominal slots stays at least 5.1 m apart (the
    rank-1 spacing of the vee, 3.5x the 1.45 m collision separation); the passes are abeam at >= 1.78 b."""
    t = np.arange(0.0, PHASES_S[-1] + 1e-9, 0.01)
    p = _positions(t)
    d = min(np.min(np.linalg.norm(p[i] - p[j], axis=-1)) for i in range(5) for j in range(i + 1, 5))
    assert d > 5.1, d
    # vehicle 1 passes vehicle 0 abeam: at x = 0 its lateral offset is two rank-1 steps
    x1 = p[1, :, 0]
    k = np.argmin(np.abs(x1))
    assert abs(p[1, k, 1]) > 1.75 * SPAN


def test_the_hold_phase_and_the_success_window_fit_the_episode():
    """The last keyframe is 18 s before the time limit: the 5 s success window starts after it for every
    follower (the hold phase of RewardWeights.hold is 180 decisions at 10 Hz)."""
    sc = get_scenario("vee_rotation")
    assert sc.duration_s == PHASES_S[-1]
    assert all(s.keyframes[-1][0] == PHASES_S[-2] for s in sc.slots)
    np.testing.assert_array_equal(hold_remaining_decisions(sc, sc.duration_s, 10.0), [-1, 180, 180, 180, 180])


def test_bad_phases_are_refused():
    slots = opt.optimum("vee5")["slots_b"]
    for bad in ((15.0, 10.0, 50.0, 62.0, 80.0), (0.0, 25.0, 50.0, 62.0, 80.0), (15.0, 25.0, 50.0, 62.0)):
        with pytest.raises(ValueError, match="phases_s"):
            rotation_keyframes(slots, bad)
    SlotSchedule(rotation_keyframes(slots)[0])  # the default is a valid schedule


def test_registered_task_and_gym_id_fly():
    """The task is registered with its baselines, the Gymnasium id steps, and every follower learns in the
    PettingZoo env (4 agents)."""
    task = get_task("vee_rotation")
    assert task.baselines == ("pid", "station_keeper")
    assert EnvConfig(scenario="vee_rotation").scenario == "vee_rotation"
    env = gym.make(task.gym_id, action_mode="setpoints")
    obs, _ = env.reset(seed=3)
    obs, r, term, trunc, _ = env.step(env.action_space.sample())
    assert np.all(np.isfinite(obs)) and np.isfinite(r) and not term
    env.close()
    par = formation_env.parallel_env("vee_rotation", action_mode="setpoints", learning="followers")
    obs, _ = par.reset(seed=1)
    assert len(par.agents) == 4
    par.close()


def test_station_keeper_rotates_a_calm_vee_and_pid_cannot():
    """Judged as the task is evaluated (every UAV an agent, the success over the followers only: vehicle 0 has no
    slot): in calm air the station keeper on every UAV flies the rotation within 1 span of every final slot for
    the last 5 s without a collision (measured 30 of 30 from seeds 7200000000..); the thesis PID, whose vehicle 0
    swings in the new vee's wake, does not (26 collisions in 30)."""
    from train.evaluation.episodes import eval_env_config, run_episodes
    from train.evaluation.policy_loader import load_policy

    keeper = load_policy("station_keeper")
    cfg = eval_env_config("vee_rotation", keeper.action_mode, turbulence_sigma_mps=0.0)
    assert cfg.learning == "all"
    (m,) = run_episodes(keeper, cfg, [7200000001])
    assert m["reconfig_success"] and not m["collision"] and m["min_separation_m"] > 4.0
    assert 40.0 < m["reconfig_time_s"] < 50.0  # from the schedule's start (15 s) to within 1 span for good (~58 s)
    pid = load_policy("pid")
    (m,) = run_episodes(pid, eval_env_config("vee_rotation", pid.action_mode, turbulence_sigma_mps=0.0), [7200000001])
    assert not m["reconfig_success"]


def test_the_leader_drops_back_so_that_no_uav_outruns_the_reference():
    """The lead is handed over by vehicle 0 slowing (Scenario.leader_schedule), not by the others outrunning it:
    vehicle 1 (the new apex) holds its place along the track and its height in the reference's frame, every UAV's
    demanded ground speed stays at or below the 25 m/s reference at every time (the others only slow or hold), the
    leader drops back 6 spans on the forward phase's blend, and it starts and ends at the reference's speed."""
    sc = get_scenario("vee_rotation")
    t = np.arange(0.0, sc.duration_s + 1e-9, 0.01)
    ref_pos, ref_vel = sc.reference(t)
    base = np.stack([sc.airspeed_mps * t, np.zeros_like(t), np.full_like(t, -sc.altitude_m)], axis=-1)
    lead_off = ref_pos - base
    np.testing.assert_allclose(lead_off[:, 1], 0.0, atol=0)
    assert lead_off[-1, 0] == pytest.approx(-6.0 * SPAN) and lead_off[0, 0] == 0.0
    np.testing.assert_allclose(ref_vel[[0, -1]], [[sc.airspeed_mps, 0, 0]] * 2, atol=1e-12)
    speeds = [ref_vel[:, 0]] + [ref_vel[:, 0] + s.offset_and_rate(t)[1][:, 0] for s in sc.slots]
    assert max(np.max(v) for v in speeds) <= sc.airspeed_mps + 1e-9
    assert np.min(ref_vel[:, 0]) == pytest.approx(sc.airspeed_mps - 0.5 * np.pi * 6.0 * SPAN / 25.0, rel=1e-4)
    v1 = lead_off + sc.slots[0].offset_and_rate(t)[0]  # vehicle 1 from the reference point
    np.testing.assert_allclose(v1[:, [0, 2]], np.broadcast_to(v1[0, [0, 2]], (len(t), 2)), atol=1e-9)


def test_the_compiled_reference_and_schedule_features_equal_the_scenarios():
    """The kernel's vehicle-0 path with the leader's schedule (guidance.reference_path) equals Scenario.reference,
    and the observed schedule features of every UAV, vehicle 0's own included, equal the numpy definition
    (tests/oracles), over the whole episode."""
    from formation_env.sim.guidance import reference_path, schedule_features
    from formation_env.sim.params import scenario_arrays
    from tests.oracles.env_step import slot_schedule_features

    sc = get_scenario("vee_rotation")
    arr = scenario_arrays(sc, False)
    assert arr.slot_keyframes[0] == len(sc.leader_schedule.keyframes)
    times = np.arange(0.0, sc.duration_s + 1.0, 0.37)
    jitter = np.random.default_rng(4).normal(0.0, 0.3, (5, 3))
    jitter[0] = 0.0
    ref = slot_schedule_features(sc, times, np.broadcast_to(jitter, (len(times), 5, 3)))
    pos, vel = np.empty(3), np.empty(3)
    for k, t in enumerate(times):
        reference_path(arr, t, np.zeros(3), np.zeros(5), pos, vel)
        p_ref, v_ref = sc.reference(t)
        np.testing.assert_allclose(pos, p_ref, rtol=0, atol=1e-9)
        np.testing.assert_allclose(vel, v_ref, rtol=0, atol=1e-12)
        out = np.zeros((5, 10))
        schedule_features(arr, t, jitter, out)
        np.testing.assert_allclose(out, ref[k], rtol=0, atol=1e-12)
    assert np.any(ref[:, 0, 3] != 0.0)  # vehicle 0 observes its own drop-back


def test_a_leader_schedule_is_checked():
    """Bad leader schedules get one clear error: a lateral offset, and randomised leader manoeuvres beside it."""
    from formation_env.scenarios import Scenario
    from formation_env.sim.config import Randomisation

    with pytest.raises(ValueError, match="lateral offset 0"):
        Scenario("x", "x", 10.0, slots=(SlotSchedule(),), leader_schedule=SlotSchedule(((0.0, (0.0, 0.5, 0.0)),)))
    with pytest.raises(ValueError, match="leader_schedule"):
        formation_env.parallel_env("vee_rotation", randomisation=Randomisation(leader_speed_mps=1.0))


def test_an_air_relative_leaders_reference_moves_with_the_air():
    """vee_rotation's leader is air-relative (Scenario.leader_air_relative): its demanded velocity is the still-air
    reference's plus the north and down wind at it, and its demanded position the still-air reference's plus the
    air's integrated displacement (backward Euler on the 50 Hz grid), east as the still-air path; in calm air exactly
    the still-air path."""
    from formation_env.sim import Simulation
    from formation_env.sim.config import Randomisation

    sc = get_scenario("vee_rotation")
    assert sc.leader_air_relative
    for sigma in (1.0, 0.0):
        sim = Simulation(EnvConfig(scenario="vee_rotation", action_mode="setpoints", learning="all",
                                   randomisation=Randomisation(turbulence_sigma_mps=sigma)), batch_size=2)
        sim.reset(seeds=[5, 6])
        for k in range(40):
            sim.step(np.zeros((2, 5, 4)))
            t = sim.time_s
            ref_pos, ref_vel = sc.reference(t[0])
            wind = sim.state.steady_wind + sim.state.gust_ned[:, 0]
            carried = sim.state.reference_position
            for ax in (0, 2):
                np.testing.assert_allclose(sim.state.velocity_demand[:, 0, ax], ref_vel[ax] + wind[:, ax], rtol=0, atol=1e-12)
                np.testing.assert_allclose(sim.state.position_demand[:, 0, ax], ref_pos[ax] + carried[:, ax], rtol=0,
                                           atol=1e-9)
            np.testing.assert_allclose(sim.state.position_demand[:, 0, 1], ref_pos[1], rtol=0, atol=1e-12)
            np.testing.assert_allclose(sim.state.velocity_demand[:, 0, 1], ref_vel[1], rtol=0, atol=1e-12)
        if sigma == 0.0:
            assert np.all(carried == 0.0)
        else:  # ~8 s in a 1 m/s field: the air has carried the reference a measurable distance
            assert np.all(np.abs(carried[:, [0, 2]]) > 0.05), carried


def test_the_leader_reference_is_an_env_option():
    """EnvConfig.leader_reference overrides the scenario's: "ground" flies vee_rotation's leader on the still-air path
    (in turbulence), "air" carries the thesis vee's, "ground" gives close_formation and the N-UAV tasks (air-relative
    since issues 24 and 25) the thesis's leader back; a bad value is one clear error naming it."""
    from formation_env.sim import Simulation
    from formation_env.sim.config import Randomisation

    rnd = Randomisation(turbulence_sigma_mps=1.0)
    sim = Simulation(EnvConfig(scenario="vee_rotation", learning="all", leader_reference="ground", randomisation=rnd))
    sim.reset(seeds=[3])
    for _ in range(20):
        sim.step(np.zeros((1, 5, 4)))
    ref_pos, ref_vel = get_scenario("vee_rotation").reference(sim.time_s[0])
    np.testing.assert_allclose(sim.state.position_demand[0, 0], ref_pos, rtol=0, atol=1e-9)
    np.testing.assert_allclose(sim.state.velocity_demand[0, 0], ref_vel, rtol=0, atol=1e-12)
    air = Simulation(EnvConfig(scenario="vee", leader_reference="air", randomisation=rnd))
    assert air.leader_air_relative and not Simulation(EnvConfig(scenario="vee")).leader_air_relative
    for name in ("close_formation", "echelon3", "vee5", "vee9"):
        assert Simulation(EnvConfig(scenario=name)).leader_air_relative
        assert not Simulation(EnvConfig(scenario=name, leader_reference="ground")).leader_air_relative
    with pytest.raises(ValueError, match="leader_reference must be None.*'sky'"):
        EnvConfig(scenario="vee5", leader_reference="sky")


def test_the_air_relative_leaders_displacement_integrates_the_wind_step_by_step():
    """The integration law itself: deciding every physics step (50 Hz), the air-relative leader's accumulated
    displacement grows each step by dt times the north / down wind at the state the step ends in (backward Euler on
    the physics grid), to the last bit, and its east component stays 0."""
    from formation_env.sim import Simulation
    from formation_env.sim.config import Randomisation

    sim = Simulation(EnvConfig(scenario="vee_rotation", learning="all", control_hz=50.0,
                               randomisation=Randomisation(turbulence_sigma_mps=1.0, steady_wind_mps=3.0)),
                     batch_size=2)
    sim.reset(seeds=[8, 9])
    before = sim.state.reference_position.copy()
    for _ in range(30):
        sim.step(np.zeros((2, 5, 4)))
        wind = sim.state.steady_wind + sim.state.gust_ned[:, 0]
        after = sim.state.reference_position.copy()
        for ax in (0, 2):
            assert np.array_equal(after[:, ax], before[:, ax] + 0.02 * wind[:, ax])
        assert np.all(after[:, 1] == 0.0)
        before = after
    assert np.all(np.abs(before[:, 0]) > 0.0)
