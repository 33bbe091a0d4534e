"""How the learning task is posed: frozen turbulence in the env, what actions can move, observation
scaling, the reward's shape, the slot schedule the agents see, the centralised state, pid_formation."""

import numpy as np
import pytest

import formation_env
from formation_env.envs import EnvConfig, Randomisation, RewardWeights
from formation_env.envs.observations import group_sizes, slog, to_dict
from formation_env.envs.rewards import huber
from formation_env.rollout import ZeroPolicy
from tests.oracles.env_step import reward_terms

B = 2.9


def _obs_groups(env, agent="uav_1"):
    allobs = env.sim.output.observation[0]
    return to_dict(allobs[env.agent_indices.index(int(agent[4:]))], env.sim.n_vehicles)


# ------------------------------------------------------------------ turbulence in the env
def _gust_series(field, seed=3, steps=300):
    env = formation_env.parallel_env("formation_keeping", action_mode="setpoints", turbulence_field=field,
                                     randomisation=Randomisation(turbulence_sigma_mps=1.0))
    _, infos = env.reset(seed=seed)
    out = [[infos["uav_1"]["gust_ned_mps"]]]
    zero = {a: np.zeros(4, np.float32) for a in env.agents}
    lead = []
    for _ in range(steps):
        _, _, _, _, infos = env.step(zero)
        out.append([infos["uav_1"]["gust_ned_mps"]])
        lead.append(env.sim.state.gust_ned[0, 0].copy())
    return np.array(out)[1:, 0], np.array(lead)


def test_frozen_field_is_the_default_and_neighbours_feel_nearly_the_same_gusts():
    assert EnvConfig().turbulence_field == "von_karman"  # issue 23: the spectral field; "frozen" = "lanes"
    follower, leader = _gust_series("frozen")
    assert follower.shape == (300, 3) and np.all(np.isfinite(follower))
    # RMS of the gust difference / sigma: ~0.26-0.29 at the thesis slot (a little more as the follower
    # drifts from it); independent streams: 1.41
    diff = np.sqrt(np.mean((follower - leader) ** 2))
    assert diff < 0.5
    # independent streams (expected 1.41; three 30 s episodes, since the lanes' correlation time is ~20 s)
    pairs = [_gust_series("independent", seed=s) for s in (3, 4, 5)]
    f_ind, l_ind = np.concatenate([p[0] for p in pairs]), np.concatenate([p[1] for p in pairs])
    assert np.sqrt(np.mean((f_ind - l_ind) ** 2)) > 1.0
    with pytest.raises(ValueError, match="turbulence_field"):
        EnvConfig(turbulence_field="mann")


def test_frozen_turbulence_episodes_replay_bit_for_bit():
    a, _ = _gust_series("frozen", seed=9, steps=50)
    b, _ = _gust_series("frozen", seed=9, steps=50)
    c, _ = _gust_series("frozen", seed=10, steps=50)
    assert np.array_equal(a, b) and not np.array_equal(a, c)


# ------------------------------------------------------------------ actions and the steady state
def _steady_along_track_error(mode, action, seconds=30.0):
    from formation_env.sim.config import Randomisation

    env = formation_env.parallel_env("formation_keeping", action_mode=mode, learning="followers", duration_s=seconds + 1.0,
                                     randomisation=Randomisation())  # calm air, no start jitter: the steady state
    env.reset(seed=0)
    a = {"uav_1": np.asarray(action, np.float32)}
    series = []
    for _ in range(int(seconds * 10)):
        _, _, _, _, info = env.step(a)
        e = info["uav_1"]["slot_error_ned_m"]
        series.append(e[0])  # the slot frame is north-aligned here (straight leader heading north)
    return np.array(series)


def test_a_constant_setpoint_action_moves_the_steady_state_by_its_offset():
    zero = _steady_along_track_error("setpoints", [0, 0, 0, 0])
    ahead = _steady_along_track_error("setpoints", [0.4, 0, 0, 0])  # 0.4 x 5 m ahead of the slot
    assert abs(zero[-50:].mean()) < 0.1
    assert ahead[-50:].mean() == pytest.approx(2.0, abs=0.2)
    faster = _steady_along_track_error("setpoints", [0, 0, 0, 0.25])  # +0.5 m/s speed demand
    assert faster[-50:].mean() == pytest.approx(0.5 / 0.125, rel=0.15)  # P-only along-track loop: dV / Kp_X


