"""Divergence and flight-envelope check: one status per aircraft, so the env can end episodes.

A diverged simulation must never emit NaN silently: :func:`step` keeps integrating every row
(one bad aircraft does not poison the batch) and this check says which rows are no longer valid.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from ..atmosphere.wind import WindInput
from .eom import air_data_of
from .params import AEROSONDE, AerosondeParams
from .state import FUEL, OMEGA, QUAT, as_state

__all__ = ["Status", "EnvelopeLimits", "check_envelope", "describe_status"]


class Status(enum.IntFlag):
    """Bit flags; 0 (OK) means the aircraft is valid. Several bits can be set at once."""

    OK = 0
    NON_FINITE = 1
    AIRSPEED_LOW = 2
    AIRSPEED_HIGH = 4
    ALTITUDE_LOW = 8
    ALTITUDE_HIGH = 16
    ATTITUDE = 32  # |phi| or |theta| beyond the limits
    ENGINE_STOPPED = 64  # shaft speed below the minimum (the engine torque P/Omega is singular at 0)
    OUT_OF_FUEL = 128


@dataclass(frozen=True)
class EnvelopeLimits:
    """Validity limits. The aerodynamic model clips airspeed to [15, 50] m/s, alpha to
    [-0.1, 0.3] rad and beta to +-0.5 rad; outside roughly these bounds the data mean nothing, so
    the defaults end an episode a little beyond them. ``altitude_min_m`` plays the ground."""

    airspeed_min_mps: float = 12.0
    airspeed_max_mps: float = 55.0
    altitude_min_m: float = 0.0
    altitude_max_m: float = 6000.0
    max_bank_rad: float = float(np.deg2rad(80.0))
    max_pitch_rad: float = float(np.deg2rad(60.0))
    omega_min_rad_s: float = 50.0
    flag_out_of_fuel: bool = True

    def __post_init__(self) -> None:
        for name in ("airspeed_min_mps", "airspeed_max_mps", "altitude_min_m", "altitude_max_m",
                     "max_bank_rad", "max_pitch_rad", "omega_min_rad_s"):
            if not np.isfinite(getattr(self, name)):
                raise ValueError(f"EnvelopeLimits.{name} must be finite")
        if not 0.0 <= self.airspeed_min_mps < self.airspeed_max_mps:
            raise ValueError("EnvelopeLimits.airspeed_min_mps must be >= 0 and < airspeed_max_mps")
        if not self.altitude_min_m < self.altitude_max_m:
            raise ValueError("EnvelopeLimits.altitude_min_m must be < altitude_max_m")
        if not (0.0 < self.max_bank_rad <= np.pi and 0.0 < self.max_pitch_rad <= np.pi / 2):
            raise ValueError("EnvelopeLimits.max_bank_rad must be in (0, pi], max_pitch_rad in (0, pi/2]")


DEFAULT_LIMITS = EnvelopeLimits()


def check_envelope(state, wind: WindInput | None = None, limits: EnvelopeLimits = DEFAULT_LIMITS,
                   params: AerosondeParams = AEROSONDE) -> np.ndarray:
    """Status flags (B,) int array; ``status == 0`` where the aircraft is valid.

    Airspeed is the raw air-relative speed with ``wind`` (still air if None).
    """
    s = as_state(state)
    status = np.zeros(s.shape[0], dtype=np.int64)
    finite = np.all(np.isfinite(s), axis=1)
    status[~finite] |= Status.NON_FINITE
    with np.errstate(all="ignore"):
        ad = air_data_of(s, wind, params)
        va = ad["airspeed_raw"]
        alt = -s[:, 12]
        q = s[:, QUAT]
        e0, ex, ey, ez = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
        n2 = e0 * e0 + ex * ex + ey * ey + ez * ez
        phi = np.arctan2(2 * (e0 * ex + ey * ez), e0 * e0 - ex * ex - ey * ey + ez * ez)
        theta = np.arcsin(np.clip(2 * (e0 * ey - ex * ez) / n2, -1, 1))
        checks = (
            (va < limits.airspeed_min_mps, Status.AIRSPEED_LOW),
            (va > limits.airspeed_max_mps, Status.AIRSPEED_HIGH),
            (alt < limits.altitude_min_m, Status.ALTITUDE_LOW),
            (alt > limits.altitude_max_m, Status.ALTITUDE_HIGH),
            ((np.abs(phi) > limits.max_bank_rad) | (np.abs(theta) > limits.max_pitch_rad), Status.ATTITUDE),
            (s[:, OMEGA] < limits.omega_min_rad_s, Status.ENGINE_STOPPED),
        )
        for cond, flag in checks:
            status[finite & cond] |= flag
        if limits.flag_out_of_fuel:
            status[finite & (s[:, FUEL] <= 0.0)] |= Status.OUT_OF_FUEL
    return status


def describe_status(code: int) -> str:
    """Human-readable form of one status code, e.g. 'AIRSPEED_LOW|ALTITUDE_LOW'."""
    code = int(code)
    if code == 0:
        return "OK"
    return "|".join(f.name for f in Status if f.value and code & f.value)
