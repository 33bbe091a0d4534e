"""Open-loop modes about the Table A.5 trim against thesis Tables A.6/A.7 (within 10 %)."""

import numpy as np
import pytest

from formation_env.aircraft.linearise import linearise, open_loop_modes
from formation_env.verification.thesis_values import thesis_values


@pytest.fixture(scope="module")
def modes(trim_a5):
    return open_loop_modes(trim_a5)


def _close(lam: complex, ref: complex, rel: float = 0.10) -> bool:
    return abs(lam - ref) <= rel * abs(ref)


def test_longitudinal_modes_match_table_a6(modes):
    ref = thesis_values()["table_a6_open_loop_longitudinal"]
    lon = modes["longitudinal"]
    assert _close(lon["short_period"].eigenvalue, complex(*ref["sppo"]))
    assert _close(lon["phugoid"].eigenvalue, complex(*ref["phugoid"]))
    assert _close(lon["engine"].eigenvalue, complex(ref["engine"]))
    assert _close(lon["heave"].eigenvalue, complex(ref["heave"]))
    assert abs(lon["surge"].eigenvalue) < 1e-7
    # Table A.6 also prints damping 0.390 and frequency 11.4 rad/s for the short period
    assert lon["short_period"].damping == pytest.approx(0.390, rel=0.05)
    assert lon["short_period"].natural_frequency == pytest.approx(11.4, rel=0.05)


def test_lateral_modes_match_table_a7(modes):
    ref = thesis_values()["table_a7_open_loop_lateral"]
    lat = modes["lateral"]
    assert _close(lat["roll_subsidence"].eigenvalue, complex(ref["roll_subsidence"]))
    assert _close(lat["dutch_roll"].eigenvalue, complex(*ref["dutch_roll"]))
    assert _close(lat["spiral"].eigenvalue, complex(ref["spiral"]))
    assert lat["spiral"].eigenvalue.real > 0  # unstable, as the thesis reports
    assert abs(lat["sway"].eigenvalue) < 1e-7 and abs(lat["heading"].eigenvalue) < 1e-7
    assert lat["dutch_roll"].damping == pytest.approx(0.214, rel=0.05)
    assert lat["dutch_roll"].natural_frequency == pytest.approx(5.96, rel=0.05)


def test_alpha_dot_terms_change_only_the_short_period(trim_a5, modes):
    full = open_loop_modes(trim_a5, alpha_dot="include")
    sp_omit = modes["longitudinal"]["short_period"].eigenvalue
    sp_full = full["longitudinal"]["short_period"].eigenvalue
    # Cm_alphadot < 0 adds pitch damping: the short period is better damped with alpha-dot
    assert sp_full.real < sp_omit.real - 0.3
    for name in ("phugoid", "engine"):
        assert _close(full["longitudinal"][name].eigenvalue, modes["longitudinal"][name].eigenvalue, 0.01)
    for name in ("roll_subsidence", "dutch_roll", "spiral"):
        assert _close(full["lateral"][name].eigenvalue, modes["lateral"][name].eigenvalue, 1e-6)


def test_symmetric_aircraft_decouples():
    """Without the engine reaction torque the trim is symmetric (beta = 0) and the elevator and
    throttle columns of B have no lateral entries."""
    from formation_env.aircraft.eom import ModelOptions
    from formation_env.aircraft.trim import trim

    opts = ModelOptions(engine_reaction_torque=False)
    t = trim(options=opts)
    assert abs(t.beta) < 1e-12 and abs(t.aileron) < 1e-12 and abs(t.rudder) < 1e-12
    lin = linearise(t, options=opts)
    lat = [lin.state_names.index(s) for s in ("v", "p", "r", "phi", "psi", "east")]
    lon = [lin.input_names.index(u) for u in ("elevator", "throttle")]
    assert np.max(np.abs(lin.B[np.ix_(lat, lon)])) < 1e-8


def test_jacobian_matches_a_known_derivative(trim_a5):
    """dq_dot/d(elevator) = qbar S c Cm_de / Jy at trim (the only elevator path into q_dot besides
    the tiny moment-arm transfer of the elevator's drag/lift change)."""
    lin = linearise(trim_a5)
    qbar = 0.5 * 1.11164 * 25.0**2
    jy = 1.1272
    expected = qbar * 0.55 * 0.189941 * -0.9918 / jy
    got = lin.B[lin.state_names.index("q"), lin.input_names.index("elevator")]
    assert got == pytest.approx(expected, rel=0.02)
    assert np.all(np.isfinite(lin.A))
