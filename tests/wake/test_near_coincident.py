"""Near-coincident and overlapping vehicles: the ELL stays physical (bounded) at any separation.

The other vehicles' branches carry the overlap core (``formation_env.wake.biot_savart.branch_cored``,
``leg_cored``; docs/ell.md), so

* the joint solve stays well conditioned: no circulation exceeds twice the largest isolated one;
* each branch induces at most CORE_PEAK / (2 pi r_min) per unit strength, r_min = min(r_o, eps)
  (r_o the overlap core, eps the Eq. 4.31 cutoff), so every point velocity is bounded by that figure
  times the summed strengths of the other vehicles' branches;
* physically: the effective wind is below (V - 1) Gamma_iso / (pi r_o) and the rotational wind below
  (V - 1) Gamma_iso / (pi r_o^2) (the peak vorticity of a Lamb-Oseen core of radius r_o), Gamma_iso the
  largest isolated circulation;
* the rotational wind is the curl of the fitted gradient: |omega_i| <= 2 W max_j |v_j|.

Before the overlap core, a 1 um vertical offset gave 3.9e3 m/s and a 1 cm lateral one 16.8 rad/s.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from formation_env.geometry import aerosonde
from formation_env.wake import FormationState, WakeModel
from formation_env.wake.biot_savart import CORE_PEAK

B = 2.9  # Aerosonde span, m


@lru_cache(maxsize=None)
def _models(n: int, tail: bool):
    return WakeModel([aerosonde(tailplane=tail)] * n), WakeModel([aerosonde(tailplane=tail)])


def _check_bounded(model: WakeModel, alone: WakeModel, state: FormationState) -> None:
    sol = model.evaluate(state)
    t = model.template
    nv = model.n_vehicles
    r_o, eps = model.overlap_core_m, t.cutoff_m
    per_branch = CORE_PEAK / (2.0 * math.pi * min(r_o, eps))
    g_iso = max(np.abs(alone.evaluate(FormationState(*(x[:, v:v + 1] for x in (
        state.position_ned, state.euler_rad, state.airspeed_mps, state.alpha_rad, state.beta_rad)))).circulation).max()
        for v in range(nv))
    for arr in (sol.circulation, sol.wind_ned, sol.omega_body, sol.point_velocity_ned):
        assert np.all(np.isfinite(arr))
    g = sol.circulation[0]
    assert np.abs(g).max() <= 2.0 * g_iso, (np.abs(g).max(), g_iso)
    for v in range(nv):
        strength = 0.0  # summed |strength| of the other vehicles' branches (2 per knot + 1 per panel)
        for s in range(len(t.surface_vehicle)):
            if t.surface_vehicle[s] != v:
                gs = g[t.surface_panel_start[s]:t.surface_panel_start[s + 1]]
                strength += 2.0 * np.abs(np.diff(np.concatenate([[0.0], gs, [0.0]]))).sum() + np.abs(gs).sum()
        j0, j1 = t.vehicle_panel_start[v], t.vehicle_panel_start[v + 1]
        vmax = np.linalg.norm(sol.point_velocity_ned[0, j0:j1], axis=1).max()
        assert vmax <= per_branch * strength * (1 + 1e-12), (vmax, per_branch * strength)
        wind = np.linalg.norm(sol.wind_ned[0, v])
        assert wind <= (nv - 1) * g_iso / (math.pi * r_o), (wind, (nv - 1) * g_iso / (math.pi * r_o))
        omega = sol.omega_body[0, v]
        assert np.linalg.norm(omega) <= (nv - 1) * g_iso / (math.pi * r_o**2), (omega, g_iso)
        w = np.abs(model.grad_w[j0:j1]).sum(axis=0).max()
        assert np.abs(omega).max() <= 2.0 * w * vmax * (1 + 1e-12) + 1e-15


_SCALE = st.sampled_from([0.0, 1e-9, 1e-6, 1e-3, 1e-2, 0.1, 0.3, 1.0, 3.0])


@st.composite
def _poses(draw, n):
    pos = [[0.0, 0.0, 0.0]]
    for _ in range(n - 1):
        scale = draw(_SCALE) * B
        pos.append([scale * draw(st.floats(-1.0, 1.0)) for _ in range(3)])
    angle = st.floats(-5.0, 5.0)
    euler = [[draw(angle), 3.0 + draw(angle), draw(angle)] for _ in range(n)]
    alpha = [3.0 + draw(st.floats(-3.0, 3.0)) for _ in range(n)]
    beta = [draw(st.floats(-3.0, 3.0)) for _ in range(n)]
    speed = [25.0 + draw(st.floats(-3.0, 3.0)) for _ in range(n)]
    return FormationState.from_degrees(pos, euler, speed, alpha, beta)


@settings(max_examples=80, deadline=None)
@given(state=_poses(2), tail=st.booleans())
def test_two_aerosondes_stay_bounded_at_any_separation(state, tail):
    _check_bounded(*_models(2, tail), state)


@settings(max_examples=40, deadline=None)
@given(state=_poses(3), tail=st.booleans())
def test_three_aerosondes_stay_bounded_at_any_separation(state, tail):
    _check_bounded(*_models(3, tail), state)


def test_the_measured_near_coincident_cases():
    """The poses that used to blow up: exactly coincident, 1 um vertical, 1 cm lateral."""
    for tail in (False, True):
        model, alone = _models(2, tail)
        for offset in ([0, 0, 0], [0, 0, 1e-6], [0, 0.01, 0], [0, 0, 0.05], [-0.1, 0.05, 0.01], [-0.85, 0, 0]):
            state = FormationState.from_degrees([[0, 0, 0], offset], [[0, 3, 0]] * 2, 25.0, 3.0)
            _check_bounded(model, alone, state)
            sol = model.evaluate(state)
            assert np.abs(sol.wind_ned).max() < 1.0 and np.abs(sol.omega_body).max() < 1.0


def test_overlap_core_leaves_the_thesis_separations_alone():
    """At the thesis slot (-2, 1, 0.3) spans and the close slot (-2, 0.96, 0.1) spans the overlap core
    changes the induced wind by < 1e-6 m/s and the rotational wind by < 1e-6 rad/s."""
    for tail in (False, True):
        vehicles = [aerosonde(tailplane=tail)] * 2
        on, off = WakeModel(vehicles), WakeModel(vehicles, overlap_core=0.0)
        for slot in ([-2, 1, 0.3], [-2, 0.96, 0.1]):
            state = FormationState.from_degrees([[0, 0, 0], np.multiply(slot, B)], [[0, 3, 0]] * 2, 25.0, 3.0)
            a, b = on.evaluate(state), off.evaluate(state)
            assert np.abs(a.wind_ned - b.wind_ned).max() < 1e-6
            assert np.abs(a.omega_body - b.omega_body).max() < 1e-6
            np.testing.assert_allclose(a.circulation, b.circulation, rtol=0, atol=1e-8)


def test_own_branches_keep_the_thesis_law():
    """A lone vehicle (only its own branches) is unchanged by the overlap core, bit for bit."""
    state = FormationState.from_degrees([[0, 0, 0]], [[1, 3, 2]], 25.0, 4.0, 1.0)
    a = WakeModel([aerosonde(tailplane=True)]).evaluate(state)
    b = WakeModel([aerosonde(tailplane=True)], overlap_core=0.0).evaluate(state)
    assert np.array_equal(a.circulation, b.circulation)
