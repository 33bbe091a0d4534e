"""Table look-ups with linear extrapolation, as AeroSim's Simulink look-up blocks do."""

from __future__ import annotations

import numpy as np

__all__ = ["interp1_extrap", "interp2_extrap"]


def _segment(breaks: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Segment index (clamped to the end segments, which then extrapolate) and fraction."""
    xs = np.where(np.isfinite(x), x, breaks[0])
    i = np.clip(np.searchsorted(breaks, xs, side="right") - 1, 0, breaks.size - 2)
    frac = (x - breaks[i]) / (breaks[i + 1] - breaks[i])
    return i, frac


def interp1_extrap(breaks: np.ndarray, values: np.ndarray, x) -> np.ndarray:
    """Piecewise-linear interpolation in ``values(breaks)`` with linear extrapolation at both ends."""
    x = np.asarray(x, dtype=float)
    i, f = _segment(breaks, x)
    return values[i] + f * (values[i + 1] - values[i])


def interp2_extrap(rows: np.ndarray, cols: np.ndarray, table: np.ndarray, xr, xc) -> np.ndarray:
    """Bilinear interpolation in ``table[rows, cols]`` with bilinear extrapolation outside."""
    xr = np.asarray(xr, dtype=float)
    xc = np.asarray(xc, dtype=float)
    i, fr = _segment(rows, xr)
    j, fc = _segment(cols, xc)
    z00 = table[i, j]
    z10 = table[i + 1, j]
    z01 = table[i, j + 1]
    z11 = table[i + 1, j + 1]
    return (1.0 - fr) * ((1.0 - fc) * z00 + fc * z01) + fr * ((1.0 - fc) * z10 + fc * z11)
