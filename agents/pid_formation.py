"""``pid_formation``: the formation-keeping controller a control engineer would put around the thesis PID.

The thesis FCS (Appendix A) flies a follower to a point that moves with the leader, but its
along-track loop is a pure proportional term on the distance (``V_demand = |V_d| - 0.125 ATD``,
Table A.13) and its speed loop holds *airspeed*: an along-track gust changes the follower's ground
speed by the gust itself, and the P loop only answers with 8 m of error per 1 m/s. This controller
sits on top of it and commands its set-points (the env's ``setpoints`` action mode: position-demand
offsets along/starboard/below the demanded track, and a speed-demand offset), from the agent's own
observation (slot errors, ground-velocity errors, the ambient wind it measures as GPS velocity minus
air velocity):

* along track: ``dV = -w_x - kp_x e_x - kd_x de_x - ki_x int(e_x)``: ground-speed feed-forward of
  the measured along-track wind (gust-aware: the airspeed demand becomes the leader's ground speed
  minus the wind), PD on the slot error and an along-track integral that removes the PID's steady
  lag (and the speed loop's residual error);
* cross track and vertical: the demanded position is displaced against the error
  (``dy = -ky e_y - kiy int(e_y)``, ``dz = -kz e_z - kiz int(e_z)``), which raises the loop gains of
  the PID's off-track and altitude loops without touching its inner loops;
* energy trade: under sigma = 1 m/s the Aerosonde's throttle is saturated ~45 % of the time (trim
  throttle 0.71 leaves little excess power in downdrafts), so a follower that has fallen behind
  cannot catch up on thrust alone; it descends ``k_energy`` m per m of lag (``dz += k_energy
  max(-e_x, 0)``, within the 5 m set-point range) and converts height into speed, the way a glider
  pilot would (total-energy reasoning);
* every output saturates at the action bounds (5 m, 2 m/s) and the integrators stop integrating
  while their output is saturated (conditional-integration anti-windup).

Gains were tuned on training seeds (never the held-out evaluation seeds) for formation keeping under
frozen Dryden turbulence sigma 1 m/s, wake on; see docs/training.md for the tuning and its numbers.
Relative position and velocity are the ones to the *real* leader (the slot moves with vehicle 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from formation_env.sim.params import SETPOINT_POSITION_SCALE_M, SETPOINT_SPEED_SCALE_MPS
from formation_env.envs.observations import POSITION_SCALE_M, VELOCITY_SCALE_MPS, WIND_SCALE_MPS
from formation_env.sim.layout import ObservationLayout

from .common import RowIntegrators, agent_layout, check_gains, observation_groups

__all__ = ["PIDFormationGains", "PIDFormation", "inverse_slog"]


def inverse_slog(y, scale):
    """The inverse of the observation's signed log: sign(y) scale (e^|y| - 1)."""
    y = np.asarray(y, dtype=float)
    return np.sign(y) * scale * np.expm1(np.abs(y))


@dataclass(frozen=True)
class PIDFormationGains:
    """Gains of :class:`PIDFormation` (SI: m, m/s, s)."""

    wind_feedforward: float = 1.0  # fraction of the measured along-track wind fed forward
    kp_along: float = 0.3  # m/s of speed demand per m of along-track error
    kd_along: float = 1.5  # m/s per m/s of along-track velocity error
    ki_along: float = 0.05  # m/s per m s
    kp_cross: float = 1.0  # m of position-demand displacement per m of cross-track error
    ki_cross: float = 0.1  # m per m s
    kp_down: float = 3.0
    ki_down: float = 0.5
    k_energy: float = 1.5  # m of descent demanded per m of along-track lag (trades height for speed)
    kp_lead: float = 0.0  # m of position-demand lead per m of along-track lag (adds to the tracker's speed demand)

    def __post_init__(self) -> None:
        check_gains(self)


