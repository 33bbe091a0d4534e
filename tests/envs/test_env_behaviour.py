"""Determinism, the PID baseline through the env, bad input, and a fuzz test."""

import numpy as np
import pytest

import formation_env
from formation_env.runs.runner import run_scenario
from formation_env.envs import EnvConfig, Randomisation
from formation_env.scenarios import scenario_names

RANDOM = Randomisation(initial_offset_m=2.0, slot_offset_b=0.1, steady_wind_mps=4.0, turbulence_sigma_mps=1.0,
                       leader_turn_deg=20.0, leader_climb_m=10.0, leader_speed_mps=2.0)


def _randomisation(scenario):
    """RANDOM, less the leader's random manoeuvre where the scenario sets its leader's reference itself (vee_rotation:
    a drop-back schedule, carried by the air), which refuses one."""
    from dataclasses import replace

    from formation_env.scenarios import get_scenario

    sc = get_scenario(scenario)
    if sc.leader_schedule is not None or sc.leader_air_relative:
        return replace(RANDOM, leader_turn_deg=0.0, leader_climb_m=0.0, leader_speed_mps=0.0)
    return RANDOM


def _rollout(scenario, seed, n_steps, mode):
    env = formation_env.parallel_env(scenario, action_mode=mode, randomisation=_randomisation(scenario))
    rng = np.random.default_rng(seed)
    obs, _ = env.reset(seed=seed)
    trace = []
    episode = 0
    for _ in range(n_steps):
        if not env.agents:
            episode += 1
            obs, _ = env.reset(seed=seed + episode)
        act = {a: rng.uniform(-1, 1, 4).astype(np.float32) for a in env.agents}
        obs, rew, term, trunc, info = env.step(act)
        trace.append((np.concatenate([obs[a] for a in sorted(obs)]), np.array([rew[a] for a in sorted(rew)]),
                      env.sim.aircraft.copy()))
    return trace


@pytest.mark.parametrize("scenario", scenario_names())
def test_seeded_1000_step_replay_is_bit_exact(scenario):
    # residual/setpoints exercise the PID path; the larger formations use the compiled surfaces path
    mode = {"tracking": "setpoints", "echelon": "surfaces", "vee": "surfaces"}.get(scenario, "residual")
    a = _rollout(scenario, 11, 1000, mode)
    b = _rollout(scenario, 11, 1000, mode)
    for (oa, ra, sa), (ob, rb, sb) in zip(a, b):
        assert np.array_equal(oa, ob) and np.array_equal(ra, rb) and np.array_equal(sa, sb)
    c = _rollout(scenario, 12, 50, mode)
    assert not all(np.array_equal(x[2], y[2]) for x, y in zip(a[:50], c))  # another seed differs


def test_a_seeded_reset_also_seeds_the_later_unseeded_resets():
    # RLlib's env runners seed only the first reset; the episodes after it must still replay.
    def episode_starts(seed):
        env = formation_env.parallel_env("formation_keeping", randomisation=Randomisation(initial_offset_m=2.0))
        starts = [env.reset(seed=seed)[0]["uav_1"]]
        starts += [env.reset()[0]["uav_1"] for _ in range(2)]
        return starts

    a, b, c = episode_starts(5), episode_starts(5), episode_starts(6)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    assert not np.array_equal(a[1], a[2])          # later episodes differ from each other
    assert not np.array_equal(a[1], c[1])          # and from another seed's
    with pytest.raises(ValueError, match="seed"):
        formation_env.parallel_env("formation_keeping").reset(seed=-1)


@pytest.mark.parametrize("scenario", ["formation_keeping", "reconfiguration"])
def test_pid_through_the_env_reproduces_the_runner(scenario):
    """Zero residual = the PID baseline: the env's trajectory equals the scenario runner's exactly."""
    # calm air and no start jitter (the task's benchmark draws both), as the runner flies
    env = formation_env.parallel_env(scenario, action_mode="residual", duration_s=30.0, randomisation=Randomisation())
    env.reset(seed=0)
    run = run_scenario(scenario, duration_s=30.0)
    k = 0
    while env.agents:
        env.step({a: np.zeros(4, np.float32) for a in env.agents})
        k += env.substeps
        if k < run.time.size:
            assert np.array_equal(env.sim.aircraft[0, :, 10:13], run.h["position_ned"][k]), k
            assert np.array_equal(env.sim.induced[0], run.h["induced_wind_ned"][k - 1]), k
    assert k >= run.time.size - 1


def test_bad_input_raises_clear_errors():
    env = formation_env.parallel_env("formation_keeping")
    env.reset(seed=0)
    good = {a: np.zeros(4, np.float32) for a in env.agents}
    with pytest.raises(ValueError, match="shape"):
        env.step({**good, "uav_1": np.zeros(3)})
    with pytest.raises(ValueError, match="NaN or inf"):
        env.step({**good, "uav_1": np.array([0, np.nan, 0, 0])})
    with pytest.raises(ValueError, match="NaN or inf"):
        env.step({**good, "uav_0": np.array([0, 0, np.inf, 0])})
    with pytest.raises(ValueError, match="uav_7"):
        env.step({**good, "uav_7": np.zeros(4)})
    with pytest.raises(ValueError, match="missing"):
        env.step({"uav_0": np.zeros(4)})
    with pytest.raises(ValueError, match="unknown scenario"):
        formation_env.parallel_env("barrel_roll")
    with pytest.raises(ValueError, match="action_mode"):
        formation_env.parallel_env("formation_keeping", action_mode="joystick")
    with pytest.raises(TypeError, match="wingspan"):  # unknown option: TypeError, as for any unexpected keyword
        formation_env.parallel_env("formation_keeping", wingspan=3)
    with pytest.raises(ValueError, match="control_hz"):
        formation_env.parallel_env("formation_keeping", control_hz=7.0)
    with pytest.raises(ValueError, match="wake_update_every"):
        formation_env.parallel_env("formation_keeping", wake_update_every=0)
    with pytest.raises(ValueError, match="turbulence_sigma_mps"):
        Randomisation(turbulence_sigma_mps=-1.0)
    with pytest.raises(ValueError, match="learning"):
        EnvConfig(learning=(5,)) and formation_env.parallel_env("formation_keeping", learning=(5,))
    with pytest.raises(ValueError, match="followers"):
        formation_env.parallel_env("gust", learning="followers")


