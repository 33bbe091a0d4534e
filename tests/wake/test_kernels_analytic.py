"""Biot-Savart kernels against closed forms, and the joint solve against an independent VLM."""

import math

import numpy as np
import pytest

from formation_env.geometry import LiftingSurface, Vehicle
from formation_env.wake import FormationState, WakeModel, vehicle_loads
from formation_env.wake.kernels import leg_velocity, segment_velocity


def test_long_segment_tends_to_infinite_line():
    h = 0.3
    v = segment_velocity(np.array([0.0, h, 0.0]), np.array([-1e4, 0.0, 0.0]), np.array([1e4, 0.0, 0.0]), 0.0)
    # Unit-strength line along +x: v = 1/(2 pi h) along x_hat x r_hat = +z for a point at +y.
    np.testing.assert_allclose(v, [0.0, 0.0, 1.0 / (2 * math.pi * h)], rtol=1e-6)


def test_finite_segment_closed_form():
    # Point on the perpendicular bisector of a segment of half-length a at distance h:
    # |v| = (1 / (4 pi h)) * 2 a / sqrt(a^2 + h^2).
    a, h = 0.7, 0.2
    v = segment_velocity(np.array([0.0, 0.0, h]), np.array([-a, 0.0, 0.0]), np.array([a, 0.0, 0.0]), 0.0)
    expected = 2 * a / math.sqrt(a * a + h * h) / (4 * math.pi * h)
    np.testing.assert_allclose(v, [0.0, -expected, 0.0], rtol=1e-12)


def test_semi_infinite_leg_is_half_a_line_at_its_start():
    h = 0.5
    v = leg_velocity(np.array([0.0, h, 0.0]), np.zeros(3), np.array([1.0, 0.0, 0.0]), 0.0, 0.0)
    np.testing.assert_allclose(v, [0.0, 0.0, 1.0 / (4 * math.pi * h)], rtol=1e-12)


def test_cutoff_clips_the_distance():
    eps = 0.1
    near = segment_velocity(np.array([0.0, 0.01, 0.0]), np.array([-1e4, 0.0, 0.0]), np.array([1e4, 0.0, 0.0]), eps)
    # With h = 0.01 < eps the kernel uses 1/(h * eps) instead of 1/h^2: |v| = 2 h / (4 pi h eps).
    np.testing.assert_allclose(np.linalg.norm(near), 2 * 0.01 / (4 * math.pi * 0.01 * eps), rtol=1e-6)


def test_points_on_the_line_give_zero_not_nan():
    a, b = np.zeros(3), np.array([1.0, 0.0, 0.0])
    for p in (np.array([0.5, 0.0, 0.0]), np.array([2.0, 0.0, 0.0]), a.copy(), b.copy()):
        assert np.all(segment_velocity(p, a, b, 0.0) == 0.0)
        assert np.all(leg_velocity(p, a, b, 0.0, 0.01) == 0.0)
    assert np.all(segment_velocity(np.ones(3), a, a, 0.0) == 0.0)  # zero-length branch


@pytest.mark.parametrize("rc", [0.01, 0.2])
def test_viscous_core_profile(rc):
    t = np.array([1.0, 0.0, 0.0])
    far = 1000 * rc
    plain = leg_velocity(np.array([-1e5, far, 0.0]), np.zeros(3), -t, 0.0, 0.0)
    visc = leg_velocity(np.array([-1e5, far, 0.0]), np.zeros(3), -t, 0.0, rc)
    np.testing.assert_allclose(visc, plain, rtol=1e-12)  # far outside the core: potential vortex
    hs = np.linspace(1e-4, 5, 2000) * rc
    speed = [np.linalg.norm(leg_velocity(np.array([-1e5, h, 0.0]), np.zeros(3), -t, 0.0, rc)) for h in hs]
    # Solid-body core: v ~ h near the axis; the peak of 1 - exp(-1.26 x^2) over x is at x = 1.0 rc.
    assert speed[0] < speed[10] < speed[100]
    assert abs(hs[int(np.argmax(speed))] / rc - 1.0) < 0.02


def _textbook_vlm_cl_alpha(ar, n):
    """Independent classic horseshoe VLM (legs from the 1/4 chord along -x), for comparison."""
    def seg(p, a, b):
        r0, r1, r2 = b - a, p - a, p - b
        c = np.cross(r1, r2)
        return c / (c @ c) * (r0 @ (r1 / np.linalg.norm(r1) - r2 / np.linalg.norm(r2))) / (4 * math.pi)
    b, c = 1.0, 1.0 / ar
    y = np.linspace(-0.5, 0.5, n + 1)
    far = np.array([-1e7, 0, 0])
    a_mat = np.zeros((n, n))
    for j in range(n):
        p = np.array([-c / 2, 0.5 * (y[j] + y[j + 1]), 0.0])
        for k in range(n):
            x1, x2 = np.array([0, y[k], 0.0]), np.array([0, y[k + 1], 0.0])
            a_mat[j, k] = -(seg(p, x1 + far, x1) + seg(p, x1, x2) + seg(p, x2, x2 + far))[2]
    g = np.linalg.solve(a_mat, -np.ones(n))  # unit alpha (small-angle), unit speed, normal -z
    return 2 * np.sum(g * np.diff(y)) / (b * c)


@pytest.mark.parametrize("ar", [6.0, 15.0])
def test_lift_slope_matches_textbook_vlm_and_helmbold(ar):
    n = 10  # the thesis's discretisation (section 4.2.4 / chapters 5-6)
    model = WakeModel([Vehicle((LiftingSurface(span_m=1.0, aspect_ratio=ar, nseg=n),))])
    alpha = np.radians([0.0, 1.0])
    state = FormationState(np.zeros((2, 1, 3)), np.zeros((2, 1, 3)), 20.0, alpha[:, None], 0.0)
    cl = vehicle_loads(model, state, model.evaluate(state)).CL[:, 0]
    cl_alpha = (cl[1] - cl[0]) / (alpha[1] - alpha[0])
    # Same lattice as a textbook VLM (the legs' tilt by alpha changes it by O(alpha^2)).
    assert cl_alpha == pytest.approx(_textbook_vlm_cl_alpha(ar, n), rel=2e-3)
    helmbold = 2 * math.pi * ar / (2 + math.sqrt(ar * ar + 4))
    assert abs(cl_alpha / helmbold - 1) < 0.05


def test_isolated_wing_loads_are_symmetric_and_drag_is_near_elliptic():
    # Near-field Kutta-Joukowski drag converges with the lattice; 40 horseshoes are needed for the
    # span efficiency of a rectangular wing (about 0.98-1.0) to within a per cent (10 give 1.07).
    model = WakeModel([Vehicle((LiftingSurface(span_m=2.0, aspect_ratio=8.0, nseg=40),))])
    state = FormationState(np.zeros((1, 1, 3)), np.zeros((1, 1, 3)), 25.0, np.radians(4.0), 0.0)
    loads = vehicle_loads(model, state, model.evaluate(state))
    assert abs(loads.CY[0, 0]) < 1e-12 and abs(loads.Cl[0, 0]) < 1e-12 and abs(loads.Cn[0, 0]) < 1e-12
    e = loads.CL[0, 0] ** 2 / (math.pi * 8.0 * loads.CD[0, 0])
    assert 0.97 < e < 1.01