class PIDFormation(RowIntegrators):
    """Batched, stateful agent: ``reset(n_rows)`` then ``act(obs (n_rows, D)) -> (n_rows, 4)`` setpoint
    actions in [-1, 1]. Works for any formation size (the observation length fixes V)."""

    action_mode = "setpoints"

    def __init__(self, gains: PIDFormationGains | None = None, control_hz: float = 10.0, *,
                 setpoint_low_m=None, setpoint_high_m=None, speed_range_mps: float | None = None,
                 layout: ObservationLayout | None = None) -> None:
        """``setpoint_low_m`` / ``setpoint_high_m`` (3,) and ``speed_range_mps``: the env's set-point ranges
        (:func:`formation_env.sim.params.setpoint_ranges`; default +-5 m and 2 m/s), so that the offsets
        this controller computes map to the actions that command them (an axis with no range is held)."""
        self.setpoint_low_m = (np.full(3, -SETPOINT_POSITION_SCALE_M) if setpoint_low_m is None
                               else np.asarray(setpoint_low_m, dtype=float).reshape(3))
        self.setpoint_high_m = (np.full(3, SETPOINT_POSITION_SCALE_M) if setpoint_high_m is None
                                else np.asarray(setpoint_high_m, dtype=float).reshape(3))
        self.speed_range_mps = SETPOINT_SPEED_SCALE_MPS if speed_range_mps is None else float(speed_range_mps)
        self.layout = agent_layout(layout, "PIDFormation")  # the optional groups its observations hold
        if (not np.all(np.isfinite(self.setpoint_low_m)) or not np.all(np.isfinite(self.setpoint_high_m))
                or np.any(self.setpoint_low_m > 0) or np.any(self.setpoint_high_m < 0)):
            raise ValueError(f"PIDFormation: set-point ranges must be finite with low <= 0 <= high, got "
                             f"{self.setpoint_low_m} and {self.setpoint_high_m}")
        if not (math.isfinite(self.speed_range_mps) and self.speed_range_mps > 0):
            raise ValueError(f"PIDFormation: speed_range_mps must be > 0, got {speed_range_mps!r}")
        self.gains = PIDFormationGains() if gains is None else gains
        if not isinstance(self.gains, PIDFormationGains):
            raise ValueError(f"PIDFormation: gains must be a PIDFormationGains, got {type(gains).__name__}")
        if isinstance(control_hz, bool) or not isinstance(control_hz, (int, float)) or not (
                math.isfinite(control_hz) and control_hz > 0):
            raise ValueError(f"PIDFormation: control_hz must be a finite number > 0, got {control_hz!r}")
        self.control_hz = float(control_hz)
        self.integral = np.zeros((0, 3))

    def setpoint_action(self, offset_m, axis: int) -> np.ndarray:
        """The action that commands ``offset_m`` on ``axis`` (the inverse of the env's piecewise-linear
        set-point map; beyond the range it exceeds 1 and is clipped; 0 on an axis with no range)."""
        hi, lo = self.setpoint_high_m[axis], -self.setpoint_low_m[axis]
        up = offset_m / hi if hi > 0 else np.zeros_like(offset_m)
        down = offset_m / lo if lo > 0 else np.zeros_like(offset_m)
        return np.where(offset_m >= 0, up, down)

    def hold_actions(self, offsets_m, obs) -> np.ndarray:
        """(N, 4) set-point actions in [-1, 1] that command the lateral and vertical ``offsets_m`` (N, 2) (m, starboard
        and down of the slot; :meth:`setpoint_action`), the along-track offset 0, and this controller's own speed
        channel on ``obs`` (advancing its integrators): how a controller that chooses where to fly across the track
        (the extremum seeker, the wake-surfing ceilings) leaves the along-track station to it."""
        off = np.asarray(offsets_m, dtype=float)
        act = np.zeros((off.shape[0], 4))
        for axis in (1, 2):
            act[:, axis] = self.setpoint_action(off[:, axis - 1], axis)
        act[:, 3] = self.act(obs)[:, 3]
        return np.clip(act, -1.0, 1.0)

    def act(self, obs) -> np.ndarray:
        obs, groups = observation_groups(obs, "PIDFormation", self.layout)
        self._rows_for(obs)
        g = self.gains
        dt = 1.0 / self.control_hz
        err = inverse_slog(groups["slot_position_error"], POSITION_SCALE_M)
        derr = inverse_slog(groups["slot_velocity_error"], VELOCITY_SCALE_MPS)
        wind = inverse_slog(groups["ambient_wind"], WIND_SCALE_MPS)
        dv = (-g.wind_feedforward * wind[:, 0] - g.kp_along * err[:, 0] - g.kd_along * derr[:, 0]
              - g.ki_along * self.integral[:, 0])
        dy = -g.kp_cross * err[:, 1] - g.ki_cross * self.integral[:, 1]
        dz = -g.kp_down * err[:, 2] - g.ki_down * self.integral[:, 2] + g.k_energy * np.maximum(-err[:, 0], 0.0)
        dx = -g.kp_lead * err[:, 0]
        raw = np.stack([self.setpoint_action(dx, 0), self.setpoint_action(dy, 1),
                        self.setpoint_action(dz, 2),
                        dv / self.speed_range_mps], axis=1)
        act = np.clip(raw, -1.0, 1.0)
        # conditional integration: integrate only the channels that are not saturated (or that the
        # error would drive out of saturation)
        free = np.abs(raw[:, [3, 1, 2]]) < 1.0
        unwind = np.sign(raw[:, [3, 1, 2]]) * err > 0
        self.integral += np.where(free | unwind, err * dt, 0.0)
        return act.astype(np.float32)
