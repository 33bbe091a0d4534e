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


# rgb_array rendering: tests/envs/test_env_render.py (each UAV drawn where its state says, frames that move)


# ---------------------------------------------------------------- option and input validation (issue 15)
def test_unknown_options_raise_type_error_naming_them_bad_values_value_error():
    from formation_env.envs import FormationVecEnv, FormationVectorEnv
    from formation_env.tasks import make_config

    makers = {
        "make_config": lambda **kw: make_config(**kw),
        "parallel_env": lambda **kw: formation_env.parallel_env("formation_keeping", **kw),
        "env": lambda **kw: formation_env.env("formation_keeping", **kw),
        "gym.make": lambda **kw: gym.make("formation_env/FormationKeeping-v1", **kw),
        "FormationVecEnv": lambda **kw: FormationVecEnv(1, scenario="formation_keeping", **kw),
        "FormationVectorEnv": lambda **kw: FormationVectorEnv(1, scenario="formation_keeping", **kw),
    }
    for name, make in makers.items():
        # TorchRL's GymEnv probes with frameskip and expects this exact Python wording
        with pytest.raises(TypeError, match="unexpected keyword argument 'frameskip'"):
            make(frameskip=4)
        with pytest.raises(TypeError, match="wingspan"):
            make(wingspan=3.0)
        with pytest.raises(ValueError, match="action_mode"):
            make(action_mode="joystick")


def test_gym_learning_selects_the_learner_or_says_why_not():
    env = gym.make("formation_env/FormationKeeping-v1", learning=(0,), duration_s=2.0)
    assert env.unwrapped.learner == 0 and env.unwrapped.agent == "uav_0"
    assert gym.make("formation_env/FormationKeeping-v1").unwrapped.agent == "uav_1"  # the id's default
    assert gym.make("formation_env/Gust-v1").unwrapped.agent == "uav_0"
    for learning in ("all", (0, 1)):
        with pytest.raises(ValueError, match="one learner"):
            gym.make("formation_env/FormationKeeping-v1", learning=learning)
    with pytest.raises(ValueError, match="disagree"):
        gym.make("formation_env/FormationKeeping-v1", learning=(0,), learner=1)
    with pytest.raises(ValueError, match="out of range"):
        gym.make("formation_env/FormationKeeping-v1", learner=2)


def test_non_integer_learning_indices_are_rejected():
    from formation_env.envs import EnvConfig

    for bad in ((1.7,), (1.0,), (True,), ("1",)):
        with pytest.raises(ValueError, match="integers"):
            EnvConfig(learning=bad)
    assert EnvConfig(learning=(np.int64(1),)).learning == (1,)


def test_complex_actions_are_rejected_naming_the_agent_or_index():
    from formation_env.envs import FormationVecEnv

    env = formation_env.parallel_env("formation_keeping", learning="followers")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="uav_1.*complex"):
        env.step({"uav_1": np.array([0, 1j, 0, 0])})
    genv = gym.make("formation_env/FormationKeeping-v1")
    genv.reset(seed=0)
    with pytest.raises(ValueError, match="complex"):
        genv.unwrapped.step(np.zeros(4, complex))
    venv = FormationVecEnv(2, scenario="formation_keeping", learning="followers")
    venv.reset()
    act = np.zeros((2, 4), complex)
    act[1, 0] = 0.5j
    with pytest.raises(ValueError, match=r"complex.*\[1\]"):
        venv.step(act)


def test_every_id_has_max_episode_steps_of_one_episode():
    from formation_env.envs import EnvConfig
    from formation_env.scenarios import get_scenario

    for env_id, (scenario, _) in GYM_IDS.items():
        steps = gym.spec(env_id).max_episode_steps
        assert steps == round(get_scenario(scenario).duration_s * EnvConfig().control_hz), env_id
    # the env itself truncates at duration x control rate: the id's limit is the same count
    env = gym.make("formation_env/FormationKeeping-v1", duration_s=2.0, max_episode_steps=-1)
    env.reset(seed=0)
    n, trunc = 0, False
    while not trunc:
        *_, term, trunc, _ = env.step(np.zeros(4, np.float32))
        assert not term
        n += 1
    assert n == env.unwrapped.episode_decisions == 20


def test_infos_are_flat_arrays_and_scalars_with_the_same_keys_at_reset_and_step():
    from formation_env.sim.simulation import INFO_REWARD_KEYS

    env = formation_env.parallel_env("formation_keeping", compute_benefit=True)
    _, infos0 = env.reset(seed=0)
    _, rewards, _, _, infos1 = env.step({a: np.full(4, 0.3, np.float32) for a in env.agents})
    for infos in (infos0, infos1):
        for a, info in infos.items():
            for k, v in info.items():
                assert isinstance(v, (bool, int, float, np.ndarray)), (a, k, type(v))
            assert set(INFO_REWARD_KEYS) <= set(info)
    for a in env.possible_agents:
        assert set(infos0[a]) == set(infos1[a])
        assert all(infos0[a][k] == 0.0 for k in INFO_REWARD_KEYS)  # nothing earned before the first step
        assert infos1[a]["reward_total"] == pytest.approx(rewards[a])
        assert infos1[a]["reward_effort"] < 0.0
