"""1976 US Standard Atmosphere, as AeroSim uses it: linear interpolation in a 100 m table.

AeroSim (``stdatm.mat``) interpolates a table of altitude 0..86 km in 100 m steps; the
table here is generated from the 1976 layer definitions at the same breakpoints, so the model sees
the same piecewise-linear atmosphere (that matters for the linearisation: the heave mode comes from
the density gradient).
"""

from __future__ import annotations

import numpy as np

__all__ = ["standard_atmosphere", "atmosphere_table", "R_AIR", "GAMMA_AIR"]

R_AIR = 287.05287  # J/(kg K), 1976 value R*/M0
GAMMA_AIR = 1.4
_G0 = 9.80665
_STEP_M = 100.0
_TOP_M = 86000.0

# Geopotential layer bases (m) and lapse rates (K/m), 1976 standard, up to 84.852 km geopotential.
_LAYERS_H = np.array([0.0, 11000.0, 20000.0, 32000.0, 47000.0, 51000.0, 71000.0, 84852.0])
_LAYERS_LAPSE = np.array([-0.0065, 0.0, 0.001, 0.0028, 0.0, -0.0028, -0.002])


def _exact(h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Temperature (K) and pressure (Pa) of the 1976 model at geopotential altitude h.

    AeroSim's table is indexed by the altitude taken as geopotential: its 1000 m row (T = 281.65 K,
    p = 89874.57 Pa) is the 1976 value at 1000 m geopotential (89876 Pa would be geometric). The
    difference is 0.002 % in pressure at 1 km; following the table keeps the trim digits.
    """
    t_base, p_base = 288.15, 101325.0
    temp = np.empty_like(h)
    pres = np.empty_like(h)
    for i, lapse in enumerate(_LAYERS_LAPSE):
        lo, hi = _LAYERS_H[i], _LAYERS_H[i + 1]
        sel = (h >= lo) & ((h < hi) | (i == len(_LAYERS_LAPSE) - 1))
        dh = h[sel] - lo
        if lapse == 0.0:
            temp[sel] = t_base
            pres[sel] = p_base * np.exp(-_G0 * dh / (R_AIR * t_base))
        else:
            temp[sel] = t_base + lapse * dh
            pres[sel] = p_base * (temp[sel] / t_base) ** (-_G0 / (R_AIR * lapse))
        # advance the base values to the top of this layer
        top = hi - lo
        if lapse == 0.0:
            p_base = p_base * np.exp(-_G0 * top / (R_AIR * t_base))
        else:
            t_top = t_base + lapse * top
            p_base = p_base * (t_top / t_base) ** (-_G0 / (R_AIR * lapse))
            t_base = t_top
    return temp, pres


def _build_table() -> np.ndarray:
    z = np.arange(0.0, _TOP_M + 0.5 * _STEP_M, _STEP_M)
    temp, pres = _exact(z)
    rho = pres / (R_AIR * temp)
    a = np.sqrt(GAMMA_AIR * R_AIR * temp)
    table = np.stack([z, temp, pres, rho, a], axis=-1)
    table.setflags(write=False)
    return table


_TABLE = _build_table()
_T, _P, _RHO, _A = (np.ascontiguousarray(_TABLE[:, k]) for k in (1, 2, 3, 4))


def atmosphere_table() -> np.ndarray:
    """The table (columns: h m, T K, p Pa, rho kg/m^3, a m/s), read-only."""
    return _TABLE


def standard_atmosphere(altitude_m) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Temperature (K), static pressure (Pa), density (kg/m^3), speed of sound (m/s).

    ``altitude_m`` (any shape) is the altitude above mean sea level; it is clipped to [0, 86000] m
    as in AeroSim. Non-finite altitudes give non-finite outputs (the envelope check reports them).
    """
    h = np.clip(np.asarray(altitude_m, dtype=float), 0.0, _TOP_M) / _STEP_M
    finite = np.isfinite(h)
    hs = np.where(finite, h, 0.0)
    i = np.minimum(hs.astype(np.int64), _T.size - 2)
    f = hs - i
    f = np.where(finite, f, np.nan)
    temp = _T[i] + f * (_T[i + 1] - _T[i])
    pres = _P[i] + f * (_P[i + 1] - _P[i])
    rho = _RHO[i] + f * (_RHO[i + 1] - _RHO[i])
    a = _A[i] + f * (_A[i + 1] - _A[i])
    return temp, pres, rho, a
