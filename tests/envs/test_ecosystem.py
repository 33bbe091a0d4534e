"""The envs in the tools RL researchers already use (issue 15): TorchRL, a CleanRL-style loop over Gymnasium's
own vector env and over FormationVectorEnv. Each test runs the snippet that docs/ecosystem.md shows.

Elsewhere: SB3's check_env on every id (test_env_api.py::test_gymnasium_and_sb3_checkers), SB3 PPO on
FormationVecEnv (test_env_vector.py::test_ppo_trains_on_the_vecenv_without_wrappers), PettingZoo's own API tests
(test_env_api.py::test_parallel_api, ::test_aec_api), RLlib (tests/train/test_rllib.py).
"""

import gymnasium as gym
import numpy as np
import pytest

import formation_env
from formation_env.sim.simulation import INFO_REWARD_KEYS
from formation_env.envs.observations import observation_size

ID = "formation_env/FormationKeeping-v1"


# ---------------------------------------------------------------- TorchRL
_TORCHRL_PZ_VERSION = "ignore:PettingZoo in TorchRL is tested using version"  # TorchRL pins an older PettingZoo


@pytest.mark.filterwarnings(_TORCHRL_PZ_VERSION)
def test_torchrl_pettingzoo_wrapper_parallel_env_rollout():
    pytest.importorskip("torchrl")
    from torchrl.envs import PettingZooWrapper
    from torchrl.envs.utils import check_env_specs

    env = PettingZooWrapper(formation_env.parallel_env("formation_keeping", action_mode="residual", duration_s=2.0),
                            use_mask=True)
    check_env_specs(env, seed=0)
    td = env.reset()
    (group,) = env.group_map  # one group of both UAVs ("uav")
    assert td[group, "observation"].shape == (2, env.observation_spec[group, "observation"].shape[-1])
    rollout = env.rollout(5)
    assert rollout.batch_size == (5,)
    reward = rollout["next", group, "reward"]
    assert reward.shape == (5, 2, 1) and bool(reward.isfinite().all())
    info = rollout["next", group, "info"]
    assert set(INFO_REWARD_KEYS) <= set(info.keys())  # flat info keys become tensors
    assert np.allclose(info["reward_total"].numpy(), reward[..., 0].numpy(), atol=1e-5)
    env.close()


@pytest.mark.filterwarnings(_TORCHRL_PZ_VERSION)
def test_torchrl_pettingzoo_wrapper_aec_env_rollout():
    pytest.importorskip("torchrl")
    from torchrl.envs import PettingZooWrapper

    env = PettingZooWrapper(formation_env.env("formation_keeping", action_mode="residual", duration_s=2.0),
                            use_mask=True)
    env.set_seed(0)
    rollout = env.rollout(4)
    assert rollout.batch_size == (4,)
    for group in env.group_map:  # AEC: one group per agent
        assert bool(rollout["next", group, "reward"].isfinite().all())
    env.close()


def test_torchrl_gymenv_on_a_registered_id_rollout():
    pytest.importorskip("torchrl")
    from torchrl.envs import GymEnv

    env = GymEnv(ID, action_mode="residual", duration_s=2.0)  # TorchRL probes with frameskip: TypeError, dropped
    env.set_seed(0)
    rollout = env.rollout(30)  # stops at the 20-decision episode end
    assert rollout.batch_size == (20,)
    assert bool(rollout["next", "truncated"][-1]) and not bool(rollout["next", "terminated"].any())
    assert bool(rollout["next", "reward"].isfinite().all())
    env.close()


# ---------------------------------------------------------------- CleanRL-style loops
def test_cleanrl_style_loop_over_gymnasium_sync_vector_env():
    def make_env(i):
        def thunk():
            env = gym.make(ID, action_mode="residual", duration_s=1.0)
            env = gym.wrappers.RecordEpisodeStatistics(env)
            return gym.wrappers.ClipAction(env)
        return thunk

    envs = gym.vector.SyncVectorEnv([make_env(i) for i in range(2)])
    obs, _ = envs.reset(seed=1)
    envs.single_action_space.seed(0)
    returns = []
    for _ in range(14):  # 10-decision episodes: one autoreset (next-step mode) on the way
        obs, reward, term, trunc, infos = envs.step(envs.action_space.sample())
        assert obs.shape == (2,) + envs.single_observation_space.shape and np.isfinite(reward).all()
        if "episode" in infos:
            returns += [float(r) for r, done in zip(infos["episode"]["r"], infos["_episode"]) if done]
        assert "reward_slot" in infos  # the flat info keys are batched by Gymnasium as arrays
    assert len(returns) == 2 and np.isfinite(returns).all()
    envs.close()


def test_cleanrl_style_loop_over_formation_vector_env():
    from formation_env.envs import FormationVectorEnv

    envs = FormationVectorEnv(2, scenario="formation_keeping", learning="followers", action_mode="residual",
                              duration_s=1.0)
    envs = gym.wrappers.vector.RecordEpisodeStatistics(envs)
    obs, _ = envs.reset(seed=1)
    lengths = []
    for _ in range(12):
        obs, reward, term, trunc, infos = envs.step(np.zeros((2, 4), np.float32))
        assert obs.shape == (2,) + envs.single_observation_space.shape and np.isfinite(reward).all()
        if "episode" in infos:
            lengths += [int(n) for n, done in zip(infos["episode"]["l"], infos["_episode"]) if done]
    assert lengths == [10, 10]  # same-step autoreset: both formations finished once, at decision 10
    envs.close()


def test_supersuit_wrappers_and_sb3_vec_env():
    """SuperSuit's PettingZoo wrappers (clip, frame stack) and its SB3 vector-env route."""
    ss = pytest.importorskip("supersuit")
    env = ss.frame_stack_v1(ss.clip_actions_v0(formation_env.parallel_env("formation_keeping", learning="all",
                                                                        action_mode="setpoints")), 3)
    obs, _ = env.reset(seed=0)
    d = observation_size(2)
    assert {a: o.shape for a, o in obs.items()} == {"uav_0": (3 * d,), "uav_1": (3 * d,)}
    for _ in range(3):
        obs, rew, term, trunc, infos = env.step({a: 2.0 * np.ones(4, np.float32) for a in env.agents})  # clipped
        assert all(np.isfinite(r) for r in rew.values()) and all(np.all(np.isfinite(o)) for o in obs.values())
    venv = ss.concat_vec_envs_v1(ss.pettingzoo_env_to_vec_env_v1(
        formation_env.parallel_env("formation_keeping", learning="followers", action_mode="setpoints")), 2,
        num_cpus=0, base_class="stable_baselines3")
    first = venv.reset()
    assert first.shape == (2, d)
    nxt, rew, done, infos = venv.step(np.zeros((2, 4), np.float32))
    assert nxt.shape == (2, d) and rew.shape == (2,) and np.all(np.isfinite(rew)) and not np.any(done)
    assert not np.array_equal(first, nxt)
    venv.close()
