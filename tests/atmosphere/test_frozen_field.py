"""Frozen (Taylor) Dryden field per formation: statistics against theory, exact transport, seeding.

Statistical tolerances: correlations are pooled over all formations and all samples; their standard
error is estimated from the spread of the per-formation estimates (formations are independent), and a
test allows 4 standard errors (plus a small bias allowance where stated). Seeds are fixed, so the
tests are deterministic; the tolerances say how far the numbers may honestly move with other seeds.
"""

import math

import numpy as np
import pytest

from formation_env.atmosphere.frozen_field import (
    FrozenFieldParams,
    FrozenFieldState,
    FrozenTurbulenceField,
    counter_bits,
    counter_normal_pair,
    dryden_correlation,
    formation_key,
    frozen_field_advance,
    frozen_field_init,
    frozen_field_params,
    frozen_field_reset,
    frozen_field_rollout,
    frozen_field_sample,
    frozen_field_theory,
    isotropic_correlation,
)

B_SPAN = 2.9  # thesis wing span b, m
L_THESIS = 304.8  # MIL-F-8785C low-altitude scale length at 1000 ft, m
V_THESIS = 25.0
DT = 0.02
SLOT = np.array([-2.0 * B_SPAN, 1.0 * B_SPAN, 0.3 * B_SPAN])  # follower relative to leader (along, cross, down)

# ---------------------------------------------------------------- helpers (readable numpy reference)

_M64 = (1 << 64) - 1


def _mix64_ref(z):
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _M64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _M64
    return z ^ (z >> 31)


def _counter_bits_ref(key, counter, stream):
    s = _mix64_ref((key + (counter + 1) * 0x9E3779B97F4A7C15) & _M64)
    return _mix64_ref((s + (stream + 1) * 0x9E3779B97F4A7C15) & _M64)


def _ned_from_track(track_xyz, chi, origin=(0.0, 0.0, 0.0)):
    """(B, V, 3) track-frame positions -> NED for track angles chi (B,)."""
    c, s = np.cos(chi)[:, None], np.sin(chi)[:, None]
    out = np.empty_like(track_xyz)
    out[..., 0] = origin[0] + c * track_xyz[..., 0] - s * track_xyz[..., 1]
    out[..., 1] = origin[1] + s * track_xyz[..., 0] + c * track_xyz[..., 1]
    out[..., 2] = origin[2] + track_xyz[..., 2]
    return out


def _track_from_ned(gust, chi):
    """(T, B, V, 3) NED gusts -> (along, cross, down) for track angles chi (B,)."""
    c, s = np.cos(chi)[None, :, None], np.sin(chi)[None, :, None]
    out = np.empty_like(gust)
    out[..., 0] = c * gust[..., 0] + s * gust[..., 1]
    out[..., 1] = -s * gust[..., 0] + c * gust[..., 1]
    out[..., 2] = gust[..., 2]
    return out


def _corr(a, b):
    """Pooled correlation of a, b (T, B, ...) over T and B, and its standard error from the spread of
    the B per-formation estimates. Returns arrays of shape (...)."""
    pooled = (a * b).sum(axis=(0, 1)) / np.sqrt((a * a).sum(axis=(0, 1)) * (b * b).sum(axis=(0, 1)))
    per = (a * b).sum(axis=0) / np.sqrt((a * a).sum(axis=0) * (b * b).sum(axis=0))
    return pooled, per.std(axis=0, ddof=1) / math.sqrt(a.shape[1])


