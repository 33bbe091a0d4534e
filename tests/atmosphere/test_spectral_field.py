"""The spectral (random Fourier mode) turbulence field against the theory of isotropic von Karman and
Dryden turbulence (formation_env.atmosphere.spectral_theory): one-point spectra, two-point
correlations, the leader-follower gust difference, each aircraft's RMS, the rotational gusts; its
seeding (batch == single, formations independent) and bad input.

Averages are over many realisations (formations): the modes' field is exact in expectation, a single
realisation is a sum of N cosines. Each tolerance is set from the sampling error measured over the same
number of realisations (quoted beside it), at 3-5 standard errors.
"""

import math

import numpy as np
import pytest
from scipy import signal

from formation_env.atmosphere.spectral_field import (DEFAULT_N_MODES, spectral_field_init, spectral_field_params,
                                                     spectral_field_reset, spectral_field_sample,
                                                     spectral_field_velocity)
from formation_env.atmosphere.spectral_field_kernels import sincos
from formation_env.atmosphere.spectral_theory import (FIELD_KINDS, correlation_fg, energy_spectrum,
                                                      gust_difference_theory, isotropic_correlation_kind,
                                                      mil_f_8785c_rotational_rms, one_point_spectrum,
                                                      rotational_gust_rms_theory)
from formation_env.constants import AEROSONDE_SPAN_M as B
from formation_env.geometry.presets import AEROSONDE_TAIL_ARM_M

L = 304.8  # the project's MIL-F-8785C scale length at 1000 m (1000 ft), every axis
V = 25.0
DT = 0.02
SLOT = np.array([-2 * B, B, 0.3 * B])  # the thesis formation-keeping slot (along, starboard, down)
_FIELDS: dict = {}


def field(kind, n, seed0=1000, n_modes=DEFAULT_N_MODES):
    """n formations of the ``kind`` field, seeds seed0 .. seed0 + n - 1 (cached)."""
    key = (kind, n, seed0, n_modes)
    if key not in _FIELDS:
        p = spectral_field_params(kind, 1.0, L, DT, n_modes=n_modes)
        st = spectral_field_init(p, n)
        spectral_field_reset(p, st, np.arange(n), list(range(seed0, seed0 + n)))
        _FIELDS[key] = (p, st)
    return _FIELDS[key]


def far_points(n, seed=0):
    """n points spread over 200 L (their samples of one realisation are nearly independent)."""
    return np.random.default_rng(seed).uniform(-100 * L, 100 * L, (n, 3))


# ------------------------------------------------------------------ the theory itself
@pytest.mark.parametrize("kind", FIELD_KINDS)
def test_theory_is_normalised(kind):
    from scipy import integrate
    e = integrate.quad(lambda k: energy_spectrum(kind, k, 1.0, L), 0, np.inf, limit=400)[0]
    f11 = 2 * integrate.quad(lambda k: one_point_spectrum(kind, k, 1.0, L)[0], 0, np.inf, limit=400)[0]
    f22 = 2 * integrate.quad(lambda k: one_point_spectrum(kind, k, 1.0, L)[1], 0, np.inf, limit=400)[0]
    scale = integrate.quad(lambda r: correlation_fg(kind, r, L)[0], 0, 60 * L, limit=400)[0]
    np.testing.assert_allclose([e, f11, f22, scale], [1.5, 1.0, 1.0, L], rtol=1e-6)
    # the notes' numbers at the thesis slot (|r| = 6.54 m)
    f, g = correlation_fg(kind, 6.54, L)
    expect = (0.939, 0.919) if kind == "von_karman" else (0.9788, 0.9683)
    np.testing.assert_allclose([f, g], expect, atol=6e-4)


def test_sincos_is_accurate():
    theta = np.concatenate([np.linspace(-10, 10, 2001), np.random.default_rng(0).uniform(-3e6, 3e6, 2000)])
    got = np.array([sincos(t) for t in theta])
    err = np.abs(got - np.stack([np.cos(theta), np.sin(theta)], 1))
    assert err[:2001].max() < 1e-13 and err.max() < 2e-10


