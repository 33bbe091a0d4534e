"""PettingZoo and Gymnasium conventions, checked with their own tools."""

import gymnasium as gym
import numpy as np
import pytest
from pettingzoo.test import parallel_api_test

import formation_env
from formation_env.envs import GYM_IDS, Randomisation
from formation_env.scenarios import scenario_names


@pytest.mark.parametrize("scenario", scenario_names())
def test_parallel_api(scenario):
    env = formation_env.parallel_env(scenario, action_mode="residual", duration_s=6.0)
    parallel_api_test(env, num_cycles=80)


def test_aec_api():
    from pettingzoo.test import api_test

    api_test(formation_env.env("formation_keeping", action_mode="residual", duration_s=4.0), num_cycles=30)


@pytest.mark.parametrize("env_id", sorted(GYM_IDS))
def test_gymnasium_and_sb3_checkers(env_id):
    from gymnasium.utils.env_checker import check_env as gym_check
    from stable_baselines3.common.env_checker import check_env as sb3_check

    env = gym.make(env_id, duration_s=4.0, action_mode="residual")
    gym_check(env.unwrapped, skip_render_check=True)
    sb3_check(env.unwrapped, warn=True)


@pytest.mark.parametrize("obs_mode", ["flat", "dict"])
def test_spaces_hold_every_emitted_value(obs_mode):
    env = formation_env.parallel_env("reconfiguration", obs_mode=obs_mode, action_mode="residual", duration_s=20.0,
                                     randomisation=Randomisation(turbulence_sigma_mps=1.0, steady_wind_mps=5.0))
    obs, _ = env.reset(seed=3)
    rng = np.random.default_rng(0)
    while env.agents:
        for a, o in obs.items():
            assert env.observation_space(a).contains(o), a
        obs, *_ = env.step({a: rng.uniform(-1, 1, 4).astype(np.float32) for a in env.agents})
    for a, o in obs.items():
        assert env.observation_space(a).contains(o)


def test_render_rgb_array():
    env = formation_env.parallel_env("formation_keeping", render_mode="rgb_array", duration_s=2.0)
    env.reset(seed=0)
    frame = env.render()
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8
    assert frame.std() > 0  # something was drawn
    env.close()
