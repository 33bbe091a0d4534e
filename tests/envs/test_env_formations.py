"""Formations of 3 and 5 UAVs (echelon, vee) through the env with the PID baseline."""

import numpy as np
import pytest

import formation_env


@pytest.mark.parametrize("scenario,n", [("echelon", 3), ("vee", 5)])
def test_pid_holds_echelon_and_vee_with_every_follower_in_upwash(scenario, n):
    from formation_env.sim.config import Randomisation

    env = formation_env.parallel_env(scenario, action_mode="residual", learning="followers", duration_s=12.0,
                                     randomisation=Randomisation())  # calm air, no start jitter
    obs, _ = env.reset(seed=0)
    assert len(env.agents) == n - 1 and obs["uav_1"].shape == (47 + 6 * (n - 1),)  # 47 own features (docs/env.md)
    infos = None
    errors = []
    while env.agents:
        obs, rew, term, trunc, infos = env.step({a: np.zeros(4, np.float32) for a in env.agents})
        if env.sim.time_s[0] > 6.0:
            errors.append([infos[a]["slot_error_m"] for a in sorted(infos)])
    assert all(trunc.values())
    assert np.max(errors) < 0.5
    for a, info in infos.items():
        assert info["induced_wind_ned_mps"][2] < -0.02  # upwash from the UAVs ahead
        assert info["min_separation_m"] > 2.9