# ------------------------------------------------------------------ one-point spectra
@pytest.mark.parametrize("kind", FIELD_KINDS)
def test_one_point_spectra_within_1p5_db_over_two_decades(kind):
    """u (along the line), v, w (across) along north lines of 16 km at 1 m, Welch (4096-point Hann
    segments), 96 realisations, in 4 bins per decade over k L = 1 .. 100 against 2 F11, 2 F22
    (one-sided). The realisations' standard error per bin is 0.12-0.23 dB (measured, 256 modes); 1.5 dB
    is 6-12 of it."""
    p, st = field(kind, 96)
    x = np.arange(16384.0)
    line = np.stack([x, np.zeros_like(x), np.zeros_like(x)], 1)
    psd = []
    for b in range(96):
        u = spectral_field_velocity(p, st, b, line + far_points(1, b)[0])
        k, pxx = signal.welch(u, fs=2 * np.pi, window="hann", nperseg=4096, axis=0)  # k in rad/m
        psd.append(pxx)
    psd = np.array(psd)  # (R, K, 3)
    f11, f22 = one_point_spectrum(kind, k, 1.0, L)
    target = 2.0 * np.stack([f11, f22, f22], 1)
    edges = np.logspace(0, 2, 9) / L
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (k >= lo) & (k < hi)
        est = psd[:, sel].mean(axis=1)  # (R, 3)
        db = 10 * np.log10(est.mean(0) / target[sel].mean(0))
        assert np.all(np.abs(db) < 1.5), (kind, lo * L, db)


# ------------------------------------------------------------------ two-point correlations
@pytest.mark.parametrize("kind", FIELD_KINDS)
def test_two_point_correlations_lateral_and_vertical(kind):
    """R_ii / sigma^2 at lateral 0.5-4 spans and vertical 0-1 span, 128 realisations x 64 points:
    rho = 1 - sum (u1 - u2)^2 / (sum u1^2 + sum u2^2) (from the structure function, whose error is a
    fraction of 1 - rho). Within 0.02 of the full spectrum's theory (the issue's tolerance), and 1 - rho
    within 10 % of the band-limited theory, what the modes have in expectation (f, g of E over
    [k_min, k_max], normalised by its variance): 5-6 of its standard errors (measured 1.5-2 %). The
    band matters here: the 0.27 % of the von Karman variance beyond k_max = 30 rad/m is 12 % of
    1 - rho at half a span."""
    p, st = field(kind, 128)
    band = (p.k_min, p.k_max)
    pts = far_points(64, 7)
    seps = [np.array([0, y * B, 0]) for y in (0.5, 1, 2, 4)] + [np.array([0, 0, z * B]) for z in (0.0, 0.25, 0.5, 1.0)]
    base = np.array([spectral_field_velocity(p, st, b, pts) for b in range(128)])
    for r in seps:
        other = np.array([spectral_field_velocity(p, st, b, pts + r) for b in range(128)])
        rho = 1 - ((other - base) ** 2).sum((0, 1)) / ((base**2).sum((0, 1)) + (other**2).sum((0, 1)))
        theory = isotropic_correlation_kind(kind, r, L)
        assert np.all(np.abs(rho - theory) < 0.02), (kind, r, rho, theory)
        if np.any(r):
            in_band = (isotropic_correlation_kind(kind, r, L, band)
                       / isotropic_correlation_kind(kind, np.zeros(3), L, band))
            np.testing.assert_allclose(1 - rho, 1 - in_band, rtol=0.10, err_msg=f"{kind} {r}")
        else:
            np.testing.assert_array_equal(rho, 1.0)


# ------------------------------------------------------------------ the leader-follower gust difference
@pytest.mark.parametrize("kind", FIELD_KINDS)
def test_gust_difference_rms_and_autocorrelation(kind):
    """A leader and a follower at the thesis slot fly north at V through the frozen field for 40 s
    (50 Hz), 160 realisations: RMS of the difference within 5 % of the theory (the issue's tolerance)
    and within 2 % of the band's (standard error 0.4 %; the band's RMS is 2 % below the full von Karman
    one), its autocorrelation at 0.1-2 s within 0.04 of the band's theory (standard error <= 0.011),
    and at 2 s below 0.08."""
    p, st = field(kind, 160)
    band = (p.k_min, p.k_max)
    t = np.arange(2000) * DT
    lead = np.stack([V * t, 0 * t, 0 * t], 1)
    d = np.array([spectral_field_velocity(p, st, b, lead + SLOT + 1e4 * b)
                  - spectral_field_velocity(p, st, b, lead + 1e4 * b) for b in range(160)])  # (R, T, 3)
    lag_steps = np.array([5, 12, 25, 50, 100])
    rms_full, _ = gust_difference_theory(kind, SLOT, L, V)
    rms_band, rho_band = gust_difference_theory(kind, SLOT, L, V, lag_steps * DT, band)
    rms = np.sqrt((d**2).mean((0, 1)))
    np.testing.assert_allclose(rms, rms_full, rtol=0.05)
    np.testing.assert_allclose(rms, rms_band, rtol=0.02)
    var = (d**2).mean((0, 1))
    for n, rho_t in zip(lag_steps, rho_band):
        rho = (d[:, :-n] * d[:, n:]).mean((0, 1)) / var
        assert np.all(np.abs(rho - rho_t) < 0.04), (kind, n * DT, rho, rho_t)
        if n == 100:
            assert np.all(np.abs(rho) < 0.08)


