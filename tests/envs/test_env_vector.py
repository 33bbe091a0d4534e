"""Vector envs: batch = single envs, selective auto-reset, SB3 PPO on the VecEnv without wrappers."""

import numpy as np
import pytest

import formation_env
from formation_env.envs import FormationVecEnv, FormationVectorEnv, Randomisation

RANDOM = Randomisation(initial_offset_m=2.0, slot_offset_b=0.1, steady_wind_mps=4.0, turbulence_sigma_mps=1.0)


@pytest.mark.parametrize("n_formations,mode,learning", [(3, "residual", "all"), (18, "surfaces", "all"),
                                                        (17, "setpoints", "followers")])
def test_batched_formations_equal_single_envs_bit_for_bit(n_formations, mode, learning):
    """Batches run on the thread pool in chunks (with a PID-flown leader too); results are still
    bit-identical to single envs."""
    opts = dict(scenario="reconfiguration", action_mode=mode, learning=learning, randomisation=RANDOM, duration_s=8.0)
    venv = FormationVecEnv(n_formations, seed=100, **opts)
    obs = venv.reset()
    singles = [formation_env.parallel_env(**opts) for _ in range(n_formations)]
    a = venv.batch.agents_per_formation
    single_obs = [env.reset(seed=100 + f * a)[0] for f, env in enumerate(singles)]
    rng = np.random.default_rng(0)
    live = set(range(n_formations))
    finished_seen = 0
    for step in range(40):
        for f in live:
            for k in range(a):
                assert np.array_equal(obs[f * a + k], single_obs[f][singles[f].possible_agents[k]]), (step, f, k)
        act = rng.uniform(-1, 1, (venv.num_envs, 4)).astype(np.float32)
        obs, rew, done, infos = venv.step(act)
        for f in sorted(live):
            names = singles[f].possible_agents
            single_obs[f], r, term, trunc, _ = singles[f].step({names[k]: act[f * a + k] for k in range(a)})
            for k in range(a):
                assert rew[f * a + k] == np.float32(r[names[k]])
                assert done[f * a + k] == (term[names[k]] or trunc[names[k]])
            if done[f * a]:  # the VecEnv auto-reset it: its last observation is in the infos
                for k in range(a):
                    assert np.array_equal(infos[f * a + k]["terminal_observation"], single_obs[f][names[k]])
                live.discard(f)
                finished_seen += 1
    assert live  # most formations kept flying for the whole comparison


def test_only_finished_formations_reset():
    venv = FormationVecEnv(3, scenario="formation_keeping", learning="followers", action_mode="residual", seed=1)
    venv.reset()
    for _ in range(5):
        venv.step(np.zeros((3, 4)))
    eng = venv.batch.sim
    eng.aircraft[1, 1, 10:13] = eng.aircraft[1, 0, 10:13] + np.array([-1.0, 0.0, 0.0])  # formation 1 collides
    obs, rew, done, infos = venv.step(np.zeros((3, 4)))
    assert done.tolist() == [False, True, False]
    assert "terminal_observation" in infos[1] and not infos[1]["TimeLimit.truncated"]
    assert infos[1]["episode"]["l"] == 6 and infos[0] == {}
    assert eng.state.step.tolist() == [30, 0, 30]  # 6 decisions x 5 physics steps; formation 1 restarted
    assert np.array_equal(obs[1], venv.batch.observations()[1])


def test_bad_vector_actions():
    venv = FormationVecEnv(2, scenario="formation_keeping", learning="followers")
    venv.reset()
    with pytest.raises(ValueError, match="shape"):
        venv.step(np.zeros((3, 4)))
    bad = np.zeros((2, 4))
    bad[1, 2] = np.nan
    with pytest.raises(ValueError, match=r"\[1\]"):
        venv.step(bad)


def test_ppo_trains_on_the_vecenv_without_wrappers():
    from stable_baselines3 import PPO

    venv = FormationVecEnv(4, scenario="formation_keeping", learning="followers", action_mode="residual",
                           duration_s=3.0, seed=0)
    model = PPO("MlpPolicy", venv, n_steps=32, batch_size=64, n_epochs=1, seed=0, device="cpu")
    model.learn(total_timesteps=256)
    assert model.num_timesteps >= 256
    assert len(model.ep_info_buffer) > 0  # the VecEnv reports episodes itself


def test_gymnasium_vector_env_same_step_autoreset():
    venv = FormationVectorEnv(2, scenario="formation_keeping", learning="followers", action_mode="residual",
                              duration_s=1.0)
    obs, info = venv.reset(seed=3)
    assert obs.shape == (2, venv.single_observation_space.shape[0]) and venv.observation_space.contains(obs)
    for _ in range(10):
        obs, rew, term, trunc, infos = venv.step(venv.action_space.sample())
    assert trunc.all() and infos["_final_obs"].all()
    assert infos["final_obs"][0].shape == obs[0].shape
    assert venv.batch.sim.state.step.tolist() == [0, 0]  # already reset
