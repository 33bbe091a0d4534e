"""The formation simulator: compiled step against the composition of the wake and aircraft APIs."""

import numpy as np
import pytest

from formation_env.aircraft import check_envelope, trim
from formation_env.atmosphere.wind import WindInput
from formation_env.sim import WakeConfig
from tests.oracles.physics_simulator import FormationSimulator
from formation_env.sim.kernels import envelope_status, pack_limits
from formation_env.aircraft.envelope import DEFAULT_LIMITS
from formation_env.aircraft.kernels import pack

B_SPAN = 2.9


def _pair_states(batch):
    tr = trim(25.0, 1000.0, 2.0)
    st = np.repeat(tr.state[None], 2, axis=1).repeat(batch, axis=0)
    st[:, 1, 10:13] += [-2 * B_SPAN, B_SPAN, 0.3 * B_SPAN]
    st[:, 1, 10] += np.linspace(0.0, 1.0, batch)
    u = np.repeat(tr.controls[None], 2, axis=1).repeat(batch, axis=0)
    u[:, 1, 1] += np.linspace(-0.01, 0.01, batch)
    return st, u


@pytest.mark.parametrize("batch", [1, 20])
def test_compiled_step_equals_the_reference_composition(batch):
    st0, u = _pair_states(batch)
    amb = np.broadcast_to(np.array([1.0, -2.0, 0.3]), (batch, 2, 3))
    turb = np.random.default_rng(0).normal(0, 0.5, (batch, 2, 3))
    from tests.oracles.formation_step import reference_step

    fast = FormationSimulator(2, batch)
    ref = FormationSimulator(2, batch)
    a, b = st0.copy(), st0.copy()
    for _ in range(100):
        ra, rb = fast.step(a, u, amb, turb), reference_step(ref, b, u, amb, turb)
        a, b = ra.state, rb.state
    # The two compute the ELL inputs with different (equivalent) formulas: agreement to round-off.
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9)
    np.testing.assert_allclose(ra.induced_wind_ned, rb.induced_wind_ned, atol=1e-12)
    np.testing.assert_allclose(ra.induced_omega_body, rb.induced_omega_body, atol=1e-10)
    assert np.array_equal(ra.status, rb.status)
    assert np.abs(ra.induced_wind_ned[:, 1]).max() > 1e-3  # the follower does feel the wake


def test_batched_equals_single_bit_for_bit():
    st0, u = _pair_states(20)
    batch = FormationSimulator(2, 20)  # the parallel kernel
    res_b = batch.step(st0, u)
    for i in range(20):
        one = FormationSimulator(2, 1).step(st0[i:i + 1], u[i:i + 1])
        assert np.array_equal(one.state[0], res_b.state[i])
        assert np.array_equal(one.induced_wind_ned[0], res_b.induced_wind_ned[i])


def test_wake_off_and_single_aircraft_feel_no_induced_wind():
    st0, u = _pair_states(1)
    res = FormationSimulator(2, 1, wake=WakeConfig(enabled=False)).step(st0, u)
    assert np.all(res.induced_wind_ned == 0) and res.circulation is None
    res1 = FormationSimulator(1, 1).step(st0[:, :1], u[:, :1])
    assert np.all(res1.induced_wind_ned == 0)


def test_envelope_kernel_matches_check_envelope():
    rng = np.random.default_rng(1)
    st0, _ = _pair_states(1)
    rows = np.repeat(st0[0, :1], 64, axis=0)
    rows[:, 0] *= rng.uniform(0.3, 2.5, 64)  # airspeed low/high
    rows[:, 12] = -rng.uniform(-50, 7000, 64)  # altitude
    rows[:, 14] = rng.uniform(0, 600, 64)  # shaft speed
    rows[:, 13] = rng.uniform(-0.1, 2, 64)  # fuel
    rows[::7, 3] = np.nan
    wind = rng.normal(0, 3, (64, 3))
    expected = check_envelope(rows, WindInput(wind_ned=wind))
    from formation_env.aircraft import AEROSONDE, DEFAULT_OPTIONS

    packed = pack(AEROSONDE, DEFAULT_OPTIONS)[0]
    lim = pack_limits(DEFAULT_LIMITS)
    got = [envelope_status(rows[i], np.concatenate([wind[i], np.zeros(9)]), packed, lim) for i in range(64)]
    assert np.array_equal(np.array(got), expected)
    assert len(set(expected.tolist())) > 4  # the draw exercises several flags


def test_bad_controls_raise():
    st0, u = _pair_states(1)
    sim = FormationSimulator(2, 1)
    with pytest.raises(ValueError, match="controls"):
        sim.step(st0, u[..., :3])
    bad = u.copy()
    bad[0, 1, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        sim.step(st0, bad)


def test_step_many_equals_repeated_steps():
    st0, u = _pair_states(3)
    rng = np.random.default_rng(2)
    amb = rng.normal(0, 1, (5, 3, 2, 3))
    turb = rng.normal(0, 0.5, (5, 3, 2, 3))
    a, b = FormationSimulator(2, 3), FormationSimulator(2, 3)
    res_many, status_any, min_sep = a.step_many(st0, u, amb, turb)
    x = st0
    seps = []
    for s in range(5):
        r = b.step(x, u, amb[s], turb[s])
        x = r.state
        seps.append(np.linalg.norm(x[:, 0, 10:13] - x[:, 1, 10:13], axis=1))
    assert np.array_equal(res_many.state, x)
    assert np.array_equal(res_many.induced_wind_ned, r.induced_wind_ned)
    np.testing.assert_allclose(min_sep, np.min(seps, axis=0), rtol=1e-15)
    assert np.all(status_any == 0)
