"""Properties of the formation solution: symmetry, decay, frame invariance, batching, robustness."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from formation_env.frames import dcm_ned_to_body, euler_from_dcm
from formation_env.geometry import aerosonde, delta_wing, verification_wing
from formation_env.wake import FormationState, WakeModel

B_AERO = 2.9


def _pair_state(offset_b, span=B_AERO, theta_deg=3.0, alpha_deg=3.0, v=25.0):
    return FormationState.from_degrees([[0, 0, 0], np.asarray(offset_b) * span], [[0, theta_deg, 0]] * 2, v, alpha_deg)


def test_port_and_starboard_followers_are_mirror_images():
    model = WakeModel([aerosonde(tailplane=True), aerosonde(tailplane=True)])
    stbd = model.evaluate(_pair_state([-2, 0.9, 0.3]))
    port = model.evaluate(_pair_state([-2, -0.9, 0.3]))
    mirror = np.array([1.0, -1.0, 1.0])
    np.testing.assert_allclose(port.wind_body[0, 1], stbd.wind_body[0, 1] * mirror, atol=1e-12)
    # Rotational wind is a pseudo-vector: under y -> -y, p and r flip, q stays.
    np.testing.assert_allclose(port.omega_body[0, 1], stbd.omega_body[0, 1] * np.array([-1.0, 1.0, -1.0]), atol=1e-10)
    assert stbd.wind_body[0, 1, 2] < 0  # upwash outboard of the leader's tip
    assert stbd.wind_body[0, 1, 1] > 0  # starboard sidewash below the wake


def test_induced_wind_decays_to_zero_with_distance():
    model = WakeModel([aerosonde(), aerosonde()])
    lateral = np.array([1.5, 3, 6, 12, 24, 48])
    mags = [np.linalg.norm(model.evaluate(_pair_state([0, y, 0])).wind_ned[0, 1]) for y in lateral]
    assert np.all(np.diff(mags) < 0)
    assert mags[-1] < 1e-3 * mags[0]
    # Far enough behind for the legs to look infinite, the growing viscous core decays the wake.
    behind = [np.linalg.norm(model.evaluate(_pair_state([-x, 1, 0.3])).wind_ned[0, 1]) for x in (20, 200, 2000, 20000)]
    assert np.all(np.diff(behind) < 0)
    assert behind[-1] < 0.2 * behind[0]
    ahead = np.linalg.norm(model.evaluate(_pair_state([50, 0, 0])).wind_ned[0, 1])
    assert ahead < 1e-3  # far ahead of the leader almost nothing is felt


def test_far_field_scaling():
    """Far abeam of the leader its wake acts as a pair of line vortices: at large lateral distance
    y the upwash falls as 1/y^2 (dipole of the two tip vortices)."""
    model = WakeModel([verification_wing(), verification_wing()], core="none")
    w = [model.evaluate(FormationState.from_degrees([[0, 0, 0], [-500, y, 0]], np.zeros((2, 3)), 25.0, 1.0)).wind_ned[0, 1, 2]
         for y in (100.0, 200.0)]
    assert w[0] / w[1] == pytest.approx(4.0, rel=0.02)


def _random_formation(draw_or_rng, n=3):
    rng = draw_or_rng
    pos = np.array([[0, 0, 0], [-2.0, 1.1, 0.4], [-1.5, -1.3, -0.3]])[:n] * 2.9 + rng.normal(0, 0.3, (n, 3))
    euler = np.column_stack([rng.normal(0, 0.1, n), rng.normal(0.05, 0.05, n), rng.normal(0, 0.1, n)])
    return pos, euler, 25 + rng.normal(0, 1, n), np.radians(3) + rng.normal(0, 0.02, n), rng.normal(0, 0.02, n)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), r0=st.tuples(*[st.floats(-3.1, 3.1)] * 3),
       shift=st.tuples(*[st.floats(-500, 500)] * 3))
def test_frame_invariance_under_rotation_and_translation(seed, r0, shift):
    """Rotating and translating the whole formation rotates the NED outputs and leaves the body
    outputs and circulations unchanged (the Table 5.3 property, over random formations)."""
    model = WakeModel([aerosonde(tailplane=True), aerosonde(), delta_wing()])
    pos, euler, v, a, b = _random_formation(np.random.default_rng(seed))
    c = dcm_ned_to_body(np.array(r0))  # new frame: p' = C p + shift
    pos2 = pos @ c.T + np.array(shift)
    euler2 = euler_from_dcm(dcm_ned_to_body(euler) @ c.T)
    s1 = model.evaluate(FormationState(pos, euler, v, a, b))
    s2 = model.evaluate(FormationState(pos2, euler2, v, a, b))
    np.testing.assert_allclose(s2.circulation, s1.circulation, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(s2.wind_body, s1.wind_body, rtol=1e-7, atol=1e-10)
    np.testing.assert_allclose(s2.omega_body, s1.omega_body, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(s2.wind_ned[0], s1.wind_ned[0] @ c.T, rtol=1e-7, atol=1e-10)


def test_batched_equals_single_bit_for_bit():
    model = WakeModel([aerosonde(), aerosonde(), aerosonde()])
    rng = np.random.default_rng(7)
    forms = [_random_formation(rng) for _ in range(40)]  # 40 >= the parallel threshold
    batch = FormationState(*[np.stack([f[i] for f in forms]) for i in range(5)])
    sol = model.evaluate(batch)
    for i, f in enumerate(forms):
        one = model.evaluate(FormationState(*[x[None] for x in f]))
        for name in ("circulation", "wind_ned", "wind_body", "omega_body", "omega_ned", "point_velocity_ned"):
            assert np.array_equal(getattr(one, name)[0], getattr(sol, name)[i]), name


def test_coincident_and_overlapping_vehicles_stay_finite():
    model = WakeModel([aerosonde(tailplane=True), aerosonde(tailplane=True)])
    for offset in ([0, 0, 0], [0, 0.145, 0], [-0.1, 0.05, 0.01], [-0.85, 0, 0]):
        for core in ("kurylowich", "lamb_oseen", "none"):
            m = WakeModel(model.vehicles, core=core)
            s = FormationState.from_degrees([[0, 0, 0], offset], [[0, 3, 0]] * 2, 25.0, 3.0)
            sol = m.evaluate(s)
            for arr in (sol.circulation, sol.wind_ned, sol.omega_body, sol.point_velocity_ned):
                assert np.all(np.isfinite(arr)), (offset, core)


def test_rotational_wind_reductions_have_the_thesis_structure():
    """Eq. 6.1 keeps only d/dy (omega_y = 0); Eq. 5.10 drops d/dz; lstsq on a flat unswept wing
    equals Eq. 6.1's structure (the points span y only)."""
    state = _pair_state([-2, 1, 0.3], theta_deg=0.0, alpha_deg=4.0)
    flat = verification_wing(nseg=10)
    sols = {m: WakeModel([flat, flat], rotational=m).evaluate(state) for m in ("lstsq", "eq4_82", "eq5_10", "eq6_1")}
    assert sols["eq6_1"].omega_body[0, 1, 1] == 0.0
    np.testing.assert_allclose(sols["lstsq"].omega_body[0, 1, 1], 0.0, atol=1e-12)
    # For a flat unswept wing every variant reduces to the same d/dy terms.
    for m in ("eq4_82", "eq5_10"):
        np.testing.assert_allclose(sols[m].omega_body[0, 1, [0, 2]], sols["eq6_1"].omega_body[0, 1, [0, 2]], rtol=1e-12)
    assert np.all(np.isfinite(WakeModel([delta_wing(), delta_wing()], rotational="eq4_82").evaluate(state).omega_body))


