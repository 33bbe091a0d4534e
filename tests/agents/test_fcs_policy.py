"""The PID policy: thesis gains, one batched pure interface, validation, signs, anti-windup."""

import math

import numpy as np
import pytest

from formation_env.control import FCSConfig, PIDFlightControl, SASGains, TrackerGains
from formation_env.control.gains import AttitudeGains, AutopilotGains
from formation_env.control.tracker import track_errors
from formation_env.control.observation import fcs_observation, slot_demand, validate_observation
from formation_env.aircraft import step, trim
from formation_env.verification.thesis_values import thesis_values


@pytest.fixture(scope="module")
def t():
    return trim()


@pytest.fixture(scope="module")
def fcs(t):
    return PIDFlightControl.from_trim(t)


def _obs(state, pd=(0.0, 0.0, -1000.0), vd=(25.0, 0.0, 0.0)):
    return fcs_observation(state, np.asarray(pd, float), np.asarray(vd, float))


def test_gains_are_the_thesis_tables():
    tv = thesis_values()
    a8, a9, a10, a13 = (tv[k] for k in ("table_a8_sas", "table_a9_attitude", "table_a10_autopilot",
                                         "table_a13_trajectory_tracker"))
    s = SASGains()
    assert (s.K_q_elevator, s.K_theta_elevator, s.K_r_rudder, s.T_r_washout_s, s.K_phi_aileron,
            s.K_aileron_rudder_interlink) == (a8["K_q_elevator"], a8["K_theta_elevator"], a8["K_r_rudder"],
                                              a8["T_r_washout_s"], a8["K_phi_aileron"], a8["K_aileron_rudder_interlink"])
    a = AttitudeGains()
    assert (a.Kp_theta, a.Ki_theta, a.Kp_phi, a.Ki_phi) == tuple(a9[k] for k in ("Kp_theta", "Ki_theta", "Kp_phi", "Ki_phi"))
    ap = AutopilotGains()
    assert {k: getattr(ap, k) for k in a10} == a10
    tr = TrackerGains()
    assert (tr.Kp_offtrack, tr.Ki_offtrack, tr.Kd_offtrack, tr.Kp_alongtrack, tr.velocity_demand_limit_mps) == (
        a13["Kp_offtrack"], a13["Ki_offtrack"], a13["Kd_offtrack"], a13["Kp_alongtrack"], a13["velocity_demand_limit_mps"])
    assert math.degrees(tr.track_angle_demand_limit_rad) == pytest.approx(a13["track_angle_demand_limit_deg"])


def test_trim_is_an_equilibrium_of_the_closed_loop(t, fcs):
    obs = _obs(t.state, pd=t.state[0, 10:13], vd=(25.0, 0.0, 0.0))
    cmd, rate, _ = fcs.evaluate(obs, fcs.initial_state(1))
    np.testing.assert_allclose(cmd, t.controls, atol=2e-4)
    assert np.max(np.abs(rate[:, :6])) < 2e-3


def test_batched_equals_single_and_pure(t, fcs):
    rng = np.random.default_rng(0)
    n = 5
    s = np.repeat(t.state, n, axis=0)
    s[:, 10:13] += rng.normal(0, 5, (n, 3))
    s[:, 3:6] += rng.normal(0, 0.05, (n, 3))
    obs = _obs(s)
    c = rng.normal(0, 0.01, (n, 7))
    c0 = c.copy()
    cmd, new = fcs.act(obs, c)
    np.testing.assert_array_equal(c, c0)  # inputs untouched
    for i in range(n):
        o = {k: v[i:i + 1] for k, v in obs.items()}
        ci, ni = fcs.act(o, c[i:i + 1])
        np.testing.assert_allclose(ci, cmd[i:i + 1], rtol=0, atol=1e-15)
        np.testing.assert_allclose(ni, new[i:i + 1], rtol=0, atol=1e-15)


def test_signs_on_the_model(t, fcs):
    """Too low -> elevator trailing edge up (less than trim); right of track -> bank demand to port
    -> aileron up-rolls left (positive); slow -> more throttle."""
    s = t.state.copy()
    s[0, 12] += 10.0  # 10 m low
    cmd, _, sig = fcs.evaluate(_obs(s), fcs.initial_state(1))
    assert cmd[0, 0] < t.elevator and sig["theta_demand"][0] > t.theta
    s = t.state.copy()
    s[0, 11] += 10.0  # 10 m east of a northbound track
    cmd, _, sig = fcs.evaluate(_obs(s), fcs.initial_state(1))
    assert sig["track_angle_demand"][0] < 0 and sig["phi_demand"][0] < 0 and cmd[0, 1] > t.aileron
    s = t.state.copy()
    s[0, 10] -= 10.0  # 10 m behind
    _, _, sig = fcs.evaluate(_obs(s), fcs.initial_state(1))
    assert sig["speed_demand"][0] == pytest.approx(25.0 + 0.125 * 10.0)


