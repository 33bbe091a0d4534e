"""Trim against thesis Table A.5 (tolerances from issue 3) and the other trim kinds."""

import numpy as np
import pytest

from formation_env.aircraft import outputs, trim
from formation_env.aircraft.eom import ModelOptions
from formation_env.verification.thesis_values import thesis_values


def test_trim_matches_table_a5(trim_a5):
    t = trim_a5
    ref = thesis_values()["table_a5_trim"]
    assert t.success
    assert t.alpha == pytest.approx(ref["alpha_rad"], abs=5e-4)
    assert t.theta == pytest.approx(ref["theta_rad"], abs=5e-4)
    assert t.elevator == pytest.approx(ref["elevator_rad"], abs=1e-3)
    assert t.aileron == pytest.approx(ref["aileron_rad"], abs=5e-4)
    assert t.rudder == pytest.approx(ref["rudder_rad"], abs=3e-4)
    # the thesis prints 0.07063: a one-decimal slip for 0.7063 (see docs/aircraft.md)
    assert t.throttle == pytest.approx(10 * ref["throttle"], abs=5e-3)
    assert t.omega == pytest.approx(ref["engine_speed_rad_s"], abs=2.0)
    u, v, w = t.state[0, 0:3]
    assert u == pytest.approx(ref["u_mps"], abs=1e-3)
    assert v == pytest.approx(ref["v_mps"], abs=1e-4)
    assert w == pytest.approx(ref["w_mps"], abs=2e-4)
    assert t.beta == pytest.approx(ref["beta_rad"], abs=1e-4)
    assert t.psi == pytest.approx(ref["psi_rad"], abs=1e-4)
    assert t.phi == pytest.approx(0.0, abs=1e-12)


def test_trim_hand_check_of_propulsion(trim_a5):
    """Spec section 14 hand check: MAP 81.1 kPa, shaft power 412.8 W, thrust 9.05 N, 135 g/h."""
    e = trim_a5.extras
    assert e["map_kpa"] == pytest.approx(81.10, abs=0.01)
    assert e["power"] == pytest.approx(412.8, abs=0.1)
    assert e["thrust"] == pytest.approx(9.05, abs=0.01)
    assert e["engine_torque"] == pytest.approx(0.757, abs=1e-3)
    assert e["fuel_flow_g_per_h"] == pytest.approx(135.2, abs=0.5)


def test_trim_is_an_equilibrium(trim_a5):
    out = outputs(trim_a5.state, trim_a5.controls)
    xdot = out["state_dot"][0]
    assert np.max(np.abs(xdot[0:6])) < 1e-9
    assert abs(xdot[14]) < 1e-7
    assert abs(xdot[12]) < 1e-9  # level
    assert out["velocity_ned"][0, 1] == pytest.approx(0.0, abs=1e-9)  # northbound track
    assert out["airspeed"][0] == pytest.approx(25.0, abs=1e-12)


def test_wgs84_gravity_trim_matches_spec_row():
    """Spec section 14, row 'WGS-84 g (9.8031)': alpha 0.05629, de -0.07476, thr 0.70615."""
    t = trim(25.0, 1000.0, 2.0, options=ModelOptions(gravity_model="wgs84"))
    assert t.alpha == pytest.approx(0.05629, abs=2e-5)
    assert t.elevator == pytest.approx(-0.07476, abs=2e-5)
    assert t.throttle == pytest.approx(0.70615, abs=5e-5)


def test_steady_climb_trim():
    gamma = 0.03
    level = trim(25.0, 1000.0, 2.0)
    climb = trim(25.0, 1000.0, 2.0, flight_path_angle=gamma)
    out = outputs(climb.state, climb.controls)
    assert -out["velocity_ned"][0, 2] == pytest.approx(25.0 * np.sin(gamma), rel=1e-9)
    assert climb.theta - climb.alpha == pytest.approx(gamma, abs=2e-3)  # gamma ~ theta - alpha (small beta)
    assert climb.throttle > level.throttle
    assert np.max(np.abs(out["state_dot"][0, 0:6])) < 1e-9


def test_steady_turn_trim():
    rate = 0.1
    t = trim(25.0, 1000.0, 2.0, turn_rate=rate)
    # coordinated turn: tan(phi) ~ V psi_dot / g (exact for beta = 0, gamma = 0)
    assert np.tan(t.phi) == pytest.approx(25.0 * rate / 9.81, rel=0.02)
    out = outputs(t.state, t.controls)
    assert abs(out["specific_force_body"][0, 1]) < 1e-9
    assert np.max(np.abs(out["state_dot"][0, 0:6])) < 1e-9
    # the body rates make the heading turn at the requested rate
    phi, theta = t.phi, t.theta
    p, q, r = t.state[0, 3:6]
    psi_dot = (q * np.sin(phi) + r * np.cos(phi)) / np.cos(theta)
    assert psi_dot == pytest.approx(rate, rel=1e-12)


@pytest.mark.parametrize("kwargs", [dict(airspeed=5.0), dict(fuel=-1.0), dict(altitude=float("nan")),
                                    dict(turn_rate=1.0)])
def test_trim_rejects_bad_requests(kwargs):
    with pytest.raises(ValueError):
        trim(**kwargs)
