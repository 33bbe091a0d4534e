"""The compiled RK4 step (numba) agrees with the numpy reference (tests/oracles/aircraft_rk4.py) to round-off."""

import numpy as np
import pytest

from formation_env.aircraft import step
from formation_env.aircraft.eom import ModelOptions
from formation_env.aircraft.trim import trim
from formation_env.atmosphere import WindInput
from tests.oracles.aircraft_rk4 import step_numpy


@pytest.mark.parametrize("options", [ModelOptions(), ModelOptions(gravity_model="wgs84", alpha_dot=False),
                                     ModelOptions(engine_reaction_torque=False)])
def test_numba_step_matches_numpy(options):
    t = trim()
    B = 6
    rng = np.random.default_rng(3)
    s = np.repeat(t.state, B, axis=0)
    s[:, 0:3] += rng.normal(0, 2.0, (B, 3))
    s[:, 3:6] += rng.normal(0, 0.3, (B, 3))
    s[0, 0] = 60.0  # beyond the clipping bounds
    s[1, 2] = 8.0  # alpha beyond its bound
    s[2, 13] = 0.0  # empty tank: engine off
    s[3, 12] = 50.0  # below sea level: atmosphere clipped
    c = np.repeat(t.controls, B, axis=0) + rng.normal(0, 0.05, (B, 4))
    c = np.concatenate([c, rng.normal(0, 0.05, (B, 1))], axis=1)  # with flap
    c[4, 3] = -0.3  # throttle below closed
    wind = WindInput(rng.normal(0, 3, (B, 3)), rng.normal(0, 1, (B, 3)), rng.normal(0, 0.5, (B, 3)),
                     rng.normal(0, 0.05, (B, 3)))
    a, b = s, s
    for _ in range(100):
        a = step(a, c, wind, 0.02, options=options, backend="numba")
        b = step_numpy(b, c, wind, 0.02, options=options)
    assert np.allclose(a, b, rtol=1e-9, atol=1e-9)


def test_nonfinite_rows_stay_contained():
    t = trim()
    s = np.repeat(t.state, 2, axis=0)
    s[1, 14] = np.nan
    a = step(s, np.repeat(t.controls, 2, axis=0))
    b = step_numpy(s, np.repeat(t.controls, 2, axis=0))
    assert np.all(np.isfinite(a[0])) and not np.all(np.isfinite(a[1]))
    assert np.array_equal(np.isfinite(a), np.isfinite(b))


def test_unknown_backend_raises():
    t = trim()
    with pytest.raises(ValueError, match="backend"):
        step(t.state, t.controls, backend="fortran")
