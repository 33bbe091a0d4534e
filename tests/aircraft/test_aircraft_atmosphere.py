"""Standard atmosphere, gravity, transient gust presets and Dryden turbulence."""

import numpy as np
import pytest

from formation_env.atmosphere import (
    DrydenConfig, DrydenTurbulence, TransientGust, WindInput, aircraft_seeds, gravity_wgs84,
    standard_atmosphere, thesis_gust_20s, thesis_gust_40s, thesis_gusts,
)
from formation_env.atmosphere.dryden import mil_f_8785c_low_altitude


def test_standard_atmosphere_sample_row():
    """Spec section 2: at 1000 m T = 281.65 K, p = 89874.57 Pa, rho = 1.1116, a = 336.434."""
    T, p, rho, a = standard_atmosphere(np.array([1000.0]))
    assert T[0] == pytest.approx(281.65, abs=0.01)
    assert p[0] == pytest.approx(89874.57, abs=0.5)
    assert rho[0] == pytest.approx(1.1116, abs=1e-4)
    assert a[0] == pytest.approx(336.434, abs=0.01)
    T0, p0, rho0, _ = standard_atmosphere(0.0)
    assert (T0, p0) == (pytest.approx(288.15), pytest.approx(101325.0))
    # clipped below 0 and piecewise linear between the 100 m breakpoints
    assert standard_atmosphere(-50.0)[2] == pytest.approx(rho0)
    mid = standard_atmosphere(1050.0)[2]
    assert mid == pytest.approx(0.5 * (standard_atmosphere(1000.0)[2] + standard_atmosphere(1100.0)[2]), rel=1e-12)
    # tropopause: isothermal above 11 km
    assert standard_atmosphere(15000.0)[0] == pytest.approx(216.65, abs=0.01)


def test_wgs84_gravity():
    assert gravity_wgs84(0.0, 0.0) == pytest.approx(9.7803267714)
    assert gravity_wgs84(np.pi / 2, 0.0) == pytest.approx(9.8321849, abs=3e-6)
    assert gravity_wgs84(np.deg2rad(45), 1000.0) == pytest.approx(9.8031, abs=1e-4)  # spec section 14


def test_thesis_gust_presets_match_definition():
    g40, g20 = thesis_gust_40s(), thesis_gust_20s()
    assert (g40.start_s, g40.end_s, g40.duration_s) == (10.0, 50.0, 40.0)
    assert (g20.start_s, g20.end_s, g20.duration_s) == (100.0, 120.0, 20.0)
    amp = np.asarray(g40.amplitude_ned)
    assert np.allclose(g40.wind_ned([0.0, 9.99, 50.0, 80.0]), 0.0)
    assert np.allclose(g40.wind_ned([20.0, 30.0, 40.0]), amp)  # maximum reached at t = 20 s (thesis)
    assert np.allclose(g40.wind_ned(15.0), 0.5 * amp)  # raised-cosine half way
    assert np.allclose(g40.wind_ned(45.0), 0.5 * amp)
    assert np.allclose(g20.wind_ned([105.0, 110.0, 115.0]), amp)
    assert np.allclose(g20.wind_ned([99.0, 121.0]), 0.0)
    # smooth: continuous, slope bounded by the raised-cosine maximum pi/(2 T_rise)
    t = np.linspace(0.0, 130.0, 130001)
    s = g40.shape(t) + g20.shape(t)
    slope = np.abs(np.diff(s)) / np.diff(t)
    assert slope.max() <= np.pi / (2 * 5.0) * (1 + 1e-6)
    assert np.allclose(thesis_gusts(t[::1000]), (s[::1000])[:, None] * amp)
    # monotone onset and decay
    up = g40.shape(np.linspace(10, 20, 101))
    assert np.all(np.diff(up) >= 0)


def test_gust_validation():
    with pytest.raises(ValueError, match="rise_s"):
        TransientGust(rise_s=0.0)
    with pytest.raises(ValueError, match="amplitude_ned"):
        TransientGust(amplitude_ned=(1.0, np.nan, 0.0))


def _record(turb: DrydenTurbulence, n: int) -> np.ndarray:
    out = np.empty((n, turb.batch_size, 3))
    for k in range(n):
        out[k] = turb.step()
    return out


def test_dryden_realised_rms_equals_sigma():
    sigma = (1.5, 1.0, 0.7)
    cfg = DrydenConfig(sigma, (150.0, 150.0, 40.0), airspeed_mps=25.0, dt=0.02)
    turb = DrydenTurbulence(cfg, aircraft_seeds(2024, 8))
    rec = _record(turb, 40000)  # 8 aircraft x 800 s, >= 130 correlation times each
    rms = np.sqrt(np.mean(rec**2, axis=(0, 1)))
    assert np.allclose(rms, sigma, rtol=0.10)
    # zero mean, and the u autocorrelation at one time constant L/V is exp(-1)
    assert np.all(np.abs(rec.mean(axis=(0, 1))) < 0.1 * np.asarray(sigma))
    lag = int(round(150.0 / 25.0 / 0.02))
    u = rec[:, :, 0]
    rho = np.mean(u[lag:] * u[:-lag]) / np.mean(u * u)
    assert rho == pytest.approx(np.exp(-1.0), abs=0.08)


def test_dryden_is_seeded_and_batch_equals_single():
    cfg = DrydenConfig.low_altitude(200.0, 10.0)
    seeds = aircraft_seeds(5, 3)
    batch = _record(DrydenTurbulence(cfg, seeds), 3000)
    for i, seed in enumerate(seeds):
        single = _record(DrydenTurbulence(cfg, [seed]), 3000)
        assert np.array_equal(batch[:, i], single[:, 0])
    again = DrydenTurbulence(cfg, seeds)
    again_rec = _record(again, 10)
    assert np.array_equal(again_rec, batch[:10])
    again.reset()
    assert np.array_equal(_record(again, 10), batch[:10])
    assert not np.allclose(batch[:, 0], batch[:, 1])


def test_mil_f_8785c_low_altitude_forms():
    (su, sv, sw), (lu, lv, lw) = mil_f_8785c_low_altitude(500 * 0.3048, 15.0)
    h = 500.0
    assert sw == pytest.approx(1.5)
    assert su == sv == pytest.approx(1.5 / (0.177 + 0.000823 * h) ** 0.4)
    assert lw == pytest.approx(h * 0.3048)
    assert lu == lv == pytest.approx(h / (0.177 + 0.000823 * h) ** 1.2 * 0.3048)
    # above 1000 ft the 1000 ft values hold (AeroSim): sigma_u = sigma_w, L = 1000 ft
    (su, _, sw), (lu, _, lw) = mil_f_8785c_low_altitude(1000.0, 15.0)
    assert su == pytest.approx(sw, rel=1e-3) and lu == pytest.approx(304.8, rel=1e-3) and lw == pytest.approx(304.8)


def test_wind_input_validation_and_broadcast():
    w = WindInput(wind_ned=np.zeros((4, 3)), ell_rotational_body=[0.0, 0.1, 0.0])
    assert w.batch_size == 4 and w.ell_rotational_body.shape == (4, 3)
    assert w.turbulence_body.shape == (4, 3)
    with pytest.raises(ValueError, match="NaN"):
        WindInput(wind_ned=[np.nan, 0, 0])
    with pytest.raises(ValueError, match="shape"):
        WindInput(turbulence_body=np.zeros((2, 2)))
    with pytest.raises(ValueError, match="rows"):
        WindInput(wind_ned=np.zeros((2, 3)), turbulence_body=np.zeros((3, 3)))
