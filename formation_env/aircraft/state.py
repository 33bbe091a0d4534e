"""Aircraft state layout and helpers. One row per aircraft: ``state`` has shape (B, N_STATES).

====  ==========  =========================================================================
col   name        meaning
====  ==========  =========================================================================
0-2   u v w       velocity of the aircraft relative to the ground, body axes, m/s
3-5   p q r       body angular rates, rad/s
6-9   e0 ex ey ez attitude quaternion, scalar first, body to NED (as stored; see eom.step)
10-12 n e d       position, flat-earth NED, m (altitude = -d)
13    fuel        fuel mass, kg
14    omega       engine/propeller shaft speed, rad/s
15    alpha_prev  raw angle of attack at the previous step (memory of the alpha-dot
                  backward difference; not integrated)
====  ==========  =========================================================================
"""

from __future__ import annotations

import numpy as np

from .. import frames

__all__ = [
    "N_STATES", "N_INTEGRATED", "IDX", "VEL", "RATES", "QUAT", "POS", "POS_N", "POS_E", "POS_D", "FUEL", "OMEGA",
    "ALPHA_PREV", "STATE_NAMES", "euler_angles", "altitude", "as_state",
]

VEL = slice(0, 3)
RATES = slice(3, 6)
QUAT = slice(6, 10)
POS = slice(10, 13)
POS_N, POS_E, POS_D = 10, 11, 12  # the columns of POS, for compiled code (numba indexes by integer constants)
FUEL = 13
OMEGA = 14
ALPHA_PREV = 15
N_INTEGRATED = 15
N_STATES = 16
STATE_NAMES = ("u", "v", "w", "p", "q", "r", "e0", "ex", "ey", "ez", "north", "east", "down",
               "fuel", "omega", "alpha_prev")
IDX = {name: i for i, name in enumerate(STATE_NAMES)}


def as_state(state) -> np.ndarray:
    """Validate a state array: float (B, N_STATES); a single (N_STATES,) row becomes (1, N_STATES)."""
    arr = np.asarray(state, dtype=float)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != N_STATES:
        raise ValueError(f"state must have shape (B, {N_STATES}), got {np.shape(state)}")
    return arr


def euler_angles(state) -> np.ndarray:
    """(B, 3) Euler angles (phi, theta, psi) from the quaternion, rad."""
    return frames.euler_from_quaternion(as_state(state)[:, QUAT])


def altitude(state) -> np.ndarray:
    """(B,) altitude above the NED origin's sea-level datum, m (= -down)."""
    return -as_state(state)[:, POS.start + 2]
