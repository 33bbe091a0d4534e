"""agents.separation_guard: the keeper's guard as a filter on set-point actions (zone, signs, the speed
excess sent along the track, bounds, pass-through outside the zone) and its training wrapper."""

import numpy as np
import pytest

from agents.separation_guard import GuardGains, SeparationGuard, guard_terms
from formation_env.control.gains import TrackerGains
from formation_env.envs.observations import group_sizes, observation_size, slog

SLOT_LEADER_M = (5.8, -2.8, 0.0)  # the leader from a follower in close_formation's slot (slot frame, m)


def _obs(err=(0.0, 0.0, 0.0), leader=SLOT_LEADER_M, n=1):
    """2-UAV observations with the slot error ``err`` (follower minus slot, m) and the leader at ``leader`` (m)
    from the follower, both slot frame."""
    obs = np.zeros((n, observation_size(2)))
    k = 0
    for name, size in group_sizes(2).items():
        if name == "slot_position_error":
            obs[:, k:k + size] = slog(np.asarray(err, float), 1.0)
        elif name == "neighbours":
            obs[:, k:k + 3] = slog(np.asarray(leader, float), 3.0)
        k += size
    return obs


def _overtaking(ahead_m, lateral_m=-2.8):
    """The follower ``5.8 - ahead_m`` m ahead of its slot, the leader ``ahead_m`` ahead of it."""
    return _obs(err=(5.8 - ahead_m, 0.0, 0.0), leader=(ahead_m, lateral_m, 0.0))


def test_outside_the_zone_actions_pass_unchanged():
    rng = np.random.default_rng(0)
    a = rng.uniform(-1.2, 1.2, size=(5, 4)).astype(np.float32)  # even out-of-range actions: the env clips them
    obs = np.concatenate([_obs(), _overtaking(5.5), _obs(leader=(30.0, -2.8, 0.0)), _obs(leader=(3.0, -6.0, 0.0)),
                          _obs(leader=(-3.0, -2.8, 0.0))])
    out = SeparationGuard().filter(obs, a)
    assert out.dtype == a.dtype
    np.testing.assert_array_equal(out, a)  # in the slot; 0.3 m ahead of it; far; out of line; behind


def test_inside_the_zone_the_target_moves_away_and_down_and_the_speed_drops():
    g, kp = GuardGains(), TrackerGains().Kp_alongtrack
    a = np.zeros((1, 4))
    close = SeparationGuard().filter(_overtaking(4.0), a)[0]
    depth = g.guard_m - 4.0
    ramp = (depth / g.guard_m) ** 2
    assert close[1] == pytest.approx(g.lateral_m * ramp / 5.0)  # the leader to port: starboard
    assert close[2] == pytest.approx(g.vertical_m * ramp / 5.0)  # down
    assert close[3] == pytest.approx(-g.k_speed * depth / 2.0)  # 1.5 m/s of the +-2 m/s channel
    assert close[0] == 0.0
    port = SeparationGuard().filter(_overtaking(4.0, 2.8), a)[0]  # the leader to starboard: port, still down
    assert port[1] == pytest.approx(-close[1]) and port[2] == pytest.approx(close[2])
    # beside the leader: the full shift; the speed demand beyond the channel goes to the along-track offset
    deeper = SeparationGuard().filter(_overtaking(3.5), a)[0]
    assert deeper[3] == -1.0
    assert deeper[0] == pytest.approx((-g.k_speed * (g.guard_m - 3.5) + 2.0) / kp / 5.0)  # 0.25 m/s -> 2 m back
    # beside the leader: the full shift, every brake saturated
    beside = SeparationGuard().filter(_overtaking(-1.0), a)[0]
    assert beside[1] == pytest.approx(g.lateral_m / 5.0) and beside[2] == pytest.approx(g.vertical_m / 5.0)
    assert beside[3] == -1.0 and beside[0] == -1.0


