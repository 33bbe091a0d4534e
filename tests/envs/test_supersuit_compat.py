"""The SuperSuit route to Stable-Baselines3 (issue 22, item 7): time-outs reach SB3 as truncations, a collision as
a termination, ``PPO(..., seed=0)`` works, seeding reproduces, and unseeded copies do not fly the same episodes."""

from __future__ import annotations

import numpy as np
import pytest

import formation_env
from formation_env.envs import Randomisation

ss = pytest.importorskip("supersuit")


def _par(**kw):
    return formation_env.parallel_env("formation_keeping", learning="followers", action_mode="residual", duration_s=0.5,
                                      randomisation=Randomisation(initial_offset_m=1.0), **kw)


def test_supersuit_vec_env_marks_time_outs_as_truncated_and_collisions_as_terminal():
    from formation_env.envs.compat import supersuit_vec_env

    venv = supersuit_vec_env(_par(), 2, seed=0)
    venv.reset()
    for k in range(5):
        obs, rew, done, infos = venv.step(np.zeros((2, 4), np.float32))
        assert done.tolist() == [k == 4] * 2
    assert [i["TimeLimit.truncated"] for i in infos] == [True, True]
    assert all(i["terminal_observation"].shape == obs[0].shape for i in infos)
    par = venv.venv.vec_envs[0].par_env  # put copy 0's follower 1 m behind the leader: a collision
    par.sim.aircraft[0, 1, 10:13] = par.sim.aircraft[0, 0, 10:13] + np.array([-1.0, 0.0, 0.0])
    _, _, done, infos = venv.step(np.zeros((2, 4), np.float32))
    assert done.tolist() == [True, False]
    assert infos[0]["TimeLimit.truncated"] is False and "TimeLimit.truncated" not in infos[1]


def test_ppo_with_a_seed_trains_on_it_and_seeding_reproduces():
    from stable_baselines3 import PPO

    from formation_env.envs.compat import supersuit_vec_env

    PPO("MlpPolicy", supersuit_vec_env(_par(), 2), seed=0, n_steps=8, batch_size=8, n_epochs=1).learn(16)

    def first(seed):
        v = supersuit_vec_env(_par(), 2)
        assert v.seed(seed) == [seed, seed + 1]
        return v.reset()

    assert np.array_equal(first(3), first(3)) and not np.array_equal(first(3), first(4))
    unseeded = supersuit_vec_env(_par(), 2).reset()
    assert not np.array_equal(unseeded[0], unseeded[1])  # SuperSuit's pickled copies share one entropy


def test_plain_supersuit_lacks_what_the_wrapper_adds():
    """What the wrapper is for (if SuperSuit ever fixes these, the wrapper can go)."""
    plain = ss.concat_vec_envs_v1(ss.pettingzoo_env_to_vec_env_v1(_par()), 2, num_cpus=0, base_class="stable_baselines3")
    with pytest.raises(AttributeError, match="seed"):
        plain.seed(0)
    plain.reset()
    for _ in range(5):
        *_, infos = plain.step(np.zeros((2, 4), np.float32))
    assert all("TimeLimit.truncated" not in i for i in infos)