def test_a_constant_surface_action_moves_the_steady_state():
    trim = _steady_along_track_error("surfaces", [0, 0, 0, 0], seconds=20.0)
    throttle = _steady_along_track_error("surfaces", [0, 0, 0, 0.1], seconds=20.0)
    assert abs(throttle[-1] - trim[-1]) > 5.0  # open loop: nothing pulls the follower back


def test_residual_actions_are_washed_out_by_the_pid_integrators():
    """Residual mode is the fast-disturbance mode (docs/env.md): a constant residual moves the
    follower at first, and the PID's speed integrator removes it (measured washout)."""
    res = _steady_along_track_error("residual", [0, 0, 0, 1.0], seconds=30.0)  # +0.2 throttle held
    peak = np.max(np.abs(res))
    assert peak > 0.3
    assert abs(res[-10:].mean()) < 0.2 * peak


# ------------------------------------------------------------------ observation scaling
def test_slot_errors_are_signed_log_scaled_and_do_not_saturate():
    env = formation_env.parallel_env("formation_keeping", action_mode="setpoints")
    env.reset(seed=0)
    eng = env.sim
    seen = []
    for along in (-300.0, -30.0, -1.0, 0.1, 30.0, 300.0):
        eng.aircraft[0, 1, 10:13] = eng.position_demand[0, 1] + np.array([along, 0.0, 0.0])
        eng.observe()
        g = _obs_groups(env)
        assert g["slot_position_error"][0] == pytest.approx(slog(along, 1.0), rel=1e-9, abs=1e-9)
        seen.append(g["slot_position_error"][0])
    assert np.all(np.diff(seen) > 0.4)  # 30 m and 300 m stay far apart
    assert abs(seen[0]) < 10.0


def test_reconfiguration_agents_see_the_slot_schedule():
    env = formation_env.parallel_env("reconfiguration", action_mode="setpoints")
    env.reset(seed=0)
    g = _obs_groups(env)["slot_schedule"]
    assert np.allclose(g[0:3], [-3.0, 1.0, 0.2]) and np.allclose(g[3:6], 0.0)
    assert np.allclose(g[6:9], 0.0) and g[9] == pytest.approx(1.0)  # next keyframe (10 s) is the same offset
    zero = {a: np.zeros(4, np.float32) for a in env.agents}
    for _ in range(120):  # t = 12 s: descending between the keyframes at 10 s and 15 s
        env.step(zero)
    g = _obs_groups(env)["slot_schedule"]
    assert 0.2 < g[2] < 1.0 and g[5] > 0.0  # offset moving down, rate positive (down)
    assert np.allclose(g[6:9], [0.0, 0.0, 1.0 - g[2]]) and g[9] == pytest.approx(0.3)
    leader = to_dict(env.sim.output.observation[0, 0], 2)["slot_schedule"]
    assert np.allclose(leader[:9], 0.0) and leader[9] == 1.0


def test_state_space_matches_state():
    env = formation_env.parallel_env("echelon", action_mode="setpoints", learning="followers")
    env.reset(seed=0)
    s = env.state()
    assert env.state_space.shape == s.shape == (3 * sum(group_sizes(3).values()),)
    assert env.state_space.contains(s)


# ------------------------------------------------------------------ reward shape
def _terms(error, prev=None, sep=10.0, w=RewardWeights()):
    e = np.atleast_1d(np.asarray(error, float))[:, None]
    p = e if prev is None else np.atleast_1d(np.asarray(prev, float))[:, None]
    z = np.zeros(e.shape + (4,))
    return reward_terms(w, e, p, z, z, np.zeros_like(e), np.full_like(e, sep), np.zeros_like(e, bool),
                        np.zeros_like(e, bool), 0.5 * B, B)


def test_slot_reward_decreases_with_the_error_everywhere():
    err = np.concatenate([np.linspace(0, 10, 101), np.geomspace(10.5, 4000, 60)])
    r = _terms(err)["slot"][:, 0]
    assert np.all(np.diff(r) < 0)
    h = huber(err / 5.0)
    assert np.allclose(r, -h)
    # quadratic near the slot, linear far from it
    assert r[10] == pytest.approx(-0.5 * (1.0 / 5.0) ** 2)
    assert _terms([1000.0])["slot"][0, 0] - _terms([2000.0])["slot"][0, 0] == pytest.approx(1000.0 / 5.0)