def test_in_line_follower_reads_the_leaders_gust_delayed():
    """Taylor: with no lateral and vertical offset a follower dx behind meets the leader's air dx / V
    later, exactly (calm air); with a steady wind the field moves with the air, u(x, t; W) = u(x - W t)."""
    p, st = field("von_karman", 1)
    pos = np.zeros((1, 2, 3))
    pos[0, 1, 0] = -10 * V * DT  # 10 steps behind
    gusts = np.array([spectral_field_sample(p, st, pos + [V * k * DT, 0, 0], k * DT)[0][0] for k in range(30)])
    np.testing.assert_allclose(gusts[10:, 1], gusts[:-10, 0], rtol=0, atol=1e-12)
    w = np.array([3.0, -4.0, 0.5])
    x = far_points(5, 3)
    np.testing.assert_array_equal(spectral_field_velocity(p, st, 0, x, time_s=7.3, wind_ned=w),
                                  spectral_field_velocity(p, st, 0, x - w * 7.3))


# ------------------------------------------------------------------ each aircraft's RMS
@pytest.mark.parametrize("kind", FIELD_KINDS)
def test_each_aircraft_rms_within_5_percent_of_sigma(kind):
    """A leader and a follower (thesis slot) in 256 formations, each sampled at 16 points along its
    flight spread 8 L apart: every UAV's RMS per axis within 5 % of sigma (times the variance the
    shells hold, > 99.7 %). Standard error over these realisations: ~1 % (16 points per path hold ~10
    independent samples each; a realisation's own variance spreads only 2 % at 256 lattice modes)."""
    p, st = field(kind, 256, seed0=50_000)
    held = math.sqrt((p.shell_amplitude**2).sum() / 6.0)  # the shells' variance: sum A_n^2 / 6
    steps = np.arange(16) * 8 * L
    pos = np.zeros((256, 2, 3))
    pos[:, 1] = SLOT
    g = np.array([spectral_field_sample(p, st, pos + [x, 0, 0], x / V)[0] for x in steps])  # (16, 256, 2, 3)
    rms = np.sqrt((g**2).mean((0, 1)))  # (2 UAVs, 3 axes)
    assert held > 0.997
    np.testing.assert_allclose(rms, held, rtol=0.05)


# ------------------------------------------------------------------ rotational gusts
def test_rotational_gusts_are_the_span_fit_and_tail_differences_of_the_field():
    """The kernel's p_g, q_g, r_g (from the CG's phases) equal the same quantities formed from the field
    itself at span and tail points: the least-squares slope of w over 4001 points along the span line,
    the central differences over the tail arm of w and v averaged over 4001 span points; a yawed
    formation (track angle 0.7 rad) with body axes along its track. Agreement to the quadrature error."""
    p, st = field("von_karman", 3)
    chi = 0.7
    c, s = math.cos(chi), math.sin(chi)
    along, cross = np.array([c, s, 0.0]), np.array([-s, c, 0.0])
    h, arm = 0.5 * B, AEROSONDE_TAIL_ARM_M
    y = np.linspace(-h, h, 4001)
    wts = np.full(4001, 1.0)
    wts[0] = wts[-1] = 0.5  # trapezoid weights
    for b in range(3):
        cg = far_points(1, 10 + b)[0]
        pos = np.zeros((3, 2, 3))
        pos[b, 0] = cg
        quat = np.zeros((3, 2, 4))
        quat[..., 0], quat[..., 3] = math.cos(chi / 2), math.sin(chi / 2)
        _, om = spectral_field_sample(p, st, pos, 0.0, 0.0, np.full(3, chi), quat)
        line = cg + y[:, None] * cross

        def track(u):  # NED -> (along, cross, down)
            return np.stack([u @ along, u @ cross, u[..., 2]], -1)

        w_line = track(spectral_field_velocity(p, st, b, line))
        p_fit = (wts * y * w_line[:, 2]).sum() / (wts * y * y).sum()
        fore = track(spectral_field_velocity(p, st, b, line + 0.5 * arm * along))
        aft = track(spectral_field_velocity(p, st, b, line - 0.5 * arm * along))
        mean = lambda u: (wts[:, None] * u).sum(0) / wts.sum()  # noqa: E731
        q_g = (mean(fore)[2] - mean(aft)[2]) / arm
        r_g = -(mean(fore)[1] - mean(aft)[1]) / arm
        np.testing.assert_allclose(om[b, 0], [p_fit, -q_g, -r_g], rtol=1e-5, atol=1e-6)  # rad/s; RMS ~0.1


