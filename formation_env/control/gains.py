"""Gains and structure of the thesis FCS (Appendix A), as printed in Tables A.8-A.10 and A.13.

The gains keep the thesis's printed signs; :mod:`formation_env.control` applies them with the sign
conventions (documented in ``docs/fcs.md``) that make the printed numbers do on this model what
the thesis describes. Every dataclass is frozen and validated (``ValueError`` names the field).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

__all__ = ["SASGains", "AttitudeGains", "AutopilotGains", "TrackerGains", "FCSStructure", "FCSConfig"]


def _check_finite(obj) -> None:
    for f in fields(obj):
        v = getattr(obj, f.name)
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            if not math.isfinite(float(v)):
                raise ValueError(f"{type(obj).__name__}.{f.name} must be finite, got {v!r}")


@dataclass(frozen=True)
class SASGains:
    """Table A.8: pitch stabiliser, yaw damper with washout, spiral stabiliser, interlink."""

    K_q_elevator: float = -0.28  # rad elevator per rad/s of pitch rate
    K_theta_elevator: float = -1.0  # rad elevator per rad of pitch attitude
    K_r_rudder: float = -0.25  # rad rudder per rad/s of (washed-out) yaw rate
    T_r_washout_s: float = 0.75  # washout time constant, s
    K_phi_aileron: float = -0.2  # rad aileron per rad of bank
    K_aileron_rudder_interlink: float = 0.5  # rad rudder per rad aileron

    def __post_init__(self) -> None:
        _check_finite(self)
        if self.T_r_washout_s <= 0.0:
            raise ValueError(f"SASGains.T_r_washout_s must be > 0, got {self.T_r_washout_s!r}")


@dataclass(frozen=True)
class AttitudeGains:
    """Table A.9: pitch and bank P+I (wrapped around the SAS)."""

    Kp_theta: float = -0.8
    Ki_theta: float = -0.8
    Kp_phi: float = -0.2
    Ki_phi: float = -0.1

    def __post_init__(self) -> None:
        _check_finite(self)


@dataclass(frozen=True)
class AutopilotGains:
    """Table A.10: altitude PID -> pitch demand, heading PI -> bank demand, speed PI -> throttle."""

    Kp_altitude: float = -0.03
    Ki_altitude: float = -0.0001
    Kd_altitude: float = -0.05
    Kp_heading: float = 0.7
    Ki_heading: float = 0.001
    Kp_speed: float = 0.5
    Ki_speed: float = 0.15

    def __post_init__(self) -> None:
        _check_finite(self)


@dataclass(frozen=True)
class TrackerGains:
    """Table A.13: off-track PID -> track-angle demand, along-track P -> velocity demand."""

    Kp_offtrack: float = 0.18
    Ki_offtrack: float = 0.0025
    Kd_offtrack: float = 0.6
    Kp_alongtrack: float = 0.125
    velocity_demand_limit_mps: float = 7.5
    track_angle_demand_limit_rad: float = math.radians(40.0)

    def __post_init__(self) -> None:
        _check_finite(self)
        for name in ("velocity_demand_limit_mps", "track_angle_demand_limit_rad"):
            if getattr(self, name) <= 0.0:
                raise ValueError(f"TrackerGains.{name} must be > 0, got {getattr(self, name)!r}")


_INTERLINK = ("demand", "total")
_WASHOUT = ("time_constant", "pole")
_DIRECTION = ("heading", "track")
_PATH = ("yaw_damper", "direct")


@dataclass(frozen=True)
class FCSStructure:
    """The block-diagram choices the thesis text leaves open (Figs. A.1, A.7, A.10 are not
    transcribed). Defaults are the variant that reproduces Table A.12 best (see docs/fcs.md).

    * ``interlink_source``: the aileron-to-rudder interlink takes the roll controller's aileron
      demand (``"demand"``) or the total aileron after the spiral stabiliser (``"total"``).
    * ``washout``: ``"time_constant"`` is ``T s / (T s + 1)`` (pole at 1/T); ``"pole"`` is
      ``s / (s + T)`` (pole at T rad/s).
    * ``interlink_path``: ``"yaw_damper"`` sums the interlinked aileron into the yaw damper's
      junction before its gain, ``rudder = -K_r (r_w + K_ari aileron)`` (net interlink 0.125
      rad/rad); ``"direct"`` adds it to the rudder, ``rudder = -K_r r_w + K_ari aileron``.
    * ``direction_feedback``: the heading controller feeds back the heading ``psi`` or the ground
      track angle ``chi = atan2(v_east, v_north)`` (the thesis's chi, A.5).
    """

    interlink_source: str = "demand"
    washout: str = "time_constant"
    direction_feedback: str = "track"
    interlink_path: str = "yaw_damper"

    def __post_init__(self) -> None:
        for name, allowed in (("interlink_source", _INTERLINK), ("washout", _WASHOUT),
                              ("direction_feedback", _DIRECTION), ("interlink_path", _PATH)):
            if getattr(self, name) not in allowed:
                raise ValueError(f"FCSStructure.{name} must be one of {allowed}, got {getattr(self, name)!r}")


@dataclass(frozen=True)
class FCSConfig:
    """Everything the PID flight control system needs besides its inputs.

    ``trim_controls`` (elevator, aileron, rudder, throttle) and ``trim_theta_rad`` are the
    reference about which the thesis's perturbation controllers act (Table A.5 trim by default,
    filled in by :meth:`formation_env.control.PIDFlightControl.from_trim`). ``surface_limit_rad`` and the
    throttle range are the saturation limits of A.3/A.4.
    """

    sas: SASGains = field(default_factory=SASGains)
    attitude: AttitudeGains = field(default_factory=AttitudeGains)
    autopilot: AutopilotGains = field(default_factory=AutopilotGains)
    tracker: TrackerGains = field(default_factory=TrackerGains)
    structure: FCSStructure = field(default_factory=FCSStructure)
    trim_controls: tuple[float, float, float, float] = (-0.0782, -0.00131, 0.000782, 0.7063)
    trim_theta_rad: float = 0.0
    surface_limit_rad: float = math.radians(25.0)
    throttle_limits: tuple[float, float] = (0.0, 1.0)
    use_tracker: bool = True
    anti_windup: bool = True

    def __post_init__(self) -> None:
        for name, typ in (("sas", SASGains), ("attitude", AttitudeGains), ("autopilot", AutopilotGains),
                          ("tracker", TrackerGains), ("structure", FCSStructure)):
            if not isinstance(getattr(self, name), typ):
                raise ValueError(f"FCSConfig.{name} must be a {typ.__name__}, got {type(getattr(self, name)).__name__}")
        tc = tuple(float(x) for x in self.trim_controls)
        if len(tc) != 4 or not all(math.isfinite(x) for x in tc):
            raise ValueError(f"FCSConfig.trim_controls must be 4 finite numbers, got {self.trim_controls!r}")
        object.__setattr__(self, "trim_controls", tc)
        if not math.isfinite(self.trim_theta_rad):
            raise ValueError(f"FCSConfig.trim_theta_rad must be finite, got {self.trim_theta_rad!r}")
        if not (math.isfinite(self.surface_limit_rad) and self.surface_limit_rad > 0):
            raise ValueError(f"FCSConfig.surface_limit_rad must be > 0, got {self.surface_limit_rad!r}")
        lo, hi = (float(x) for x in self.throttle_limits)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ValueError(f"FCSConfig.throttle_limits must be (low, high) with low < high, got {self.throttle_limits!r}")
        object.__setattr__(self, "throttle_limits", (lo, hi))