def _run(params, seeds, track_xyz, chi, n_steps, stride=1, origin=(0.0, 0.0, 0.0)):
    bsz, nveh = track_xyz.shape[:2]
    state = frozen_field_init(params, bsz, nveh)
    frozen_field_reset(params, state, np.arange(bsz), seeds)
    pos = _ned_from_track(track_xyz, chi, origin)
    if stride == 1:
        return frozen_field_rollout(params, state, pos, chi, n_steps)
    out = np.empty((n_steps // stride, bsz, nveh, 3))
    chunk = np.empty((stride, bsz, nveh, 3))
    for t in range(out.shape[0]):
        frozen_field_rollout(params, state, pos, chi, stride, chunk)
        out[t] = chunk[0]
    return out


# ---------------------------------------------------------------- the long thesis-slot run

N_FORM, N_STEPS = 64, 20000  # 64 formations x 400 s


@pytest.fixture(scope="module")
def thesis_run():
    params = frozen_field_params(1.0, L_THESIS, V_THESIS, DT)
    chi = np.linspace(-3.0, 3.0, N_FORM)
    track = np.zeros((N_FORM, 2, 3))
    track[:, 1] = SLOT
    gust_ned = _run(params, list(range(1000, 1000 + N_FORM)), track, chi, N_STEPS, origin=(500.0, -200.0, -1000.0))
    return params, _track_from_ned(gust_ned, chi)


def test_rms_equals_sigma_per_axis(thesis_run):
    _, g = thesis_run
    rms = np.sqrt((g * g).mean(axis=(0, 1)))  # (V, 3)
    print("RMS / sigma (leader, follower) x (u, v, w):", np.round(rms, 4).tolist())
    assert np.all(np.abs(rms - 1.0) < 0.05), rms


@pytest.mark.parametrize("lag_steps", [25, 100, 500])
def test_autocorrelation_is_single_point_dryden(thesis_run, lag_steps):
    _, g = thesis_run
    lag = lag_steps * DT
    f, gg = dryden_correlation(V_THESIS * lag, L_THESIS)
    want = np.array([f, gg, gg])
    np.testing.assert_allclose(frozen_field_theory(np.zeros(3), lag, L_THESIS, V_THESIS)[..., :], want, rtol=1e-12)
    for ac in range(2):
        r, se = _corr(g[:-lag_steps, :, ac], g[lag_steps:, :, ac])
        assert np.all(np.abs(r - want) < 4.0 * se + 0.01), (ac, r, want, se)


def test_thesis_slot_correlation_at_zero_lag(thesis_run):
    _, g = thesis_run
    r, se = _corr(g[:, :, 0], g[:, :, 1])
    model = frozen_field_theory(SLOT, 0.0, L_THESIS, V_THESIS)
    iso = frozen_field_theory(SLOT, 0.0, L_THESIS, V_THESIS, exact=True)
    np.testing.assert_allclose(iso, [0.977, 0.970, 0.968], atol=6e-4)  # the notes' numbers
    print("zero lag: measured", np.round(r, 4).tolist(), "model", np.round(model, 4).tolist(),
          "isotropic", np.round(iso, 4).tolist(), "se", np.round(se, 4).tolist())
    assert np.all(np.abs(r - model) < 4.0 * se + 1e-3), (r, model, se)
    assert np.all(np.abs(r - np.array([0.977, 0.970, 0.968])) < 0.03), r


def test_thesis_slot_correlation_at_transport_lag(thesis_run):
    _, g = thesis_run
    tau = -SLOT[0] / V_THESIS  # 0.232 s = 11.6 steps: interpolate the measured lag-11 and lag-12 values
    k0 = int(math.floor(tau / DT))
    w = tau / DT - k0
    rs, ses, models = [], [], []
    for k in (k0, k0 + 1):
        r, se = _corr(g[:-k, :, 0], g[k:, :, 1])  # leader at t, follower at t + k dt
        rs.append(r)
        ses.append(se)
        models.append(frozen_field_theory(SLOT, k * DT, L_THESIS, V_THESIS))
    r = (1 - w) * rs[0] + w * rs[1]
    se = np.maximum(ses[0], ses[1])
    model = (1 - w) * models[0] + w * models[1]
    at_tau = frozen_field_theory(SLOT, tau, L_THESIS, V_THESIS)
    np.testing.assert_allclose(at_tau, frozen_field_theory(SLOT, tau, L_THESIS, V_THESIS, exact=True), atol=1e-12)
    np.testing.assert_allclose(at_tau, [0.985, 0.990, 0.986], atol=6e-4)
    print("transport lag: measured", np.round(r, 4).tolist(), "theory", np.round(at_tau, 4).tolist(),
          "se", np.round(se, 4).tolist())
    assert np.all(np.abs(r - model) < 4.0 * se + 1e-3), (r, model, se)
    assert np.all(np.abs(r - np.array([0.985, 0.990, 0.986])) < 0.03), r


def test_thesis_slot_gust_difference(thesis_run):
    _, g = thesis_run
    d = g[:, :, 1] - g[:, :, 0]
    rms = np.sqrt((d * d).mean(axis=(0, 1)))
    per = np.sqrt((d * d).mean(axis=0))  # (B, 3)
    se = per.std(axis=0, ddof=1) / math.sqrt(per.shape[0])
    model = np.sqrt(2.0 * (1.0 - frozen_field_theory(SLOT, 0.0, L_THESIS, V_THESIS)))
    iso = np.sqrt(2.0 * (1.0 - frozen_field_theory(SLOT, 0.0, L_THESIS, V_THESIS, exact=True)))
    print("RMS(follower - leader) / sigma: measured", np.round(rms, 4).tolist(), "model", np.round(model, 4).tolist(),
          "isotropic frozen field", np.round(iso, 4).tolist())
    assert np.all(np.abs(rms - model) < 4.0 * se + 0.005), (rms, model, se)
    assert np.all(rms < 0.3)  # independent draws per aircraft would give sqrt(2) = 1.41


# ---------------------------------------------------------------- pairwise spatial structure

def test_pairwise_correlation_equals_isotropic_r_kk():
    # airspeed 100 m/s only shortens the time scale (T = L / V = 3 s) so 64 x 400 s hold many
    # independent samples; the zero-lag correlation of aircraft side by side does not depend on V.
    v_air = 100.0
    params = frozen_field_params((1.0, 2.0, 0.5), (L_THESIS, 200.0, 150.0), v_air, DT)
    b = B_SPAN
    layout = np.array([[0.0, 0.0, 0.0], [0.0, 0.5 * b, 0.0], [0.0, 10 * b, 0.0], [0.0, 100 * b, 0.0],
                       [0.0, 0.0, 3 * b], [-30.0, 0.0, 0.0]])  # the last: along, 15 steps behind
    bsz = 64
    chi = np.linspace(-3.1, 3.1, bsz)
    track = np.broadcast_to(layout, (bsz,) + layout.shape).copy()
    g = _track_from_ned(_run(params, list(range(bsz)), track, chi, 20000, stride=10, origin=(1e3, 2e3, -500.0)), chi)
    rms = np.sqrt((g * g).mean(axis=(0, 1)))
    assert np.all(np.abs(rms / params.sigma_mps - 1.0) < 0.05), rms
    nveh = layout.shape[0]
    for i in range(nveh):
        for j in range(i + 1, nveh):
            sep = layout[j] - layout[i]
            model = frozen_field_theory(sep, 0.0, params.length_scale_m, v_air)
            if sep[0] == 0.0 or (sep[1] == 0.0 and sep[2] == 0.0):  # no approximation: isotropic R_kk
                np.testing.assert_allclose(model, isotropic_correlation(sep, params.length_scale_m), atol=1e-12)
            r, se = _corr(g[:, :, i], g[:, :, j])
            print(i, j, np.round(r, 4).tolist(), np.round(model, 4).tolist(), np.round((r - model) / se, 2).tolist())
            assert np.all(np.abs(r - model) < 4.0 * se + 0.005), (i, j, sep, r, model, se)


# ---------------------------------------------------------------- transport delay, exact

@pytest.mark.parametrize("chi", [0.0, 0.3, -2.5])
def test_follower_is_leader_delayed_when_in_line(chi):
    params = frozen_field_params((1.0, 0.7, 0.4), L_THESIS, V_THESIS, DT)
    steps = 12  # dx = 6 m = 12 * V dt
    track = np.zeros((1, 3, 3))  # the foremost aircraft is number 1
    track[0, 0, 0] = -steps * V_THESIS * DT
    track[0, 2, 0] = -5.8  # 11.6 steps: linear interpolation
    track[0, :, 0] += 40.0
    g = _run(params, [3], track, np.array([chi]), 300, origin=(10.0, -7.0, -300.0))[:, 0]
    np.testing.assert_array_equal(g[steps:, 0], g[:-steps, 1])  # bit for bit
    np.testing.assert_allclose(g[12:, 2], 0.4 * g[1:-11, 1] + 0.6 * g[:-12, 1], rtol=0, atol=1e-12)


def test_delays_beyond_the_buffer_are_clipped():
    params = frozen_field_params(1.0, L_THESIS, V_THESIS, DT, buffer_s=1.0)
    assert params.buffer_steps == 50
    track = np.zeros((2, 2, 3))
    track[:, 1, 0] = -100 * B_SPAN  # 11.6 s behind, clipped to 1 s
    g = _run(params, [1, 2], track, np.zeros(2), 200)
    np.testing.assert_array_equal(g[50:, :, 1], g[:-50, :, 0])


def test_reset_fills_the_buffer_stationary():
    # many formations, statistics at t = 0: leader reads the newest sample, the follower 150 steps
    # back in the pre-filled buffer; their correlation is the Dryden one at 3 s.
    params = frozen_field_params(1.0, L_THESIS, V_THESIS, DT)
    bsz = 3000
    track = np.zeros((bsz, 2, 3))
    track[:, 1, 0] = -150 * V_THESIS * DT
    state = frozen_field_init(params, bsz, 2)
    frozen_field_reset(params, state, np.arange(bsz), list(range(bsz)))
    g = np.empty((bsz, 2, 3))
    frozen_field_sample(params, state, track, np.zeros(bsz), g)
    rms = np.sqrt((g * g).mean(axis=0))
    assert np.all(np.abs(rms - 1.0) < 0.05), rms  # SE about 1.3 %
    r = (g[:, 0] * g[:, 1]).sum(axis=0) / np.sqrt((g[:, 0] ** 2).sum(axis=0) * (g[:, 1] ** 2).sum(axis=0))
    want = frozen_field_theory(np.zeros(3), 3.0, L_THESIS, V_THESIS)  # (0.78, 0.68, 0.68)
    assert np.all(np.abs(r - want) < 0.06), (r, want)  # SE about 0.012


# ---------------------------------------------------------------- reproducibility

def _geometry(bsz, nveh, rng):
    pos = rng.normal(0.0, 8.0, (bsz, nveh, 3)) + np.array([100.0, 50.0, -1000.0])
    return pos, rng.uniform(-math.pi, math.pi, bsz)


def _loop(params, state, pos, chi, n):
    out = np.empty((n,) + pos.shape)
    for t in range(n):
        frozen_field_sample(params, state, pos, chi, out[t])
        frozen_field_advance(params, state)
    return out


def test_batch_equals_single_bit_for_bit_and_rollout_equals_loop():
    params = frozen_field_params((1.2, 0.8, 0.6), (300.0, 250.0, 100.0), 22.0, 0.01, buffer_s=0.5)
    rng = np.random.default_rng(0)
    pos, chi = _geometry(4, 3, rng)
    seeds = [11, 12, 13, 2**40 + 7]
    state = frozen_field_init(params, 4, 3)
    frozen_field_reset(params, state, np.arange(4), seeds)
    batch = _loop(params, state, pos, chi, 120)
    # formation 2 restarts mid-run: identical to a fresh single run with that seed
    frozen_field_reset(params, state, [2], [99])
    batch2 = frozen_field_rollout(params, state, pos, chi, 80)
    for b, seed in enumerate(seeds):
        single = frozen_field_init(params, 1, 3)
        frozen_field_reset(params, single, [0], [seed])
        one = frozen_field_rollout(params, single, pos[b:b + 1], chi[b:b + 1], 200)
        np.testing.assert_array_equal(batch[:, b], one[:120, 0])
        if b != 2:
            np.testing.assert_array_equal(batch2[:, b], one[120:, 0])
    single = frozen_field_init(params, 1, 3)
    frozen_field_reset(params, single, [0], [99])
    np.testing.assert_array_equal(batch2[:, 2], _loop(params, single, pos[2:3], chi[2:3], 80)[:, 0])
    # the lanes do not depend on how many aircraft the formation has
    s2, s3 = frozen_field_init(params, 1, 2), frozen_field_init(params, 1, 3)
    frozen_field_reset(params, s2, [0], [5])
    frozen_field_reset(params, s3, [0], [5])
    np.testing.assert_array_equal(s2.ring, s3.ring[..., :2])


def test_same_seed_same_field_different_seed_differs():
    params = frozen_field_params(1.0, L_THESIS, V_THESIS, DT)
    pos, chi = _geometry(3, 2, np.random.default_rng(1))
    pos[1], chi[1] = pos[0], chi[0]
    pos[2], chi[2] = pos[0], chi[0]
    field = FrozenTurbulenceField(params, 3, 2, [7, 7, 8])
    out = np.stack([field.sample(pos, chi) for _ in range(50) if field.advance() is None])
    np.testing.assert_array_equal(out[:, 0], out[:, 1])
    assert np.all(out[:, 0] != out[:, 2])
    field.reset([0, 1, 2], [7, 7, 8])
    np.testing.assert_array_equal(np.stack([field.sample(pos, chi) for _ in range(50) if field.advance() is None]), out)


def test_counter_generator_uint64_arithmetic():
    rng = np.random.default_rng(3)
    keys = [0, 1, 2**63 + 5, 2**64 - 1] + [int(k) for k in rng.integers(0, 2**63, 4)]
    for key in keys:
        for counter in (0, 1, 200, 2**40 + 3):
            for stream in (0, 5, 29):
                got = counter_bits(np.uint64(key), np.uint64(counter), np.uint64(stream))
                assert int(got) == _counter_bits_ref(key, counter, stream)
            b1 = _counter_bits_ref(key, counter, 2)
            b2 = _counter_bits_ref(key, counter, 3)
            u1 = ((b1 >> 11) + 1) * 2.0**-53
            u2 = (b2 >> 11) * 2.0**-53
            want = math.sqrt(-2 * math.log(u1)) * np.array([math.cos(2 * math.pi * u2), math.sin(2 * math.pi * u2)])
            np.testing.assert_allclose(counter_normal_pair(np.uint64(key), np.uint64(counter), np.uint64(1)), want,
                                       rtol=1e-14, atol=1e-14)
    assert formation_key(5) == np.random.SeedSequence(5).generate_state(1, dtype=np.uint64)[0]


def test_sigma_zero_gives_exactly_zero():
    pos, chi = _geometry(2, 3, np.random.default_rng(2))
    for sigma, zero_axes in [((0.0, 0.0, 0.0), [0, 1, 2]), ((1.0, 1.0, 0.0), [2])]:
        params = frozen_field_params(sigma, L_THESIS, V_THESIS, DT)
        field = FrozenTurbulenceField(params, 2, 3, [1, 2])
        for _ in range(20):
            g = field.sample(pos, chi)
            field.advance()
            assert np.all(g[..., zero_axes] == 0.0)
            assert np.all(np.isfinite(g))


def test_coincident_cross_positions_keep_unit_rows():
    # three aircraft with identical cross position, one displaced: the factorisation must not fail
    params = frozen_field_params(1.0, L_THESIS, V_THESIS, DT)
    track = np.zeros((1, 4, 3))
    track[0, 3, 1] = 1e-7
    g = _run(params, [4], track, np.zeros(1), 50)[:, 0]
    assert np.all(np.isfinite(g))
    np.testing.assert_array_equal(g[:, 0], g[:, 1])
    np.testing.assert_allclose(g[:, 3], g[:, 0], atol=1e-3)


# ---------------------------------------------------------------- bad input

@pytest.mark.parametrize("kwargs,match", [
    (dict(sigma_mps=(-1.0, 1.0, 1.0)), "sigma_mps"),
    (dict(sigma_mps=(1.0, np.nan, 1.0)), "sigma_mps"),
    (dict(sigma_mps=(1.0, 1.0)), "sigma_mps"),
    (dict(length_scale_m=0.0), "length_scale_m"),
    (dict(length_scale_m=(1.0, -2.0, 3.0)), "length_scale_m"),
    (dict(airspeed_mps=0.0), "airspeed_mps"),
    (dict(airspeed_mps=-25.0), "airspeed_mps"),
    (dict(dt_s=0.0), "dt_s"),
    (dict(dt_s=np.inf), "dt_s"),
    (dict(buffer_s=-1.0), "buffer_s"),
])
def test_bad_parameters_raise(kwargs, match):
    args = dict(sigma_mps=1.0, length_scale_m=L_THESIS, airspeed_mps=V_THESIS, dt_s=DT)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        frozen_field_params(**args)


def test_bad_shapes_and_seeds_raise():
    params = frozen_field_params(1.0, L_THESIS, V_THESIS, DT)
    state = frozen_field_init(params, 2, 3)
    assert isinstance(params, FrozenFieldParams) and isinstance(state, FrozenFieldState)
    out = np.empty((2, 3, 3))
    with pytest.raises(ValueError, match="positions_ned"):
        frozen_field_sample(params, state, np.zeros((2, 2, 3)), np.zeros(2), out)
    with pytest.raises(ValueError, match="track_angle_rad"):
        frozen_field_sample(params, state, np.zeros((2, 3, 3)), np.zeros(3), out)
    with pytest.raises(ValueError, match="out_gust_ned"):
        frozen_field_sample(params, state, np.zeros((2, 3, 3)), np.zeros(2), np.empty((2, 3, 3), np.float32))
    with pytest.raises(ValueError, match="finite"):
        frozen_field_sample(params, state, np.full((2, 3, 3), np.nan), np.zeros(2), out)
    with pytest.raises(ValueError, match="seed"):
        frozen_field_reset(params, state, [0], [-1])
    with pytest.raises(ValueError, match="seeds"):
        frozen_field_reset(params, state, [0, 1], [1])
    with pytest.raises(ValueError, match="indices"):
        frozen_field_reset(params, state, [2], [1])
    with pytest.raises(ValueError, match="batch_size"):
        frozen_field_init(params, 0, 3)
    with pytest.raises(ValueError, match="state.ring"):
        frozen_field_advance(frozen_field_params(1.0, L_THESIS, V_THESIS, DT, buffer_s=1.0), state)
