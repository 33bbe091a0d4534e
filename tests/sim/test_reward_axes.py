"""The slot error's along-track weight (``RewardWeights.along_track_weight``, issue 24): the reward's slot error
is the slot-frame error with its along-track component scaled, at reset and at every step."""

from __future__ import annotations

import math

import numpy as np
import pytest

import formation_env
from formation_env.control.observation import ned_to_track_frame
from formation_env.sim import Randomisation, RewardWeights


def _track_error(sim, i=0):
    err = sim.aircraft[i, :, 10:13] - sim.position_demand[i]
    vd = sim.velocity_demand[i, 0]
    chi = math.atan2(vd[1], vd[0])
    return np.array([ned_to_track_frame(e, chi) for e in err])


@pytest.mark.parametrize("weight", [0.0, 0.25, 1.0])
def test_slot_error_weights_the_along_track_component(weight):
    env = formation_env.parallel_env("close_formation", action_mode="setpoints",
                                     reward=RewardWeights(along_track_weight=weight),
                                     randomisation=Randomisation(initial_offset_m=2.0))
    _, infos = env.reset(seed=3)
    for step in range(2):
        trk = _track_error(env.sim)[1]
        assert abs(trk[0]) > 0.05  # the jitter moved the follower along the track: the weight is tested
        expected = math.sqrt((weight * trk[0]) ** 2 + trk[1] ** 2 + trk[2] ** 2)
        assert infos["uav_1"]["slot_error_m"] == pytest.approx(expected, rel=1e-9, abs=1e-12)
        for _ in range(20):
            _, _, _, _, infos = env.step({a: np.zeros(4, np.float32) for a in env.agents})


def test_along_track_weight_out_of_range_is_one_clear_error():
    with pytest.raises(ValueError, match=r"along_track_weight must be in \[0, 1\].*1\.5"):
        RewardWeights(along_track_weight=1.5)


def test_turbulence_spread_scales_each_episode_field_and_keeps_the_rest():
    """``turbulence_sigma_spread``: each episode's field is the seed's field scaled by one factor in
    [1 - spread, 1] (drawn per episode, so the factors differ), wavevectors and phases unchanged; without a
    spread the episode is the seed's as before."""
    from formation_env.sim import EnvConfig, Simulation

    def sim_for(spread):
        cfg = EnvConfig(scenario="close_formation", action_mode="setpoints",
                        randomisation=Randomisation(turbulence_sigma_mps=1.0, turbulence_sigma_spread=spread))
        sim = Simulation(cfg, batch_size=4)
        sim.reset(seeds=[1, 2, 3, 4])
        return sim.state.modes

    plain, spread = sim_for(0.0), sim_for(0.8)
    np.testing.assert_array_equal(plain.wavevector, spread.wavevector)
    np.testing.assert_array_equal(plain.phase, spread.phase)
    ratio = spread.amplitude / plain.amplitude
    factors = ratio[:, 0, 0]
    np.testing.assert_allclose(ratio, factors[:, None, None] * np.ones_like(ratio), rtol=1e-12)
    assert np.all((factors >= 0.2 - 1e-12) & (factors <= 1.0)) and np.ptp(factors) > 0.01


def test_turbulence_spread_needs_a_spectral_field():
    from formation_env.sim import EnvConfig

    with pytest.raises(ValueError, match="turbulence_sigma_spread.*lanes"):
        EnvConfig(scenario="close_formation", turbulence_field="lanes",
                  randomisation=Randomisation(turbulence_sigma_mps=1.0, turbulence_sigma_spread=0.5))
    with pytest.raises(ValueError, match=r"turbulence_sigma_spread must be in \[0, 1\]"):
        Randomisation(turbulence_sigma_spread=2.0)