def test_progress_term_is_potential_based():
    w = RewardWeights()
    errs = np.array([30.0, 20.0, 12.0, 13.0, 5.0, 2.0])
    f = [_terms([b], [a])["progress"][0, 0] for a, b in zip(errs, errs[1:])]
    disc = sum(w.shaping_gamma ** t * x for t, x in enumerate(f))
    phi = -huber(errs / w.slot_scale_m)
    assert disc == pytest.approx(w.shaping_gamma ** (len(f)) * phi[-1] - phi[0], rel=1e-12)
    assert f[0] > 0 and f[2] < 0  # closing in pays, drifting away costs


def test_separation_barrier_acts_before_the_collision_radius():
    seps = np.array([1.46, 2.0, 2.9, 3.4, 3.5, 10.0])
    r = np.array([_terms([0.0], sep=s)["separation"][0, 0] for s in seps])
    assert np.all(np.diff(r) >= 0) and r[0] < -4.5 and r[-2] == 0.0 and r[-1] == 0.0
    assert r[1] < 0  # active between the collision radius (1.45 m) and 1.2 spans (3.48 m)


# ------------------------------------------------------------------ pid_formation
def test_pid_formation_holds_the_slot_in_calm_air_and_beats_the_thesis_pid_in_gusts():
    from agents.pid_formation import PIDFormation
    from train.evaluation.evaluate import eval_env_config, run_episodes, summarise

    calm = eval_env_config("formation_keeping", "setpoints", turbulence_sigma_mps=0.0, duration_s=30.0)
    agent = PIDFormation()
    s = summarise(run_episodes(agent, calm, [1]))
    assert s["max_slot_error_m"] < 0.1
    seeds = list(range(100, 106))  # training-range seeds, not the held-out ones
    gusty = eval_env_config("formation_keeping", "setpoints", duration_s=40.0)
    pf = summarise(run_episodes(agent, gusty, seeds))["rms_slot_error_m"]
    pid = summarise(run_episodes(ZeroPolicy(),
                                 eval_env_config("formation_keeping", "residual", duration_s=40.0), seeds))
    assert pf < 0.7 * pid["rms_slot_error_m"]


def test_ending_the_episode_never_pays():
    """A collision charges the slot cost still to come: with 300 decisions left at 30 m, colliding costs
    more than flying on at that error."""
    w = RewardWeights()
    e = np.array([[30.0]])
    z = np.zeros((1, 1, 4))
    hit = reward_terms(w, e, e, z, z, np.zeros((1, 1)), np.ones((1, 1)), np.ones((1, 1), bool), np.zeros((1, 1), bool),
                       0.5 * B, B, remaining_decisions=np.array([300.0]))
    stay = -w.slot * huber(30.0 / w.slot_scale_m)
    assert hit["collision"][0, 0] == pytest.approx(-(w.collision + 300 * w.slot * huber(30.0 / w.slot_scale_m)))
    assert hit["collision"][0, 0] < 300 * stay


def test_a_diverged_uav_does_not_break_the_frozen_field():
    """The field is read after every physics step; a UAV whose state went non-finite in that step (its
    episode ends on that step's envelope status) must not raise or poison the other formations."""
    env = formation_env.parallel_env("formation_keeping", action_mode="setpoints", learning="followers",
                                     randomisation=Randomisation(turbulence_sigma_mps=1.0))
    env.reset(seed=0)
    eng = env.sim
    eng.aircraft[0, 1, 10:13] = np.nan  # as if the follower had diverged in the last physics step
    eng.observe()
    assert np.all(np.isfinite(eng.state.gust_ned)) and np.all(np.isfinite(eng.info.gust_ned_mps))
    assert np.all(np.isfinite(env.sim.output.observation))
    obs, rew, term, trunc, _ = env.step({a: np.zeros(4, np.float32) for a in env.agents})
    assert term["uav_1"] and np.isfinite(rew["uav_1"]) and np.all(np.isfinite(obs["uav_1"]))


# ------------------------------------------------------------------ the hold phase (success window) of a moving slot
def test_hold_phase_follows_the_slot_schedule():
    from formation_env.scenarios import get_scenario
    from formation_env.sim.params import hold_remaining_decisions

    sc = get_scenario("reconfiguration")  # last keyframe at 50 s
    np.testing.assert_array_equal(hold_remaining_decisions(sc, 60.0, 10.0), [-1.0, 100.0])
    np.testing.assert_array_equal(hold_remaining_decisions(sc, 52.0, 5.0), [-1.0, 10.0])
    np.testing.assert_array_equal(hold_remaining_decisions(sc, 40.0, 10.0), [-1.0, 0.0])  # never reached: last decision only
    fixed = get_scenario("formation_keeping")  # a fixed slot: the whole episode
    np.testing.assert_array_equal(hold_remaining_decisions(fixed, 60.0, 10.0), [-1.0, 600.0])


