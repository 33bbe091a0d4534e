"""Formation state: what ELL needs to know about each vehicle at one instant."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FormationState"]


@dataclass(frozen=True)
class FormationState:
    """Poses and air data of B formations of V vehicles (arrays with a leading batch axis).

    position_ned:  (B, V, 3) m, body origin of each vehicle in NED earth axes.
    euler_rad:     (B, V, 3) 3-2-1 Euler angles (phi, theta, psi), rad.
    airspeed_mps:  (B, V) true airspeed V > 0, m/s.
    alpha_rad:     (B, V) angle of attack, rad.
    beta_rad:      (B, V) sideslip angle, rad.

    Unbatched inputs (V, 3) / (V,) are promoted to a batch of one. Construction validates shapes
    and values and raises ValueError naming the offending field.
    """

    position_ned: np.ndarray
    euler_rad: np.ndarray
    airspeed_mps: np.ndarray
    alpha_rad: np.ndarray
    beta_rad: np.ndarray

    def __post_init__(self) -> None:
        pos = np.asarray(self.position_ned, dtype=float)
        if pos.ndim == 2:
            pos = pos[None]
        if pos.ndim != 3 or pos.shape[-1] != 3:
            raise ValueError(f"FormationState: position_ned must have shape (B, V, 3) or (V, 3), got {np.shape(self.position_ned)}")
        batch, nveh = pos.shape[:2]
        fields = {"position_ned": pos}
        for name in ("euler_rad",):
            arr = np.asarray(getattr(self, name), dtype=float)
            try:
                arr = np.broadcast_to(arr, (batch, nveh, 3))
            except ValueError:
                raise ValueError(f"FormationState: {name} must have shape {(batch, nveh, 3)}, got {arr.shape}") from None
            fields[name] = arr
        for name in ("airspeed_mps", "alpha_rad", "beta_rad"):
            raw = np.asarray(getattr(self, name), dtype=float)
            try:
                arr = np.broadcast_to(raw, (batch, nveh))
            except ValueError:
                raise ValueError(f"FormationState: {name} must broadcast to shape {(batch, nveh)}, got {raw.shape}") from None
            fields[name] = arr
        for name, arr in fields.items():
            if not np.all(np.isfinite(arr)):
                bad = arr[~np.isfinite(arr)].flat[0]
                raise ValueError(f"FormationState: {name} must be finite, got {bad!r}")
        if np.any(fields["airspeed_mps"] <= 0.0):
            bad = fields["airspeed_mps"][fields["airspeed_mps"] <= 0.0].flat[0]
            raise ValueError(f"FormationState: airspeed_mps must be > 0, got {bad!r}")
        for name, arr in fields.items():
            object.__setattr__(self, name, np.ascontiguousarray(arr, dtype=np.float64))

    @property
    def batch_size(self) -> int:
        return self.position_ned.shape[0]

    @property
    def n_vehicles(self) -> int:
        return self.position_ned.shape[1]

    @classmethod
    def from_degrees(cls, position_ned, euler_deg, airspeed_mps, alpha_deg, beta_deg=0.0) -> "FormationState":
        """Convenience constructor with angles in degrees (as printed in the thesis)."""
        return cls(
            position_ned=position_ned,
            euler_rad=np.radians(np.asarray(euler_deg, dtype=float)),
            airspeed_mps=airspeed_mps,
            alpha_rad=np.radians(np.asarray(alpha_deg, dtype=float)),
            beta_rad=np.radians(np.asarray(beta_deg, dtype=float)),
        )

    def select(self, index) -> "FormationState":
        """The formations ``index`` (an int, slice or index array) as a new batched state."""
        sl = np.atleast_1d(np.arange(self.batch_size)[index])
        return FormationState(self.position_ned[sl], self.euler_rad[sl], self.airspeed_mps[sl], self.alpha_rad[sl], self.beta_rad[sl])
