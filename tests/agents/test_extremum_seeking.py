"""The extremum-seeking baseline (agents.extremum_seeking): it converges on the optimum in calm air,
its gradient estimate has the right sign, and its set-point stays in the safe box."""

import numpy as np
import pytest

from agents.extremum_seeking import ExtremumSeeking, ExtremumSeekingGains
from formation_env.envs.config import Randomisation
from formation_env.envs.observations import observation_size
from formation_env.tasks import make_config
from formation_env.scenarios import get_scenario
from formation_env.sim.params import setpoint_ranges, setpoint_speed_range
from formation_env.tasks.wake_surfing.optimum import reference_optimum
from train.evaluation.wake_surfing_rollout import fly

B = 2.9
SC = get_scenario("wake_surfing")


def _agent(**gains):
    from formation_env.sim.params import safe_box_offsets

    low, high = setpoint_ranges(SC)
    box_low, box_high = safe_box_offsets(SC)
    return ExtremumSeeking(low, high, setpoint_speed_range(SC), gains=ExtremumSeekingGains(**gains),
                           box_low_m=box_low, box_high_m=box_high)


def test_converges_on_the_optimum_in_calm_air():
    """No wind, no turbulence, no manoeuvre: from the thesis slot (saving ~0.15) the seeker climbs to the
    best point it may hold. The optimum sits on the box's 0.1 b floor; the seeker's centre may come no
    closer than the floor plus its dither amplitude and margin (so that it stays in the box), so its
    target is the constrained optimum on that line: from 130 s on its vertical centre stays within 0.01 span
    (3 cm, a tenth of the scale on which the saving changes) of the limit, and over the last 60 s of 180 its
    mean centre has a static saving (ELL map) within 3 % of the best on that line, laterally within 0.1 span
    of the optimum, never leaving the box. (With the energy tasks' load-weighted coupling the lift-matched
    wake is ~1.7x stronger than the thesis's flat-wing one: the seeker first reaches the limit at 121 s, not
    99 s, and holds 0.003 span above it, measured; with the thesis coupling 99 s and 0.0015 span.)"""
    from formation_env.tasks.close_formation.optimum import LATTICE_WAKE, slot_savings

    cfg = make_config(scenario="wake_surfing", learning="followers", randomisation=Randomisation(), duration_s=180.0)
    agent = _agent()
    centres = []

    class Watched:  # the seeker, its centre recorded at every decision
        name = "es"
        reset, observe = agent.reset, agent.observe

        def act(self, obs):
            a = agent.act(obs)
            centres.append(agent.centre_m[0] / B + np.asarray(SC.slots[0].keyframes[0][1])[1:])
            return a

    ep = fly(Watched(), [5], config=cfg, keep_series=True)[0]
    centres = np.asarray(centres)
    g = agent.gains
    z_limit = SC.safe_box_b[2][0] + (g.amplitude_z_m + g.margin_m) / B
    y_opt, _, s_opt = reference_optimum(0.0)
    saving = np.asarray(ep["series"]["saving"])
    assert saving[:50].mean() < 0.5 * s_opt  # it starts far from the optimum
    assert np.all(centres[1300:, 1] < z_limit + 0.01)  # at the floor limit from 130 s on
    y_line = np.linspace(0.7, 1.3, 61)
    line = slot_savings(np.stack([np.full(61, -2.0), y_line, np.full(61, z_limit)], -1), wake=LATTICE_WAKE)[:, 1]
    mean_centre = centres[-600:].mean(axis=0)
    at_centre = slot_savings(np.array([-2.0, *mean_centre]), wake=LATTICE_WAKE)[1]  # wake_surfing's wake
    assert at_centre > 0.97 * line.max()
    assert abs(mean_centre[0] - y_opt) < 0.1
    assert not ep["collision"] and ep["box_outside_frac"] == 0.0


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
    from formation_env.sim.params import safe_box_offsets

    low, high = safe_box_offsets(SC)  # the box's walls, inside the set-point map's reach
    for k in range(600):
        act = agent.act(obs, np.array([k * 0.01, -k * 0.01]))  # a saving that rises forever: the centre runs off
        assert np.all(np.abs(act) <= 1.0)
    centre = agent.centre_m
    assert np.all(centre >= low[1:] - 1e-12) and np.all(centre <= high[1:] + 1e-12)
    assert np.any(np.isclose(centre, low[1:] + np.array([agent.gains.amplitude_y_m, agent.gains.amplitude_z_m])
                             + agent.gains.margin_m)) or np.any(np.isclose(centre, high[1:] - np.array(
                                 [agent.gains.amplitude_y_m, agent.gains.amplitude_z_m]) - agent.gains.margin_m))


def test_bad_arguments_raise():
    with pytest.raises(ValueError, match="gain_y"):
        ExtremumSeekingGains(gain_y=-1.0)
    with pytest.raises(ValueError, match="period_y_s"):
        ExtremumSeekingGains(period_y_s=0.0)
    agent = _agent()
    with pytest.raises(ValueError, match="agree"):
        agent.act(np.zeros((2, observation_size(2))), np.zeros(3))
