"""Component checks: propeller, engine, mass properties, look-ups, actuators, parameters."""

import numpy as np
import pytest

from formation_env.aircraft import AEROSONDE, AerosondeParams
from formation_env.aircraft.actuators import ActuatorConfig, Actuators, clip_controls
from formation_env.aircraft.lookup import interp1_extrap, interp2_extrap
from formation_env.aircraft.mass import mass_properties
from formation_env.aircraft.propulsion import engine, propeller


def test_propeller_hand_check():
    """Spec section 14: at V = 25, rho = 1.1116, Omega = 545.4: J = 0.567, CT = 0.01623, T = 9.05 N."""
    T, Q, J, CT, CP = propeller(np.array([25.0]), np.array([1.11164]), np.array([545.4]), AEROSONDE)
    assert J[0] == pytest.approx(0.567, abs=1e-3)
    assert CT[0] == pytest.approx(0.01623, abs=2e-5)
    assert CP[0] == pytest.approx(0.01678, abs=2e-5)
    assert T[0] == pytest.approx(9.05, abs=0.01)
    assert -Q[0] * 545.4 == pytest.approx(412.8, abs=0.5)  # shaft power absorbed


def test_engine_map_formula_and_power():
    p = np.array([89874.57])
    T = np.array([281.65])
    om = np.array([545.4])
    map_kpa, power, torque, ff = engine(np.array([0.7063]), p, T, om, AEROSONDE)
    assert map_kpa[0] == pytest.approx(60 + 0.7063 * (89.87457 - 60), rel=1e-12)
    assert power[0] == pytest.approx(412.8, abs=0.5)
    assert torque[0] == pytest.approx(power[0] / 545.4)
    assert ff[0] * 3.6e6 == pytest.approx(135.2, abs=0.5)
    # the throttle misprint 0.07063 gives MAP 62.1 kPa and about half the power (spec section 14)
    m2, p2, _, _ = engine(np.array([0.07063]), p, T, om, AEROSONDE)
    assert m2[0] == pytest.approx(62.1, abs=0.05) and p2[0] == pytest.approx(202, abs=3)
    # closed throttle floors at MAPmin; no upper bound above full throttle
    m3, _, _, _ = engine(np.array([-0.5, 1.5]), np.repeat(p, 2), np.repeat(T, 2), np.repeat(om, 2), AEROSONDE)
    assert m3[0] == 60.0 and m3[1] > 89.87


def test_mass_properties_at_2kg():
    m, cg, J = mass_properties(np.array([2.0, 0.0, 9.0]), AEROSONDE)
    assert m[0] == 10.5
    assert np.allclose(cg[0], [0.1572, 0.0, 0.0834])
    assert np.allclose(J[0], [0.79746, 1.1272, 1.7548, 0.12082])
    assert np.allclose(cg[1], AEROSONDE.cg_empty_body)
    assert m[2] == AEROSONDE.mass_gross  # clipped to the tank capacity


def test_lookups_extrapolate_linearly():
    x = np.array([0.0, 1.0, 2.0])
    y = np.array([0.0, 1.0, 3.0])
    assert interp1_extrap(x, y, np.array([-1.0, 0.5, 3.0])).tolist() == [-1.0, 0.5, 5.0]
    z = np.add.outer(2 * x, 3 * x)  # bilinear function is reproduced exactly, even outside
    assert interp2_extrap(x, x, z, np.array([-1.0, 4.0]), np.array([5.0, 0.5])) == pytest.approx([13.0, 9.5])


def test_params_are_frozen_and_validated():
    with pytest.raises(Exception):
        AEROSONDE.CL0 = 1.0
    with pytest.raises(ValueError):
        AEROSONDE.prop_CT[0] = 1.0
    with pytest.raises(ValueError, match="mac"):
        AerosondeParams(mac=-1.0)
    with pytest.raises(ValueError, match="va_bounds"):
        AerosondeParams(va_bounds=(20.0, 10.0))
    assert AEROSONDE.aspect_ratio == pytest.approx(15.245, abs=1e-3)


def test_actuators_clip_lag_and_rate_limit():
    cfg = ActuatorConfig()
    act = Actuators(np.zeros((2, 4)), cfg)
    dt = 0.02
    out = act.update(np.array([[1.0, -1.0, 0.1, 2.0], [0.0, 0.0, 0.0, 0.5]]), dt)
    # rate limit binds for the big surface command: 200 deg/s * 0.02 s
    assert out[0, 0] == pytest.approx(np.deg2rad(200) * dt)
    assert out[0, 1] == pytest.approx(-np.deg2rad(200) * dt)
    # small command: first-order lag, exact for a held input
    assert out[0, 2] == pytest.approx(0.1 * (1 - np.exp(-dt / 0.05)))
    for _ in range(500):
        out = act.update(np.array([[1.0, -1.0, 0.1, 2.0], [0.0, 0.0, 0.0, 0.5]]), dt)
    assert np.allclose(out[0], [np.deg2rad(25), -np.deg2rad(25), 0.1, 1.0])  # clipped to limits
    assert np.allclose(out[1], [0, 0, 0, 0.5])
    assert np.allclose(clip_controls([[0.9, 0, 0, -1]], cfg), [[np.deg2rad(25), 0, 0, 0]])
    with pytest.raises(ValueError, match="NaN"):
        act.update(np.array([[np.nan, 0, 0, 0], [0, 0, 0, 0]]), dt)
    with pytest.raises(ValueError, match="shape"):
        act.update(np.zeros((3, 4)), dt)
    with pytest.raises(ValueError, match="lower"):
        ActuatorConfig(lower=(1, 0, 0, 0), upper=(0, 1, 1, 1))
