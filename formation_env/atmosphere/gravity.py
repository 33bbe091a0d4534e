"""Gravity: a constant (9.81 m/s^2, the value that reproduces the thesis trim) or WGS-84 normal gravity."""

from __future__ import annotations

import numpy as np

__all__ = ["G_CONSTANT", "gravity_wgs84"]

G_CONSTANT = 9.81
_WGS84_E2 = 0.0818191908426**2


def gravity_wgs84(latitude_rad, altitude_m):
    """WGS-84 normal gravity with the free-air altitude correction (AeroSim WGS-84 block)."""
    s2 = np.sin(np.asarray(latitude_rad, dtype=float)) ** 2
    h = np.asarray(altitude_m, dtype=float)
    g0 = 9.7803267714 * (1.0 + 0.00193185138639 * s2) / np.sqrt(1.0 - _WGS84_E2 * s2)
    return g0 - (3.0877e-6 - 0.0044e-6 * s2) * h + 0.072e-12 * h * h