def test_saturations_and_anti_windup(t, fcs):
    s = t.state.copy()
    s[0, 10] -= 1000.0  # far behind: velocity demand saturates at +7.5 m/s
    s[0, 11] += 1000.0  # far off track: track correction saturates at 40 deg
    cmd, rate, sig = fcs.evaluate(_obs(s), fcs.initial_state(1))
    assert sig["speed_demand"][0] == pytest.approx(32.5)
    assert sig["track_angle_demand"][0] == pytest.approx(-math.radians(40.0))
    assert rate[0, 5] == 0.0  # off-track integrator frozen while saturated
    c = fcs.initial_state(1)
    c[0, 0] = 100.0  # speed integrator wound up: throttle saturated at 1, integration frozen
    cmd, rate, _ = fcs.evaluate(_obs(s), c)
    assert cmd[0, 3] == 1.0 and rate[0, 0] == 0.0
    assert np.all(np.abs(cmd[:, :3]) <= math.radians(25.0) + 1e-12)


def test_track_errors_eq_a16_a21():
    # demanded track 90 deg (east); aircraft 3 m ahead (east) and 2 m to starboard (south)
    atd, otd, dotd, chi = track_errors(np.array([[-2.0, 3.0, 0.0]]), np.array([[1.0, 25.0, 0.0]]),
                                       np.zeros((1, 3)), np.array([[0.0, 25.0, 0.0]]))
    assert chi[0] == pytest.approx(math.pi / 2)
    assert atd[0] == pytest.approx(3.0) and otd[0] == pytest.approx(2.0) and dotd[0] == pytest.approx(-1.0)


def test_slot_demand_along_leader_track():
    pos, vel = slot_demand(np.array([[0.0, 0.0, -1000.0]]), np.array([[0.0, 25.0, 0.0]]),
                           np.array([[-5.8, 2.9, 0.87]]))
    # leader flying east: 'behind' is west, 'starboard' is south
    np.testing.assert_allclose(pos, [[-2.9, -5.8, -999.13]], atol=1e-12)
    np.testing.assert_allclose(vel, [[0.0, 25.0, 0.0]])


def test_bad_inputs_raise(t, fcs):
    obs = _obs(t.state)
    with pytest.raises(ValueError, match="controller_state"):
        fcs.act(obs, np.zeros((1, 3)))
    bad = dict(obs, airspeed=np.array([np.nan]))
    with pytest.raises(ValueError, match="airspeed"):
        fcs.act(bad, fcs.initial_state(1))
    with pytest.raises(ValueError, match="missing"):
        validate_observation({"airspeed": np.ones(1)})
    with pytest.raises(ValueError, match="T_r_washout_s"):
        SASGains(T_r_washout_s=0.0)
    with pytest.raises(ValueError, match="interlink_path"):
        from formation_env.control import FCSStructure
        FCSStructure(interlink_path="sideways")
    with pytest.raises(ValueError, match="trim_controls"):
        FCSConfig(trim_controls=(0.0, 0.0, float("nan"), 0.5))


def test_holds_trim_in_closed_loop_simulation(t, fcs):
    """30 s from trim in still air with the autopilot+tracker: stays on the moving reference."""
    s, c = t.state.copy(), fcs.initial_state(1)
    for k in range(1500):
        time = (k) * 0.02
        cmd, c = fcs.act(_obs(s, pd=(25.0 * time, 0.0, -1000.0)), c)
        s = step(s, cmd, None, 0.02)
    ref = np.array([25.0 * 1500 * 0.02, 0.0, -1000.0])
    assert np.max(np.abs(s[0, 10:13] - ref)) < 0.05


@pytest.mark.parametrize("structure", [{}, {"washout": "pole", "interlink_path": "direct"},
                                       {"interlink_source": "total", "direction_feedback": "heading"}])
@pytest.mark.parametrize("use_tracker", [True, False])
def test_compiled_law_equals_the_numpy_layers(t, structure, use_tracker):
    """The compiled law (formation_env.control.law) against the readable layer-by-layer numpy
    definition (tests/oracles/fcs_numpy.py), at random states that drive every saturation and freeze."""
    from dataclasses import replace

    from formation_env.control import FCSStructure
    from tests.oracles.fcs_numpy import evaluate_numpy

    fcs = PIDFlightControl.from_trim(t)
    fcs = PIDFlightControl(replace(fcs.config, structure=FCSStructure(**structure), use_tracker=use_tracker), fcs.dt)
    rng = np.random.default_rng(7)
    n = 400
    s = np.repeat(t.state, n, axis=0)
    s[:, 10:13] += rng.normal(0, 1, (n, 3)) * rng.choice([1.0, 30.0, 1000.0], (n, 1))
    s[:, 0:6] += rng.normal(0, 0.3, (n, 6))
    s[:, 6:10] += rng.normal(0, 0.1, (n, 4))
    obs = _obs(s, pd=(0.0, 0.0, -1000.0), vd=(25.0, 3.0, -1.0))
    c = rng.normal(0, 1, (n, 7)) * rng.choice([0.01, 1.0, 100.0], (n, 1))
    cmd, rate, sig = fcs.evaluate(obs, c)
    cmd_np, rate_np, sig_np = evaluate_numpy(fcs.config, obs, c)
    np.testing.assert_allclose(cmd, cmd_np, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rate, rate_np, rtol=0, atol=1e-12)
    for k, v in sig_np.items():
        np.testing.assert_allclose(sig[k], v, rtol=0, atol=1e-12, err_msg=k)
    saturated = (cmd_np[:, 3] == 1.0) | (cmd_np[:, 3] == 0.0) | (np.abs(cmd_np[:, :3]) >= math.radians(25.0)).any(1)
    assert 0.05 < saturated.mean() < 0.95  # the draws exercise the limits and the linear range