def test_hold_cost_is_charged_after_the_last_keyframe_only_and_matches_the_oracle():
    """Reconfiguration shortened to 52 s, the thesis PID flying the schedule: no hold cost before 50 s; after,
    the step ``hold`` exactly at the decisions the follower is at least the radius from its slot (a radius
    of 0.52 span: the PID closes from 1.65 to 1.39 m over these 2 s, so that both occur), as the numpy definition says."""
    from formation_env.sim import Simulation

    w = RewardWeights(hold=2.0, hold_radius_b=0.52)
    cfg = EnvConfig(scenario="reconfiguration", action_mode="setpoints", learning="followers", duration_s=52.0,
                    reward=w)
    sim = Simulation(cfg, batch_size=1)
    sim.reset(seeds=[3])
    hold, err, left = [], [], []
    for k in range(520):
        sim.step(np.zeros((1, 1, 4)))
        out = sim.output
        hold.append(out.reward_terms[0, 1, 9])
        err.append(out.slot_error_m[0, 1])
        left.append(519 - k)
    hold, err, left = np.array(hold), np.array(err), np.array(left, float)
    assert np.all(hold[:499] == 0.0)  # decisions ending before 50 s
    late = left <= 20
    assert np.any(hold[late] == -2.0) and np.any(hold[late] == 0.0)
    z = np.zeros((520, 1))
    ref = reward_terms(w, err[:, None], err[:, None], z[..., None].repeat(4, -1), z[..., None].repeat(4, -1), z,
                       np.full((520, 1), 100.0), np.zeros((520, 1), bool), np.zeros((520, 1), bool), 0.5 * B, B,
                       remaining_decisions=left, hold_remaining=[20.0])
    np.testing.assert_array_equal(hold, ref["hold"][:, 0])


def test_ending_the_episode_never_avoids_the_hold_costs():
    """The compiled reward against its oracle on random inputs, collisions and crashes included: a collision
    charges (terminal_forfeit times) the hold cost of every hold-phase decision left, so ending never pays."""
    from formation_env.scenarios import get_scenario
    from formation_env.sim.observe import REWARD_TERMS, reward_formation
    from formation_env.sim.params import RewardParams

    sc = get_scenario("reconfiguration")
    w = RewardWeights(hold=1.5, hold_radius_b=1.0, terminal_forfeit=0.5)
    p = RewardParams.from_config(w, sc, 0.5, duration_s=60.0, control_hz=10.0)
    rng = np.random.default_rng(0)
    for remaining in (300.0, 100.0, 37.0, 0.0):
        for collided in (False, True):
            err = rng.uniform(0.0, 6.0, 2)
            act, prev = rng.uniform(-1, 1, (2, 4)), rng.uniform(-1, 1, (2, 4))
            crashed = np.array([False, bool(rng.integers(2))])
            terms = np.zeros((2, len(REWARD_TERMS)))
            reward_formation(p, err, err, act, prev, np.zeros(2), np.full(2, 50.0), collided, crashed, remaining,
                             np.zeros(2), terms)
            ref = reward_terms(w, err[None], err[None], act[None], prev[None], np.zeros((1, 2)), np.full((1, 2), 50.0),
                               np.full((1, 2), collided), crashed[None], 0.5 * B, B,
                               remaining_decisions=np.array([remaining]), hold_remaining=p.hold_remaining)
            for j, key in enumerate(REWARD_TERMS):
                np.testing.assert_allclose(terms[:, j], ref[key][0], rtol=1e-12, atol=1e-15, err_msg=key)
    hit = reward_terms(w, np.array([[5.0]]), np.array([[5.0]]), np.zeros((1, 1, 4)), np.zeros((1, 1, 4)), np.zeros((1, 1)),
                       np.ones((1, 1)), np.ones((1, 1), bool), np.zeros((1, 1), bool), 0.5 * B, B,
                       remaining_decisions=np.array([60.0]), hold_remaining=[100.0])
    forfeit = 0.5 * w.slot * huber(5.0 / w.slot_scale_m) * 60
    assert hit["collision"][0, 0] == pytest.approx(-(w.collision + forfeit + 0.5 * 60 * 1.5))