def test_the_clip_keeps_the_lateral_set_point_beyond_the_shift_deep_in_the_guard():
    """With ``clip_ramp`` the policy's lateral command toward the guarded UAV is clipped to the guard's shift once the
    ramp reaches it; away from the UAV, shallower in the guard, and on every other axis the additive guard's action."""
    g = GuardGains(clip_ramp=0.25)
    add, clip = SeparationGuard(), SeparationGuard(g)
    rng = np.random.default_rng(2)
    for ahead in (4.0, 2.0, 0.0, -3.0):  # ramp 0.04, 0.36, 1, 1 (the leader to port: the shift is starboard)
        for lateral in (-2.8, 2.8):
            obs = np.repeat(_overtaking(ahead, lateral), 16, axis=0)
            a = rng.uniform(-1, 1, size=(16, 4))
            ref, out = add.filter(obs, a), clip.filter(obs, a)
            np.testing.assert_array_equal(out[:, [0, 2, 3]], ref[:, [0, 2, 3]])
            ramp = min((g.guard_m - ahead) / g.guard_m, 1.0) ** 2
            side = 1.0 if lateral < 0 else -1.0
            shift = g.lateral_m * ramp / 5.0
            if ramp < g.clip_ramp:
                np.testing.assert_array_equal(out, ref)
            else:
                assert np.all(side * out[:, 1] >= shift - 1e-12)  # never nearer than the shift
                away = side * ref[:, 1] >= shift
                np.testing.assert_array_equal(out[away], ref[away])  # commands away from the UAV untouched
                assert np.all(out[~away, 1] == pytest.approx(side * shift))
    np.testing.assert_array_equal(SeparationGuard(GuardGains(clip_ramp=0.0)).filter(obs, a), add.filter(obs, a))
    with pytest.raises(ValueError, match="clip_ramp must be in"):
        GuardGains(clip_ramp=1.5)


def test_bounded_and_nan_rows_pass():
    rng = np.random.default_rng(1)
    obs = rng.normal(0.0, 2.0, size=(64, observation_size(2)))
    obs[0] = np.nan
    a = rng.uniform(-1, 1, size=(64, 4))
    out = SeparationGuard().filter(obs, a)
    assert np.all(np.abs(out[1:]) <= 1.0) and np.all(np.isfinite(out[1:]))
    np.testing.assert_array_equal(out[0], a[0])


def test_guard_terms_and_validation():
    side, depth, ramp = guard_terms(np.zeros((2, 3)), None, 5.0, 4.5)
    assert np.all(depth == 0.0) and np.all(ramp == 0.0)
    with pytest.raises(ValueError, match="actions must have shape"):
        SeparationGuard().filter(_obs(), np.zeros((2, 4)))
    with pytest.raises(ValueError, match="GuardGains.lateral_m"):
        GuardGains(lateral_m=-1.0)
    with pytest.raises(ValueError, match="guard_m must be > 0"):
        GuardGains(guard_m=0.0)


def test_training_wrapper_filters_with_the_last_observation():
    """GuardedVecEnv hands the inner env the guard's filter of the policy's actions on the observation they were
    chosen on; TrainConfig refuses the guard without set-points or with a safe box."""
    from train.sb3.config import TrainConfig
    from train.sb3.guard import GuardedVecEnv

    class Inner:
        num_envs, observation_space, action_space = 1, None, None
        render_mode = None

        def __init__(self):
            self.sent = None

        def reset(self):
            return _overtaking(4.0)

        def step_async(self, actions):
            self.sent = actions

        def step_wait(self):
            return _obs(), np.zeros(1), np.zeros(1, bool), [{}]

    inner = Inner()
    env = GuardedVecEnv.__new__(GuardedVecEnv)  # VecEnvWrapper's constructor wants spaces; the filter does not
    env.venv, env._obs = inner, None
    from agents.separation_guard import SeparationGuard as _G
    env.guard = _G()
    with pytest.raises(RuntimeError, match="before reset"):
        env.step_async(np.zeros((1, 4)))
    env.reset()
    env.step_async(np.zeros((1, 4)))
    assert inner.sent[0, 1] > 0 and inner.sent[0, 3] < 0  # guarded on the overtaking observation
    env.step_wait()
    env.step_async(np.zeros((1, 4)))
    np.testing.assert_array_equal(inner.sent, 0.0)  # the next observation is in the slot: unchanged
    with pytest.raises(ValueError, match="action_guard filters set-point"):
        TrainConfig(scenario="close_formation", algo="ppo", action_mode="residual", seed=0, n_timesteps=1000,
                    action_guard=True)
    with pytest.raises(ValueError, match="safe box"):
        TrainConfig(scenario="wake_surfing", algo="ppo", action_mode="setpoints", seed=0, n_timesteps=1000,
                    action_guard=True)
