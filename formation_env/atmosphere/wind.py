"""The wind one integration step sees, per aircraft.

Everything is *air-mass velocity* (where the air goes), held constant over one RK4 step:

* ``wind_ned`` (B, 3): steady wind + transient gust, NED, m/s.
* ``turbulence_body`` (B, 3): Dryden turbulence velocities in body axes, m/s (MIL-F-8785C defines
  them along the aircraft axes; AeroSim adds them to the body-axis wind in the same way).
* ``ell_translational_ned`` (B, 3): the ELL effective induced translational wind, NED (thesis Eq. 4.8).
* ``ell_rotational_body`` (B, 3): the ELL effective induced rotational wind in body axes, rad/s
  (thesis Eq. 4.9); it is subtracted from the body rates the aerodynamics see.

The aircraft's air-relative velocity is ``V_body - C_bn (wind_ned + ell_translational_ned) - turbulence_body``.
The NED parts are rotated with the attitude of each RK4 stage.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["WindInput", "steady_wind"]

_FIELDS = ("wind_ned", "turbulence_body", "ell_translational_ned", "ell_rotational_body")


def _as_b3(name: str, value, n: int | None) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"WindInput.{name} must have shape (B, 3) or (3,), got {np.shape(value)}")
    if n is not None and arr.shape[0] != n:
        if arr.shape[0] == 1:
            arr = np.broadcast_to(arr, (n, 3))
        else:
            raise ValueError(f"WindInput.{name} has {arr.shape[0]} rows, expected {n}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"WindInput.{name} contains NaN or inf")
    return arr


@dataclass(frozen=True, eq=False)
class WindInput:
    """Per-aircraft wind for one step. Omitted parts are zero; a (3,) or (1, 3) part broadcasts."""

    wind_ned: np.ndarray | None = None
    turbulence_body: np.ndarray | None = None
    ell_translational_ned: np.ndarray | None = None
    ell_rotational_body: np.ndarray | None = None

    def __post_init__(self) -> None:
        rows = [np.atleast_2d(np.asarray(getattr(self, f))).shape[0] for f in _FIELDS if getattr(self, f) is not None]
        n = max(rows) if rows else 1
        for f in _FIELDS:
            v = getattr(self, f)
            object.__setattr__(self, f, np.zeros((n, 3)) if v is None else _as_b3(f, v, n))

    @property
    def batch_size(self) -> int:
        return self.wind_ned.shape[0]

    @classmethod
    def zeros(cls, batch_size: int = 1) -> "WindInput":
        return cls(wind_ned=np.zeros((int(batch_size), 3)))

    def for_batch(self, batch_size: int) -> "WindInput":
        """The same wind broadcast to ``batch_size`` aircraft (only if it is for 1 or that many)."""
        if self.batch_size == batch_size:
            return self
        if self.batch_size != 1:
            raise ValueError(f"wind is for {self.batch_size} aircraft, state for {batch_size}")
        return WindInput(*(np.broadcast_to(getattr(self, f), (batch_size, 3)) for f in _FIELDS))

    def select(self, index) -> "WindInput":
        """Rows ``index`` (an int keeps a batch axis of 1)."""
        idx = [index] if np.isscalar(index) else index
        return WindInput(*(getattr(self, f)[idx] for f in _FIELDS))

    def total_translational_ned(self) -> np.ndarray:
        """The NED part of the air-mass velocity (steady + gust + ELL translational)."""
        return self.wind_ned + self.ell_translational_ned


def steady_wind(wind_ned, batch_size: int = 1) -> WindInput:
    """A steady NED wind (m/s), the same for ``batch_size`` aircraft unless given per aircraft."""
    arr = np.asarray(wind_ned, dtype=float)
    if arr.ndim == 1:
        arr = np.broadcast_to(arr, (batch_size, 3))
    return WindInput(wind_ned=arr)
