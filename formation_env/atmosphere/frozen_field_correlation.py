"""The statistics the frozen turbulence field has (and the isotropic Dryden field it approximates):
Dryden f and g, the isotropic R_kk / sigma^2, and the correlation of two aircraft at a time lag.
numpy, analytic; see :mod:`.frozen_field` for the method."""

from __future__ import annotations

import numpy as np

__all__ = ["dryden_correlation", "isotropic_correlation", "frozen_field_theory"]


def dryden_correlation(r_m, length_scale_m):
    """Dryden longitudinal and transverse correlations (f, g) at distance ``r_m`` (array-like):
    f = exp(-r/L), g = (1 - r/(2L)) exp(-r/L)."""
    r = np.abs(np.asarray(r_m, dtype=np.float64))
    length = np.asarray(length_scale_m, dtype=np.float64)
    f = np.exp(-r / length)
    return f, (1.0 - r / (2.0 * length)) * f


def isotropic_correlation(separation_m, length_scale_m):
    """R_kk / sigma_k^2 of isotropic Dryden turbulence for separation vectors (..., 3) given in the
    track frame (along, cross, down); ``length_scale_m`` (3,) gives L per component. Returns
    (..., 3): (f - g) r_k^2 / r^2 + g with f, g at component k's scale length."""
    sep = np.asarray(separation_m, dtype=np.float64)
    length = np.broadcast_to(np.asarray(length_scale_m, dtype=np.float64), (3,))
    r = np.linalg.norm(sep, axis=-1)
    out = np.empty(sep.shape[:-1] + (3,))
    with np.errstate(invalid="ignore", divide="ignore"):
        for k in range(3):
            f, g = dryden_correlation(r, length[k])
            frac = np.where(r > 0.0, sep[..., k] ** 2 / np.where(r > 0.0, r, 1.0) ** 2, 0.0)
            out[..., k] = (f - g) * frac + g
    return out


def frozen_field_theory(separation_m, lag_s, length_scale_m, airspeed_mps, exact: bool = False):
    """Correlation (..., 3) between aircraft A at time t and aircraft B at t + ``lag_s``, B displaced
    from A by ``separation_m`` (..., 3) = (dx along, dy cross, dz down) in the track frame.

    ``exact=False``: what this module's field has, C^k(dy, dz) rho_k(lag + dx / V) with
    rho_u(s) = f(V s), rho_v = rho_w = g(V s) (within the transport buffer).
    ``exact=True``: an isotropic Dryden field frozen (Taylor): R_kk(dx + V lag, dy, dz) / sigma^2.
    """
    sep = np.asarray(separation_m, dtype=np.float64)
    lag = np.asarray(lag_s, dtype=np.float64)
    length = np.broadcast_to(np.asarray(length_scale_m, dtype=np.float64), (3,))
    v = float(airspeed_mps)
    sep, lag = np.broadcast_arrays(sep, lag[..., None])
    lag = lag[..., 0]
    if exact:
        moved = sep.copy()
        moved[..., 0] = sep[..., 0] + v * lag
        return isotropic_correlation(moved, length)
    cross = sep.copy()
    cross[..., 0] = 0.0
    c = isotropic_correlation(cross, length)
    s = np.abs(v * lag + sep[..., 0])
    out = np.empty_like(c)
    for k in range(3):
        f, g = dryden_correlation(s, length[k])
        out[..., k] = c[..., k] * (f if k == 0 else g)
    return out
