"""The statistics of isotropic turbulence that the spectral (random Fourier mode) field has, in numpy and
scipy: von Karman and Dryden correlations f, g and energy spectra E(k), the one-point (1-D) spectra,
the two-point correlation R_ii, the leader-follower gust difference, and the rotational gusts' RMS
over the span and to the tail (the field's own theory) beside MIL-F-8785C's p_g, q_g, r_g.

Isotropic turbulence of intensity sigma and integral scale L (MIL-F-8785C / MIL-HDBK-1797 forms):

* von Karman, a = L Gamma(1/3) / (sqrt(pi) Gamma(5/6)) = 1.33898 L (MIL rounds it to 1.339 L):
  f(r) = 2^(2/3)/Gamma(1/3) (r/a)^(1/3) K_1/3(r/a), g(r) = f(r) - 2^(2/3)/Gamma(1/3) (r/a)^(1/3) (r/(2a)) K_2/3(r/a),
  E(k) = sigma^2 a 55/(9 sqrt(pi)) Gamma(5/6)/Gamma(1/3) (a k)^4 / (1 + (a k)^2)^(17/6),
  F11(k1) = sigma^2 L/pi (1 + (a k1)^2)^(-5/6), F22(k1) = sigma^2 L/(2 pi) (1 + 8/3 (a k1)^2) / (1 + (a k1)^2)^(11/6).
* Dryden: f(r) = exp(-r/L), g(r) = (1 - r/(2L)) exp(-r/L), E(k) = 8 sigma^2 L/pi (k L)^4 / (1 + (k L)^2)^3,
  F11 = sigma^2 L/pi / (1 + (L k1)^2), F22 = sigma^2 L/(2 pi) (1 + 3 (L k1)^2) / (1 + (L k1)^2)^2.

F11, F22 are two-sided (integral over all k1 = sigma^2): the MIL one-sided Phi(Omega) is 2 F(Omega).
R_ij(r) = sigma^2 [(f - g) r_i r_j / r^2 + g delta_ij]; integral of E over k = 3/2 sigma^2.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import integrate, special

__all__ = ["FIELD_KINDS", "VK_SCALE_RATIO", "correlation_fg", "energy_spectrum", "one_point_spectrum",
           "isotropic_correlation_kind", "gust_difference_theory", "rotational_gust_rms_theory",
           "mil_f_8785c_rotational_rms"]

FIELD_KINDS = ("von_karman", "dryden")
VK_SCALE_RATIO = special.gamma(1.0 / 3.0) / (math.sqrt(math.pi) * special.gamma(5.0 / 6.0))  # a / L = 1.33898
_VK_C = 2.0 ** (2.0 / 3.0) / special.gamma(1.0 / 3.0)
_VK_E = 55.0 / (9.0 * math.sqrt(math.pi)) * special.gamma(5.0 / 6.0) / special.gamma(1.0 / 3.0)


def _kind(kind: str) -> str:
    if kind not in FIELD_KINDS:
        raise ValueError(f"kind must be one of {FIELD_KINDS}, got {kind!r}")
    return kind


def correlation_fg(kind: str, r_m, length_scale_m: float, band=None):
    """Longitudinal and transverse correlations (f, g) at distances ``r_m`` (array-like, m) of the
    ``kind`` ("von_karman" | "dryden") with integral scale ``length_scale_m``; with ``band`` =
    (k_min, k_max) rad/m, those of the spectrum restricted to that band (what a mode field over it has in
    expectation; still relative to sigma^2, so f(0) = g(0) < 1 by the variance outside the band)."""
    if band is not None:
        return _band_fg(kind, r_m, float(length_scale_m), float(band[0]), float(band[1]))
    r = np.abs(np.asarray(r_m, dtype=np.float64))
    length = float(length_scale_m)
    if _kind(kind) == "dryden":
        f = np.exp(-r / length)
        return f, (1.0 - r / (2.0 * length)) * f
    x = r / (VK_SCALE_RATIO * length)
    with np.errstate(invalid="ignore", over="ignore"):
        xs = np.where(x > 0.0, x, 1.0)
        base = _VK_C * xs ** (1.0 / 3.0)
        f = base * special.kv(1.0 / 3.0, xs)
        g = f - base * 0.5 * xs * special.kv(2.0 / 3.0, xs)
    f = np.where(x > 0.0, f, 1.0)
    g = np.where(x > 0.0, g, 1.0)
    big = x > 700.0  # K_nu underflows: the correlation is 0 there
    return np.where(big, 0.0, f), np.where(big, 0.0, g)


def _band_fg(kind: str, r_m, length: float, k_min: float, k_max: float):
    """f, g of E restricted to [k_min, k_max]: f = 2 int E (sin x - x cos x) / x^3 dk,
    g = int E (sin x / x - (sin x - x cos x) / x^3) dk, x = k r (unit sigma), by Simpson's rule in ln k on
    a grid that resolves the oscillation at k_max r (the band's f, g are exact to ~1e-8)."""
    r = np.abs(np.asarray(r_m, dtype=np.float64))
    flat = r.reshape(-1)
    n = int(max(4001, 40 * (k_max * max(float(flat.max(initial=0.0)), 1e-9) / (2 * math.pi) + 1) * 8)) | 1
    lnk = np.linspace(math.log(k_min), math.log(k_max), n)
    k = np.exp(lnk)
    wts = np.full(n, 2.0)
    wts[1::2] = 4.0
    wts[0] = wts[-1] = 1.0
    ek = energy_spectrum(kind, k, 1.0, length) * k * wts * (lnk[1] - lnk[0]) / 3.0  # E dk = E k d(ln k)
    f = np.empty(flat.shape)
    g = np.empty(flat.shape)
    for i, ri in enumerate(flat):
        x = k * ri
        small = x < 1e-2
        xs = np.where(small, 1.0, x)
        a = np.where(small, 1.0 / 3.0 - x * x / 30.0 + x**4 / 840.0, (np.sin(xs) - xs * np.cos(xs)) / xs**3)
        sinc = np.where(small, 1.0 - x * x / 6.0 + x**4 / 120.0, np.sin(xs) / xs)
        f[i] = 2.0 * (ek * a).sum()
        g[i] = (ek * (sinc - a)).sum()
    return f.reshape(r.shape), g.reshape(r.shape)


def energy_spectrum(kind: str, k, sigma_mps: float, length_scale_m: float):
    """E(k), (m/s)^2 m, at wavenumbers ``k`` (rad/m): integral over k in (0, inf) = 3/2 sigma^2."""
    k = np.asarray(k, dtype=np.float64)
    s2, length = float(sigma_mps) ** 2, float(length_scale_m)
    if _kind(kind) == "dryden":
        x = k * length
        return 8.0 / math.pi * s2 * length * x**4 / (1.0 + x * x) ** 3
    a = VK_SCALE_RATIO * length
    x = k * a
    return _VK_E * s2 * a * x**4 / (1.0 + x * x) ** (17.0 / 6.0)


def one_point_spectrum(kind: str, k1, sigma_mps: float, length_scale_m: float):
    """Two-sided 1-D spectra (F11, F22) at wavenumbers ``k1`` (rad/m) along a line: F11 of the velocity
    component along the line, F22 of either one across it; each integrates to sigma^2 over all k1."""
    k1 = np.abs(np.asarray(k1, dtype=np.float64))
    s2, length = float(sigma_mps) ** 2, float(length_scale_m)
    if _kind(kind) == "dryden":
        x2 = (k1 * length) ** 2
        return s2 * length / math.pi / (1.0 + x2), s2 * length / (2.0 * math.pi) * (1.0 + 3.0 * x2) / (1.0 + x2) ** 2
    x2 = (k1 * VK_SCALE_RATIO * length) ** 2
    f11 = s2 * length / math.pi * (1.0 + x2) ** (-5.0 / 6.0)
    return f11, s2 * length / (2.0 * math.pi) * (1.0 + 8.0 / 3.0 * x2) / (1.0 + x2) ** (11.0 / 6.0)


def isotropic_correlation_kind(kind: str, separation_m, length_scale_m: float, band=None):
    """R_ii / sigma^2 (..., 3) for separation vectors (..., 3): (f - g) r_i^2 / r^2 + g (``band``: as
    :func:`correlation_fg`)."""
    sep = np.asarray(separation_m, dtype=np.float64)
    r = np.linalg.norm(sep, axis=-1)
    f, g = correlation_fg(kind, r, length_scale_m, band)
    with np.errstate(invalid="ignore", divide="ignore"):
        frac = np.where(r[..., None] > 0.0, sep**2 / np.where(r > 0.0, r, 1.0)[..., None] ** 2, 0.0)
    return (f - g)[..., None] * frac + g[..., None]


def gust_difference_theory(kind: str, separation_m, length_scale_m: float, airspeed_mps: float, lags_s=(), band=None):
    """The difference D = u(follower) - u(leader) of a pair displaced by ``separation_m`` (3,) (along,
    cross, down; any frame, the field is isotropic), both flying at ``airspeed_mps`` along the first axis
    through the frozen field: (RMS(D) / sigma (3,), autocorrelation of D at ``lags_s`` (n, 3)),
    rho_D(tau) = (2 R(s) - R(s - r) - R(s + r)) / (2 R(0) - 2 R(r)), s = (V tau, 0, 0) (``band``: as
    :func:`correlation_fg`)."""
    r = np.asarray(separation_m, dtype=np.float64)

    def corr(sep):
        return isotropic_correlation_kind(kind, sep, length_scale_m, band)

    var = 2.0 * (corr(np.zeros(3)) - corr(r))
    rho = []
    for tau in np.atleast_1d(np.asarray(lags_s, dtype=np.float64)):
        s = np.array([airspeed_mps * tau, 0.0, 0.0])
        rho.append((2.0 * corr(s) - corr(s - r) - corr(s + r)) / var)
    return np.sqrt(var), np.array(rho).reshape(-1, 3)


def rotational_gust_rms_theory(kind: str, sigma_mps: float, length_scale_m: float, span_m: float, tail_arm_m: float):
    """RMS (rad/s) of the rotational gusts (p_g, q_g, r_g) as the spectral field defines them, from the
    correlations alone (independent of the modes), h = b/2, l the tail arm:

    * p_g: the least-squares slope of w over the span line y in [-h, h] (the ELL's linear fit over evenly
      spread points): var = 9 / (4 h^6) int int y1 y2 R_ww(0, y1 - y2, 0) dy1 dy2;
    * q_g = dw/dx, r_g = -dv/dx: central differences over the tail arm of the span-averaged w and v,
      var = 2 (C(0) - C(l)) / l^2, C(dx) = int_{-2h}^{2h} (2h - |s|) / (2h)^2 R(dx, s, 0) ds
      (R_ww = sigma^2 g, R_vv = sigma^2 ((f - g) s^2 / r^2 + g), r = |(dx, s)|)."""
    s2, length_scale = float(sigma_mps) ** 2, float(length_scale_m)
    h, arm = 0.5 * float(span_m), float(tail_arm_m)
    pieces = ((0.0, 1e-3 * h), (1e-3 * h, 0.1 * h), (0.1 * h, 2.0 * h))  # the r^(2/3) cusp of g at 0

    def quad(fun):
        return sum(integrate.quad(fun, a, b, limit=200, epsabs=0.0, epsrel=1e-11)[0] for a, b in pieces)

    def slope_kernel(s):  # integral of y2 (y2 + s) over the y2 where y2 and y2 + s lie in [-h, h], s >= 0
        lo, hi = -h, h - s
        return (hi**3 - lo**3) / 3.0 + s * (hi**2 - lo**2) / 2.0

    var_p = 9.0 / (4.0 * h**6) * s2 * quad(
        lambda s: 2.0 * slope_kernel(s) * float(correlation_fg(kind, s, length_scale)[1]))

    def r_ww(dx, s):
        return float(correlation_fg(kind, math.hypot(dx, s), length_scale)[1])

    def r_vv(dx, s):
        r = math.hypot(dx, s)
        f, g = (float(x) for x in correlation_fg(kind, r, length_scale))
        return (f - g) * s * s / r**2 + g if r > 0.0 else 1.0

    def averaged(cov, dx):
        return quad(lambda s: 2.0 * (2.0 * h - s) / (2.0 * h) ** 2 * cov(dx, s))

    var_q = 2.0 * s2 * (averaged(r_ww, 0.0) - averaged(r_ww, arm)) / arm**2
    var_r = 2.0 * s2 * (averaged(r_vv, 0.0) - averaged(r_vv, arm)) / arm**2
    return np.sqrt(np.array([var_p, var_q, var_r]))


def mil_f_8785c_rotational_rms(kind: str, sigma_mps: float, length_scale_m: float, span_m: float, airspeed_mps: float):
    """RMS (rad/s) of MIL-F-8785C's p_g, q_g, r_g (its spectra, one-sided in omega rad/s):
    Phi_p = sigma_w^2 / (V L_w) 0.8 (pi L_w / (4 b))^(1/3) / (1 + (4 b omega / (pi V))^2),
    Phi_q = (omega/V)^2 / (1 + (4 b omega / (pi V))^2) Phi_w(omega), Phi_r the same with Phi_v; Phi_w, Phi_v
    the ``kind``'s transverse spectra (Phi(omega) = 2 F22(omega / V) / V)."""
    s2, length, b, v = float(sigma_mps) ** 2, float(length_scale_m), float(span_m), float(airspeed_mps)
    c = 4.0 * b / (math.pi * v)
    var_p = s2 / (v * length) * 0.8 * (math.pi * length / (4.0 * b)) ** (1.0 / 3.0) * math.pi / (2.0 * c)

    def phi_q(w):
        return (w / v) ** 2 / (1.0 + (c * w) ** 2) * 2.0 * one_point_spectrum(kind, w / v, 1.0, length)[1] / v

    var_q = s2 * sum(integrate.quad(phi_q, a, bb, limit=400)[0]
                     for a, bb in ((0.0, 1.0), (1.0, 100.0), (100.0, np.inf)))
    return np.sqrt(np.array([var_p, var_q, var_q]))
