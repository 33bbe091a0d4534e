"""MAPPO's centralised critic over the native VecEnv (train/sb3/central_critic.py, issue 25): the agent-specific
global state, the split actor-critic (the actor reads only the agent's own observation, the critic everything), a
training run with it, and decentralised execution of the saved zip by the evaluation's loader."""

import json

import numpy as np
import pytest
import torch

from formation_env.envs import FormationVecEnv
from train.sb3.central_critic import CentralCriticPolicy, GlobalStateVecEnv, agent_specific_state
from train.sb3.train import train

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")


def test_agent_specific_state_is_own_then_the_others_in_order():
    obs = np.arange(2 * 3 * 2, dtype=np.float32).reshape(6, 2)  # 2 formations x 3 agents x 2 values
    s = agent_specific_state(obs, 3)
    assert s.shape == (6, 6)
    np.testing.assert_array_equal(s[0], [0, 1, 2, 3, 4, 5])
    np.testing.assert_array_equal(s[1], [2, 3, 0, 1, 4, 5])
    np.testing.assert_array_equal(s[5], [10, 11, 6, 7, 8, 9])
    np.testing.assert_array_equal(agent_specific_state(obs, 1), obs)
    with pytest.raises(ValueError, match="whole formations"):
        agent_specific_state(obs, 4)


def test_wrapper_extends_observations_and_terminal_observations():
    """vee5, 2 formations x 4 followers, 0.3 s episodes: every row (and every terminal observation) is its own
    observation followed by its formation's other three followers'."""
    base = FormationVecEnv(2, scenario="vee5", learning="followers", action_mode="setpoints", duration_s=0.3, seed=1)
    env = GlobalStateVecEnv(base, 4)
    d = base.observation_space.shape[0]
    assert env.observation_space.shape == (4 * d,) and env.local_dim == d
    obs = env.reset()
    assert obs.shape == (8, 4 * d)
    np.testing.assert_array_equal(obs[:, d:2 * d].reshape(2, 4, d)[:, 0], obs[:, :d].reshape(2, 4, d)[:, 1])
    done = np.zeros(8, bool)
    while not done.any():
        env.step_async(np.zeros((8, 4), np.float32))
        obs, _, done, infos = env.step_wait()
    assert done.all()
    final = np.stack([infos[i]["terminal_observation"] for i in range(8)])
    assert final.shape == (8, 4 * d)
    np.testing.assert_array_equal(final, agent_specific_state(final[:, :d], 4))
    env.close()


def _policy(local_dim=5, full=20):
    from gymnasium import spaces

    obs = spaces.Box(-10.0, 10.0, (full,), np.float32)
    act = spaces.Box(-1.0, 1.0, (4,), np.float32)
    return CentralCriticPolicy(obs, act, lambda _: 3e-4, net_arch=[16], local_dim=local_dim)


def test_the_actor_reads_only_its_own_observation_and_the_critic_everything():
    torch.manual_seed(0)
    pol = _policy()
    x = torch.randn(7, 20)
    y = x.clone()
    y[:, 5:] += torch.randn(7, 15)  # another global state, the same own observation
    with torch.no_grad():
        np.testing.assert_array_equal(pol.get_distribution(x).distribution.mean.numpy(),
                                      pol.get_distribution(y).distribution.mean.numpy())
        assert not torch.allclose(pol.predict_values(x), pol.predict_values(y))
    # decentralised execution: the own observation alone gives the same action as with any global state
    a_full, _ = pol.predict(x.numpy(), deterministic=True)
    a_own, _ = pol.predict(x[:, :5].numpy(), deterministic=True)
    np.testing.assert_array_equal(a_full, a_own)
    with pytest.raises(ValueError, match="local_dim"):
        _policy(local_dim=21)


def test_mappo_trains_and_its_zip_flies_on_plain_observations(tmp_path, tiny):
    """A tiny MAPPO run on vee5 (every follower a row, the critic on the global state) writes a zip whose policy
    the evaluation's loader flies on the per-agent observation."""
    from train.evaluation.policy_loader import load_policy

    over = tiny("ppo")
    over["policy"] = "CentralCriticPolicy"
    out = tmp_path / "m"
    s = train(scenario="vee5", algo="ppo", action_mode="setpoints", seed=0, steps=256, out_dir=out, overrides=over,
              progress_bar=False, log=lambda m: None)
    assert s["num_timesteps"] >= 256
    cfg = json.loads((out / "final_model.json").read_text())
    assert cfg["action_mode"] == "setpoints"
    pol = load_policy(str(out / "final_model.zip"))
    d = FormationVecEnv(1, scenario="vee5", learning="followers", action_mode="setpoints").observation_space.shape[0]
    act = pol.act(np.zeros((4, d), np.float32))
    assert act.shape == (4, 4) and np.all(np.abs(act) <= 1.0)
    with pytest.raises(ValueError, match="CentralCriticPolicy"):
        train(scenario="vee5", algo="sac", action_mode="setpoints", seed=0, steps=64, out_dir=tmp_path / "s",
              overrides={**tiny("sac"), "policy": "CentralCriticPolicy"}, progress_bar=False, log=lambda m: None)
