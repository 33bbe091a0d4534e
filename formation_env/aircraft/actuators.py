"""Optional actuator model: position limits, rate limits and a first-order lag per channel.

AeroSim's Aerosonde has no actuators and no limits (its optional library actuator is a
first-order lag with rate limit); this project's defaults are documented choices for a small UAV:

=========  ==================  ===============  ============
channel    position limits     rate limit       lag (tau)
=========  ==================  ===============  ============
elevator   +-0.4363 rad (25 deg)  3.49 rad/s (200 deg/s)  0.05 s
aileron    +-0.4363 rad           3.49 rad/s              0.05 s
rudder     +-0.4363 rad           3.49 rad/s              0.05 s
throttle   [0, 1]                 2.0 /s                  0.10 s
=========  ==================  ===============  ============

Commands outside the position limits are clipped. Per step of dt: the command is clipped, the
lag is applied exactly for a held input (``x += (1 - exp(-dt/tau)) (u - x)``, tau = 0 means no
lag), the change is rate-limited to ``rate * dt`` and the result clipped again.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ActuatorConfig", "Actuators", "clip_controls", "DEFAULT_ACTUATORS"]

_SURF = float(np.deg2rad(25.0))
_RATE = float(np.deg2rad(200.0))


@dataclass(frozen=True)
class ActuatorConfig:
    """Per channel [elevator, aileron, rudder, throttle]: limits, rate limit (units/s; inf = none)
    and first-order time constant (s; 0 = none)."""

    lower: tuple[float, float, float, float] = (-_SURF, -_SURF, -_SURF, 0.0)
    upper: tuple[float, float, float, float] = (_SURF, _SURF, _SURF, 1.0)
    rate: tuple[float, float, float, float] = (_RATE, _RATE, _RATE, 2.0)
    tau: tuple[float, float, float, float] = (0.05, 0.05, 0.05, 0.10)

    def __post_init__(self) -> None:
        for name in ("lower", "upper", "rate", "tau"):
            vals = tuple(float(x) for x in getattr(self, name))
            if len(vals) != 4 or any(np.isnan(vals)):
                raise ValueError(f"ActuatorConfig.{name} must be 4 numbers (elevator, aileron, rudder, throttle)")
            object.__setattr__(self, name, vals)
        if any(not (np.isfinite(lo) and np.isfinite(hi) and lo < hi) for lo, hi in zip(self.lower, self.upper)):
            raise ValueError("ActuatorConfig.lower must be below upper, both finite")
        if any(r <= 0.0 for r in self.rate):
            raise ValueError("ActuatorConfig.rate must be positive (inf for no limit)")
        if any(not (np.isfinite(t) and t >= 0.0) for t in self.tau):
            raise ValueError("ActuatorConfig.tau must be finite and >= 0")


DEFAULT_ACTUATORS = ActuatorConfig()


def clip_controls(controls, config: ActuatorConfig = DEFAULT_ACTUATORS) -> np.ndarray:
    """Clip (B, 4) commands to the position limits (no dynamics)."""
    c = np.asarray(controls, dtype=float)
    return np.clip(c, np.asarray(config.lower), np.asarray(config.upper))


class Actuators:
    """Actuator states for B aircraft. ``update(commands, dt)`` returns the deflections to fly."""

    def __init__(self, initial, config: ActuatorConfig = DEFAULT_ACTUATORS):
        self.config = config
        init = np.atleast_2d(np.asarray(initial, dtype=float))
        if init.ndim != 2 or init.shape[1] != 4 or not np.all(np.isfinite(init)):
            raise ValueError(f"Actuators: initial positions must be finite (B, 4), got shape {np.shape(initial)}")
        self.position = clip_controls(init, config)
        self._lo = np.asarray(config.lower)
        self._hi = np.asarray(config.upper)
        self._rate = np.asarray(config.rate)
        self._tau = np.asarray(config.tau)

    def update(self, commands, dt: float) -> np.ndarray:
        cmd = np.asarray(commands, dtype=float)
        if cmd.ndim == 1:
            cmd = cmd[None, :]
        if cmd.shape != self.position.shape:
            raise ValueError(f"Actuators: commands must have shape {self.position.shape}, got {np.shape(commands)}")
        if not np.all(np.isfinite(cmd)):
            raise ValueError("Actuators: commands contain NaN or inf")
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"Actuators: dt must be positive, got {dt!r}")
        target = np.clip(cmd, self._lo, self._hi)
        with np.errstate(divide="ignore"):
            gain = np.where(self._tau > 0.0, 1.0 - np.exp(-dt / np.where(self._tau > 0, self._tau, 1.0)), 1.0)
        delta = gain * (target - self.position)
        max_delta = self._rate * dt
        delta = np.clip(delta, -max_delta, max_delta)
        self.position = np.clip(self.position + delta, self._lo, self._hi)
        return self.position.copy()
