"""The extremum-seeking baseline (agents.extremum_seeking): it converges on the optimum in calm air,
its gradient estimate has the right sign, and its set-point stays in the safe box."""

import numpy as np
import pytest

from agents.extremum_seeking import ExtremumSeeking, ExtremumSeekingGains
from formation_env.envs.config import Randomisation
from formation_env.envs.observations import observation_size
from formation_env.envs.parallel import make_config
from formation_env.scenarios import get_scenario
from formation_env.sim.params import setpoint_ranges, setpoint_speed_range
from formation_env.verification.wake_surfing import reference_optimum
from train.wake_surfing_rollout import Surfer, fly

B = 2.9
SC = get_scenario("wake_surfing")


def _agent(**gains):
    low, high = setpoint_ranges(SC)
    return ExtremumSeeking(low, high, setpoint_speed_range(SC), gains=ExtremumSeekingGains(**gains))


def test_converges_on_the_optimum_in_calm_air():
    """No wind, no turbulence, no manoeuvre: from the thesis slot (saving ~0.15) the seeker climbs to
    the reference optimum (0.3645 at y 0.963 b on the box's 0.1 b floor) less what its dither and
    margin cost: over the last 30 s of 120 it saves at least 75 % of the optimum, its centre has moved
    up by more than 0.1 span and stays within 0.15 span of the optimum laterally."""
    cfg = make_config(scenario="wake_surfing", learning="followers", randomisation=Randomisation(), duration_s=120.0)
    agent = _agent()
    ep = fly(Surfer("es", agent.act, agent.reset), [5], config=cfg, keep_series=True)[0]
    y_opt, z_opt, s_opt = reference_optimum(0.0)
    saving = np.asarray(ep["series"]["saving"])
    assert saving[:50].mean() < 0.5 * s_opt  # it starts far from the optimum
    assert saving[-300:].mean() > 0.75 * s_opt
    centre_b = agent.centre_m[0] / B + np.asarray(SC.slots[0].keyframes[0][1])[1:]
    assert centre_b[1] < 0.3 - 0.1
    assert abs(centre_b[0] - y_opt) < 0.15
    assert not ep["collision"] and ep["box_outside_longest_s"] <= 1.0


def test_gradient_estimate_points_uphill():
    """A static map J = -k (y - y0)^2 seen through the dither alone (no plant): the estimated
    gradient's sign is the true one on both sides of the peak and the centre moves toward y0."""
    for start, sign in ((-0.4, 1.0), (0.4, -1.0)):
        agent = _agent(phase_lag_y_s=0.0, phase_lag_z_s=0.0, gain_z=0.0)
        agent.reset(1)
        agent.centre_m[:] = (start, 0.0)
        obs = np.zeros((1, observation_size(2)), dtype=np.float32)  # zero errors: no along-track correction
        grad = []
        for _ in range(400):
            y = agent.centre_m[0, 0] + agent._dither(agent.t_s)[0, 0]
            j = np.array([-0.5 * y * y])
            agent.act(obs, j)
            grad.append(agent.gradient[0, 0])
        assert np.sign(np.mean(grad[100:])) == sign
        assert abs(agent.centre_m[0, 0]) < abs(start)


def test_setpoint_never_leaves_the_box():
    agent = _agent(gain_y=50.0, gain_z=50.0)
    agent.reset(2)
    obs = np.zeros((2, observation_size(2)), dtype=np.float32)
    low, high = setpoint_ranges(SC)
    for k in range(600):
        act = agent.act(obs, np.array([k * 0.01, -k * 0.01]))  # a saving that rises forever: the centre runs off
        assert np.all(np.abs(act) <= 1.0)
    centre = agent.centre_m
    assert np.all(centre >= low[1:] - 1e-12) and np.all(centre <= high[1:] + 1e-12)


def test_bad_arguments_raise():
    with pytest.raises(ValueError, match="gain_y"):
        ExtremumSeekingGains(gain_y=-1.0)
    with pytest.raises(ValueError, match="period_y_s"):
        ExtremumSeekingGains(period_y_s=0.0)
    agent = _agent()
    with pytest.raises(ValueError, match="agree"):
        agent.act(np.zeros((2, observation_size(2))), np.zeros(3))
