"""Overlapping UAVs through the env: the decision ends as a collision, and nothing the env returns
(observations, rewards, infos) is NaN or inf, also when the same physics step diverges a UAV."""

from __future__ import annotations

import numpy as np
import pytest

import formation_env


def _values(info: dict):
    for key, value in info.items():
        if isinstance(value, dict):
            yield from ((f"{key}.{k}", v) for k, v in value.items())
        else:
            yield key, value


def _assert_finite(obs, rew, info):
    for a in obs:
        assert np.all(np.isfinite(obs[a])), a
        assert np.isfinite(rew[a]), a
        for key, value in _values(info[a]):
            if isinstance(value, (bool, int, str)):
                continue
            assert np.all(np.isfinite(np.asarray(value, dtype=float))), (a, key, value)


def _coincident_env(offset_ned):
    env = formation_env.parallel_env("formation_keeping")
    env.reset(seed=0)
    eng = env.sim
    eng.aircraft[0, 1] = eng.aircraft[0, 0]
    eng.aircraft[0, 1, 10:13] += np.asarray(offset_ned, dtype=float)
    eng.observe()
    return env


@pytest.mark.parametrize("offset", [[0.0, 0.0, 0.0], [0.0, 0.0, 1e-6], [0.0, 0.01, 0.0], [-0.3, 0.2, 0.05]],
                         ids=["coincident", "1um_vertical", "1cm_lateral", "overlapping"])
def test_overlapping_start_ends_as_a_collision_with_finite_outputs(offset):
    env = _coincident_env(offset)
    assert np.all(np.isfinite(env.sim.output.observation))
    assert np.all(np.abs(env.sim.induced) < 5.0)  # bounded induced wind (no 1e3-1e5 m/s)
    obs, rew, term, trunc, info = env.step({a: np.zeros(4, np.float32) for a in env.agents})
    assert all(term.values()) and not any(trunc.values()) and env.agents == []
    for a in ("uav_0", "uav_1"):
        assert info[a]["collision"], info[a]
        assert info[a]["min_separation_m"] < 1.45
    assert bool(env.sim.info.collision[0])
    _assert_finite(obs, rew, info)


def test_a_collision_in_the_step_that_diverges_a_uav_is_still_a_collision():
    """The follower sits on the leader with a non-finite velocity: the physics step makes its state
    non-finite (crashed) and the separation after the step is unknown; the pre-step positions and
    velocities still show the overlap, so the decision ends as a collision, with finite outputs."""
    env = _coincident_env([0.0, 0.0, 0.0])
    env.sim.aircraft[0, 1, 0] = np.nan
    obs, rew, term, trunc, info = env.step({a: np.zeros(4, np.float32) for a in env.agents})
    assert all(term.values())
    assert info["uav_1"]["crashed"] and info["uav_1"]["collision"] and info["uav_0"]["collision"]
    out = env.sim.output
    assert bool(out.collided[0]) and np.isfinite(out.min_separation_m[0]) and out.min_separation_m[0] < 1.45
    assert np.all(np.isfinite(out.slot_error_m[0])) and np.all(np.isfinite(out.separation_m[0]))
    _assert_finite(obs, rew, info)
