"""Chapter 5.4 validation study (delta wing of Table 5.5): the thesis's findings."""

import numpy as np
import pytest

from formation_env.verification.sweeps import lateral_sweep, longitudinal_sweep, vertical_sweep


@pytest.fixture(scope="module")
def lateral():
    return lateral_sweep()


def test_lift_loss_is_largest_directly_behind(lateral):
    y, dcl = lateral.coordinate, lateral.increments["dCL"]
    assert y[np.argmin(dcl)] == 0.0
    assert dcl.min() < 0
    assert lateral.dalpha_rad[y == 0.0][0] == lateral.dalpha_rad.min()  # strongest downwash there too


def test_largest_lift_gain_near_0_8_span(lateral):
    y, dcl = lateral.coordinate, lateral.increments["dCL"]
    assert abs(abs(y[np.argmax(dcl)]) - 0.8) <= 0.1 + 1e-9
    assert dcl.max() > 0


def test_sweeps_are_symmetric_in_y(lateral):
    assert np.array_equal(lateral.coordinate, -lateral.coordinate[::-1])
    for arr, sign in ((lateral.increments["dCL"], 1), (lateral.wind_body[:, 0], 1), (lateral.wind_body[:, 2], 1),
                      (lateral.wind_body[:, 1], -1), (lateral.increments["dCl"], -1)):
        np.testing.assert_allclose(arr, sign * arr[::-1], atol=1e-12)


def test_vertical_sweep_at_0_75_span_peaks_near_0_1_span():
    sweep = vertical_sweep(y_b=0.75)
    z = sweep.coordinate
    assert abs(z[np.argmax(sweep.increments["dCL"])] - 0.1) <= 0.05 + 1e-9
    assert abs(z[np.argmin(sweep.wind_body[:, 2])] - 0.1) <= 0.05 + 1e-9  # strongest upwash


def test_longitudinal_sweep_signs_and_decay():
    sweep = longitudinal_sweep()
    x = sweep.coordinate
    behind = x <= -1.0
    assert np.all(sweep.wind_body[behind, 1] > 0)  # starboard sidewash (follower starboard and below)
    assert np.all(sweep.wind_body[behind, 2] < 0)  # upwash
    ahead = x >= 1.5
    assert np.all(np.linalg.norm(sweep.wind_body[ahead], axis=1) < 0.2 * np.linalg.norm(sweep.wind_body[behind], axis=1).max())