def test_fuzz_random_and_extreme_actions_never_emit_non_finite():
    rng = np.random.default_rng(5)
    for episode, mode in enumerate(["surfaces", "surfaces", "residual", "setpoints"] * 2):
        env = formation_env.parallel_env("reconfiguration", action_mode=mode, randomisation=RANDOM, duration_s=30.0)
        obs, _ = env.reset(seed=episode)
        while env.agents:
            kind = rng.integers(3)
            act = {a: (rng.choice([-1.0, 1.0], 4) if kind == 0 else rng.uniform(-1, 1, 4) * (5.0 if kind == 1 else 1.0))
                   for a in env.agents}
            obs, rew, term, trunc, info = env.step(act)
            for a in obs:
                assert np.all(np.isfinite(obs[a])) and env.observation_space(a).contains(obs[a])
                assert np.isfinite(rew[a])
        assert all(term.values()) or all(trunc.values())


def test_collision_terminates_every_agent_with_the_penalty():
    env = formation_env.parallel_env("formation_keeping", action_mode="residual")
    env.reset(seed=0)
    # Put the follower 1 m behind the leader's CG (less than 0.5 span = 1.45 m).
    env.sim.aircraft[0, 1, 10:13] = env.sim.aircraft[0, 0, 10:13] + np.array([-1.0, 0.0, 0.0])
    obs, rew, term, trunc, info = env.step({a: np.zeros(4, np.float32) for a in env.agents})
    assert all(term.values()) and not any(trunc.values()) and env.agents == []
    for a in ("uav_0", "uav_1"):
        assert info[a]["collision"] and info[a]["reward_collision"] <= -50.0
        assert info[a]["min_separation_m"] < 1.45
        assert np.all(np.isfinite(obs[a]))


def test_truncation_at_the_time_limit():
    env = formation_env.parallel_env("formation_keeping", action_mode="residual", duration_s=3.0)
    env.reset(seed=0)
    n = 0
    while env.agents:
        obs, rew, term, trunc, info = env.step({a: np.zeros(4, np.float32) for a in env.agents})
        n += 1
    assert n == 30 and all(trunc.values()) and not any(term.values())
    assert info["uav_1"]["time_s"] == pytest.approx(3.0)


def test_compiled_observations_equal_the_numpy_definition():
    """The decision step's compiled observation equals the readable numpy definition (tests/oracles),
    slot schedule features included, along a randomised episode with every action mode's PID state."""
    from tests.oracles.env_step import build_observations_reference, slot_schedule_features

    env = formation_env.parallel_env("reconfiguration", action_mode="residual", randomisation=RANDOM)
    env.reset(seed=4)
    rng = np.random.default_rng(1)
    for _ in range(40):
        act = {a: rng.uniform(-1, 1, 4) for a in env.agents}
        obs, *_ = env.step(act)
        e = env.sim
        prev = e.state.previous_action
        np.testing.assert_allclose(prev[0, 1], act["uav_1"], rtol=0, atol=1e-6)
        sched = slot_schedule_features(e.scenario, e.time_s, e.state.slot_jitter)
        ref = build_observations_reference(e.aircraft, e.induced, e.omega, e.ambient_wind(), np.zeros_like(e.induced),
                                           e.position_demand, e.velocity_demand, prev, sched, e.state.controller,
                                           e.scenario.airspeed_mps, e.scenario.altitude_m)
        np.testing.assert_allclose(env.sim.output.observation, ref, rtol=0, atol=1e-12)
        np.testing.assert_allclose(obs["uav_1"], ref[0, 1].astype(np.float32), rtol=0, atol=0)


def test_leader_manoeuvre_turns_climbs_and_changes_speed_as_drawn():
    """The randomised reference path: after the manoeuvre the demanded velocity has the drawn
    heading change, zero climb rate and the drawn speed change; the path is its integral."""
    env = formation_env.parallel_env("formation_keeping", action_mode="residual", duration_s=40.0,
                                     randomisation=Randomisation(leader_turn_deg=30.0, leader_climb_m=10.0,
                                                                 leader_speed_mps=2.0))
    env.reset(seed=7)
    eng = env.sim
    t0, dpsi, dh, dv = eng.state.manoeuvre[0, :4]  # [4]: the base speed offset (0 here)
    assert 0.0 <= t0 <= 20.0 and abs(dpsi) > 0 and abs(dh) > 0 and abs(dv) > 0
    while env.agents:
        env.step({a: np.zeros(4, np.float32) for a in env.agents})
    vd = eng.velocity_demand[0, 0]
    assert np.arctan2(vd[1], vd[0]) == pytest.approx(dpsi, abs=1e-12)
    assert np.hypot(vd[0], vd[1]) == pytest.approx(25.0 + dv, abs=1e-12)
    assert vd[2] == 0.0
    # Altitude of the reference changed by the drawn amount (within one physics step of climb).
    assert -eng.state.reference_position[0, 2] - 1000.0 == pytest.approx(dh, abs=1.5 * eng.dt + 1e-9)
