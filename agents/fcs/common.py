"""Small helpers shared by the FCS layers (pure, batched)."""

from __future__ import annotations

import numpy as np

__all__ = ["wrap_angle", "pi_integrator_rate", "saturate"]


def wrap_angle(x: np.ndarray) -> np.ndarray:
    """Angle wrapped into [-pi, pi)."""
    return (np.asarray(x) + np.pi) % (2.0 * np.pi) - np.pi


def saturate(x: np.ndarray, lo, hi) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(clipped, at_upper, at_lower)``: the saturated value and where each limit is active."""
    x = np.asarray(x, dtype=float)
    return np.clip(x, lo, hi), x > hi, x < lo


def pi_integrator_rate(error: np.ndarray, ki: float, at_upper: np.ndarray, at_lower: np.ndarray,
                       anti_windup: bool) -> np.ndarray:
    """Rate of a PI controller's error integrator with conditional-integration anti-windup:
    the integral is frozen while the output is saturated and the error would drive it further
    into the limit (``ki * error`` has the sign of the exceeded limit)."""
    if not anti_windup:
        return error
    push = ki * error
    frozen = (at_upper & (push > 0.0)) | (at_lower & (push < 0.0))
    return np.where(frozen, 0.0, error)
