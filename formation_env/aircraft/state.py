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
    "ALPHA_PREV", "STATE_NAMES", "make_state", "euler_angles", "altitude", "as_state",
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


def _b(x, n: int, width: int | None, name: str) -> np.ndarray:
    arr = np.asarray(x, dtype=float)
    shape = (n,) if width is None else (n, width)
    try:
        return np.broadcast_to(arr, shape)
    except ValueError:
        raise ValueError(f"make_state: {name} cannot be broadcast to {shape}, got {arr.shape}") from None


def make_state(velocity_body, rates_body=(0.0, 0.0, 0.0), euler_rad=(0.0, 0.0, 0.0),
               position_ned=(0.0, 0.0, -1000.0), fuel_kg=2.0, omega_rad_s=5000 * np.pi / 30,
               wind=None, batch_size: int | None = None) -> np.ndarray:
    """Build a (B, N_STATES) state. Vectors are (3,) or (B, 3); scalars or (B,).

    ``wind`` (a :class:`~formation_env.atmosphere.WindInput`) is used only to initialise the
    alpha-dot memory so that alpha-dot is 0 on the first step, as AeroSim's Derivative block is.
    """
    cands = [np.asarray(v) for v in (velocity_body, rates_body, euler_rad, position_ned)]
    n = batch_size or max([c.shape[0] if c.ndim == 2 else 1 for c in cands]
                          + [np.size(fuel_kg), np.size(omega_rad_s)])
    s = np.zeros((n, N_STATES))
    s[:, VEL] = _b(velocity_body, n, 3, "velocity_body")
    s[:, RATES] = _b(rates_body, n, 3, "rates_body")
    s[:, QUAT] = frames.quaternion_from_euler(_b(euler_rad, n, 3, "euler_rad"))
    s[:, POS] = _b(position_ned, n, 3, "position_ned")
    s[:, FUEL] = _b(fuel_kg, n, None, "fuel_kg")
    s[:, OMEGA] = _b(omega_rad_s, n, None, "omega_rad_s")
    from .eom import air_data_of  # local import: eom imports this module

    s[:, ALPHA_PREV] = air_data_of(s, wind)["alpha_raw"]
    return s


def euler_angles(state) -> np.ndarray:
    """(B, 3) Euler angles (phi, theta, psi) from the quaternion, rad."""
    return frames.euler_from_quaternion(as_state(state)[:, QUAT])


def altitude(state) -> np.ndarray:
    """(B,) altitude above the NED origin's sea-level datum, m (= -down)."""
    return -as_state(state)[:, POS.start + 2]