def test_lstsq_gradient_recovers_a_linear_field():
    from formation_env.wake.lattice import gradient_weights

    model = WakeModel([delta_wing(), delta_wing()])  # swept: points span x and y
    g = np.array([[0.1, -0.3, 0.0], [0.7, 0.2, 0.0], [-0.4, 0.5, 0.0]])  # dV_a/dx_c, no z dependence
    w = gradient_weights(model.template, model.eval_b, "lstsq", 0.1)
    pts = model.eval_b[:10]
    v = (pts - pts.mean(0)) @ g.T + np.array([1.0, 2.0, 3.0])
    np.testing.assert_allclose(v.T @ w[:10], g, atol=1e-12)


@pytest.mark.parametrize("n_vehicles", [2, 5])
def test_shared_field_equals_the_separately_evaluated_field(n_vehicles):
    """The field at the control points is the sum of the branch vectors the AIC kept (issue 26: each
    segment-point interaction evaluated once). Against the field evaluated branch by branch at the same
    points moved by one ulp (which takes the separate path): equal to round-off, over random formations
    including vehicles inside each other's cores and overlapping."""
    from formation_env.wake import kernels
    from formation_env.wake.arrays import lattice_arrays

    model = WakeModel([aerosonde(nseg=10)] * n_vehicles)
    t = model.template
    rng = np.random.default_rng(11)
    b = 2.9
    for trial in range(20):
        pos = rng.normal(0.0, 0.6 * b if trial % 4 else 0.05 * b, (n_vehicles, 3))
        pos[:, 0] -= 2.0 * b * np.arange(n_vehicles)
        euler = rng.normal(0.0, 0.1, (n_vehicles, 3))
        speed = 25.0 + rng.normal(0.0, 1.0, n_vehicles)
        alpha, beta = rng.normal(0.05, 0.03, n_vehicles), rng.normal(0.0, 0.02, n_vehicles)
        out = {}
        for label, eval_b in (("shared", t.control_b), ("separate", np.nextafter(t.control_b, np.inf))):
            gamma, vpts = np.empty(t.n_panels), np.empty((t.n_panels, 3))
            winds = [np.empty((n_vehicles, 3)) for _ in range(4)]
            lat = lattice_arrays(model)._replace(eval_b=np.ascontiguousarray(eval_b), aic_core_mode=model.core_mode)
            kernels.evaluate_one(lat, pos, euler, speed, alpha, beta, gamma, vpts, *winds)
            out[label] = gamma, vpts
        np.testing.assert_array_equal(out["shared"][0], out["separate"][0])  # the solve is untouched
        scale = max(np.abs(out["separate"][1]).max(), 1e-3)
        np.testing.assert_allclose(out["shared"][1], out["separate"][1], rtol=0.0, atol=1e-12 * scale)