@pytest.mark.parametrize("kind", FIELD_KINDS)
def test_rotational_gust_rms_against_theory(kind):
    """RMS of p_g, q_g, r_g over 512 realisations x 16 points within 6 % of the field's theory from its
    correlations (rotational_gust_rms_theory: the span's least-squares slope, the tail arm's central
    differences; standard error ~1.5 %). MIL-F-8785C's values (its Phi_p, Phi_q, Phi_r for span b) are
    a different weighting: printed beside for the docs, and the Dryden p_g within 15 % of it."""
    p, st = field(kind, 512, seed0=90_000)
    pos = np.zeros((512, 1, 3))
    om = np.array([spectral_field_sample(p, st, pos + [x, 0, 0], 0.0)[1][:, 0] for x in np.arange(16) * 8 * L])
    rms = np.sqrt((om**2).mean((0, 1)))
    theory = rotational_gust_rms_theory(kind, 1.0, L, B, AEROSONDE_TAIL_ARM_M)
    np.testing.assert_allclose(rms, theory, rtol=0.06)
    mil = mil_f_8785c_rotational_rms(kind, 1.0, L, B, V)
    print(kind, "rotational RMS", rms, "theory", theory, "MIL-F-8785C", mil)
    if kind == "dryden":
        assert abs(rms[0] / mil[0] - 1.0) < 0.15


# ------------------------------------------------------------------ seeds
def test_batch_equals_single_and_formations_are_independent():
    p = spectral_field_params("von_karman", 1.0, L, DT)
    seeds = [11, 12, 13]
    batch = spectral_field_init(p, 3)
    spectral_field_reset(p, batch, [0, 1, 2], seeds)
    x = far_points(50, 4)
    pos = np.broadcast_to(x[:2], (3, 2, 3))
    gb, ob = spectral_field_sample(p, batch, pos, 1.5, [1.0, 2.0, 0.0], 0.3)
    for i, sd in enumerate(seeds):
        one = spectral_field_init(p, 1)
        spectral_field_reset(p, one, [0], [sd])
        for name in ("wavevector", "amplitude", "phase"):
            np.testing.assert_array_equal(getattr(one, name)[0], getattr(batch, name)[i])
        g1, o1 = spectral_field_sample(p, one, pos[i:i + 1], 1.5, [1.0, 2.0, 0.0], 0.3)
        np.testing.assert_array_equal(g1[0], gb[i])
        np.testing.assert_array_equal(o1[0], ob[i])
    again = spectral_field_init(p, 3)
    spectral_field_reset(p, again, [2, 0], [13, 11])  # order and index do not matter
    np.testing.assert_array_equal(again.phase[2], batch.phase[2])
    assert not np.array_equal(batch.phase[0], batch.phase[1])
    # formations of one batch (consecutive seeds) are uncorrelated: 200 pairs x 64 points each,
    # |rho| < 4 standard errors (1 / sqrt(12800) = 0.009)
    p2, st = field("von_karman", 400, seed0=7)
    pts = far_points(64, 9)
    u = np.array([spectral_field_velocity(p2, st, b, pts) for b in range(400)])
    a, c = u[0::2].reshape(-1, 3), u[1::2].reshape(-1, 3)
    rho = (a * c).mean(0) / np.sqrt((a**2).mean(0) * (c**2).mean(0))
    assert np.all(np.abs(rho) < 4 / math.sqrt(a.shape[0])), rho


def test_zero_sigma_gives_zero_and_bad_input_raises():
    p = spectral_field_params("dryden", 0.0, L, DT, n_modes=8)
    st = spectral_field_init(p, 2)
    spectral_field_reset(p, st, [0, 1], [1, 2])
    g, o = spectral_field_sample(p, st, far_points(4, 1).reshape(2, 2, 3))
    assert not g.any() and not o.any()
    for kw, match in ((dict(kind="mann"), "kind"), (dict(sigma_mps=-1.0), "sigma"),
                      (dict(length_scale_m=0.0), "length"),
                      (dict(dt_s=np.nan), "dt_s"), (dict(n_modes=0), "n_modes"), (dict(n_modes=2.5), "n_modes"),
                      (dict(k_min=1.0, k_max=0.5), "k_max"), (dict(span_m=-2.0), "span_m")):
        args = dict(kind="von_karman", sigma_mps=1.0, length_scale_m=L, dt_s=DT) | kw
        with pytest.raises(ValueError, match=match):
            spectral_field_params(**args)
    with pytest.raises(ValueError, match="seed"):
        spectral_field_reset(p, st, [0], [-1])
    with pytest.raises(ValueError, match="indices"):
        spectral_field_reset(p, st, [2], [1])
    with pytest.raises(ValueError, match="positions_ned"):
        spectral_field_sample(p, st, np.zeros((3, 2, 3)))
    with pytest.raises(ValueError, match="positions_ned"):
        spectral_field_sample(p, st, np.full((2, 2, 3), np.nan))
    with pytest.raises(ValueError, match="index"):
        spectral_field_velocity(p, st, 5, np.zeros(3))
