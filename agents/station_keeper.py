"""``station_keeper``: a classical station keeper tuned for cross-track precision in ``close_formation``.

The follower's induced-drag saving lives within ~0.1 span (0.29 m) of the optimum *across* the track
(starboard y, down z of the slot frame) and hardly depends on the along-track error (+-0.1 b changes it
by 0.001), so this controller spends its authority across the track and only keeps the along-track
station safe. It flies the env's ``setpoints`` action mode (offsets of the thesis PID's demands) from
the agent's own observation, and it holds whatever slot the scenario defines (the errors are to it).

Design: the set-point offsets as attitude commands. The thesis loops (formation_env.control.law) are
linear in the offsets: an offset dy starboard shifts the tracker's track-angle demand by Kp_offtrack dy
and so the bank demand by ``Kp_heading Kp_offtrack dy`` (0.126 rad/m); an offset dz down shifts the
pitch demand by ``Kp_altitude dz`` (-0.03 rad/m). At zero offset those loops already demand
``bank_own = -Kp_heading (Kp_offtrack e_y + Ki_offtrack int_offtrack + (Kd_offtrack + 1/V) de_y)`` (the
heading loop feeds back the ground track, chi - chi_d ~ de_y / V) and ``pitch_own = -Kp_altitude e_z -
Kd_altitude de_z``. The station keeper chooses the *total* laws

* cross track: ``bank = -(kp_lat e_y + kd_lat de_y + ki_lat int e_y)``;
* vertical: ``pitch = kp_ver e_z + kd_ver de_z + ki_ver int e_z + kw_ver w_z / V`` (the last term is
  the vertical-gust feed-forward: a downdraft w_z lowers the angle of attack by w_z / V, and pitching up
  by as much holds the lift before the aircraft sinks);

and commands the difference, ``dy = (bank - bank_own) / 0.126``, ``dz = (pitch - pitch_own) / -0.03``
(the tracker's own off-track integral is cancelled from the observed controller state, so it cannot wind
up against the offsets). Along track it keeps ``pid_formation``'s law (speed feed-forward of the
measured along-track wind, PD + I on the slot error; the part beyond the +-2 m/s speed channel goes to
the along-track offset through the tracker's ``Kp_alongtrack``), with two safety terms:

* energy trade beyond a dead band, both ways: more than ``lag_deadband_m`` behind, descend ``k_energy``
  m per m (height into speed, when the throttle is saturated); ahead, climb (the only brake once the
  throttle is closed); inside the band nothing disturbs the vertical precision;
* separation guard: once the nearest other UAV is less than ``guard_m`` ahead along the track (the slot
  is 2 spans = 5.8 m behind), the demand moves ``k_guard`` m per m away from it across the track and the
  speed demand drops ``k_guard`` m/s per m, so an overtaking follower passes beside the leader, not into it.

Every output saturates at the action bounds and the integrators stop while their channel is saturated.

Gains (chosen on training seeds 1-60 only, frozen von Karman turbulence sigma 1 m/s and calm air, wake
on; docs/close_formation.md has the tables): the thesis's own laws are bank 0.126 e_y + 0.45 de_y and
pitch 0.03 e_z + 0.05 de_z (a dominant lateral pole near 0.3 rad/s). Vertical: raising the pitch gains
4x (0.12 rad/m, 0.2 rad per m/s) and feeding forward the vertical gust took the vertical RMS at sigma 1
from 1.2 m to 0.21 m (grid kp 0.03-0.12 x kd 0.05-0.2 x kw 0/1). Lateral: the grid kp 0.1-0.35 x kd
0.15-1.0 x ki 0.02-0.05 showed that the lateral error is set by the damping, not the stiffness: lower
damping than the thesis's 0.45 or higher stiffness without more damping drove 2-4 m limit cycles; kp 0.2,
kd 1.0, ki 0.05 was best. Along: kd_along 2.5 (against pid_formation's 1.5) and the guard (5 m, 1.5)
removed the collisions found on training seeds 21-60 (a follower that had fallen 20 m behind closing at
2 m/s and overtaking beside the leader in a lateral limit cycle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from formation_env.control.gains import AutopilotGains, TrackerGains
from formation_env.envs.actions import SETPOINT_POSITION_SCALE_M, SETPOINT_SPEED_SCALE_MPS
from formation_env.envs.observations import (NEIGHBOUR_POSITION_SCALE_M, POSITION_SCALE_M, VELOCITY_SCALE_MPS,
                                             WIND_SCALE_MPS)

from .common import RowIntegrators, check_gains, observation_groups
from .pid_formation import inverse_slog

__all__ = ["StationKeeperGains", "StationKeeper"]


@dataclass(frozen=True)
class StationKeeperGains:
    """Gains of :class:`StationKeeper` (SI: m, m/s, s, rad). The cross-track and vertical gains are the
    *total* attitude-demand laws the follower flies (the thesis loops' own terms are subtracted)."""

    # cross track (starboard y): bank demand, rad per m / (m/s) / (m s) of slot error
    kp_lateral: float = 0.2
    kd_lateral: float = 1.0
    ki_lateral: float = 0.05
    # vertical (down z): pitch demand about trim, rad per m / (m/s) / (m s) of slot error
    kp_vertical: float = 0.12
    kd_vertical: float = 0.2
    ki_vertical: float = 0.01
    kw_vertical: float = 1.0  # fraction of the vertical-gust angle of attack w_z / V fed forward in pitch
    # along track: speed-demand offset (m/s) per m / (m/s) / (m s), fraction of along-track wind fed forward
    wind_feedforward: float = 1.0
    kp_along: float = 0.3
    kd_along: float = 2.5
    ki_along: float = 0.05
    # energy trade (m of descent per m of lag beyond lag_deadband_m): cross-track precision first
    k_energy: float = 0.5
    lag_deadband_m: float = 3.0
    # separation guard: the nearest other UAV less than guard_m ahead along the track -> k_guard m of
    # offset away from it across the track (and k_guard m/s less speed) per m inside the guard
    guard_m: float = 5.0
    k_guard: float = 1.5

    def __post_init__(self) -> None:
        check_gains(self)


class StationKeeper(RowIntegrators):
    """Batched, stateful agent: ``reset(n_rows)`` then ``act(obs (n_rows, D)) -> (n_rows, 4)`` setpoint
    actions in [-1, 1]."""

    action_mode = "setpoints"

    def __init__(self, gains: StationKeeperGains | None = None, control_hz: float = 10.0, *,
                 airspeed_mps: float = 25.0, tracker: TrackerGains | None = None,
                 autopilot: AutopilotGains | None = None) -> None:
        self.gains = StationKeeperGains() if gains is None else gains
        if not isinstance(self.gains, StationKeeperGains):
            raise ValueError(f"StationKeeper: gains must be a StationKeeperGains, got {type(gains).__name__}")
        for name, v, lo in (("control_hz", control_hz, 0.0), ("airspeed_mps", airspeed_mps, 0.0)):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and v > lo):
                raise ValueError(f"StationKeeper: {name} must be a finite number > 0, got {v!r}")
        self.control_hz = float(control_hz)
        self.airspeed_mps = float(airspeed_mps)
        self.tracker = TrackerGains() if tracker is None else tracker
        self.autopilot = AutopilotGains() if autopilot is None else autopilot
        # the thesis loops' gains that turn a set-point offset into an attitude-demand increment
        # (law.trajectory_tracker, law.fcs_law): 1 m starboard -> Kp_offtrack rad of track demand ->
        # Kp_heading Kp_offtrack rad of bank demand; 1 m down -> Kp_altitude rad of pitch demand (< 0)
        self.bank_per_m = self.autopilot.Kp_heading * self.tracker.Kp_offtrack
        self.pitch_per_m = self.autopilot.Kp_altitude
        if not (self.bank_per_m > 0 and self.pitch_per_m < 0):
            raise ValueError(f"StationKeeper: the thesis loops must map offsets to attitude with Kp_heading "
                             f"Kp_offtrack > 0 and Kp_altitude < 0, got {self.bank_per_m!r}, {self.pitch_per_m!r}")
        self.integral = np.zeros((0, 3))

    def act(self, obs) -> np.ndarray:
        obs, groups = observation_groups(obs, "StationKeeper")
        self._rows_for(obs)
        g, dt = self.gains, 1.0 / self.control_hz
        err = inverse_slog(groups["slot_position_error"], POSITION_SCALE_M)
        derr = inverse_slog(groups["slot_velocity_error"], VELOCITY_SCALE_MPS)
        wind = inverse_slog(groups["ambient_wind"], WIND_SCALE_MPS)
        integ = self.integral
        cstate = inverse_slog(groups["controller_state"], 1.0)
        tr, ap, v = self.tracker, self.autopilot, self.airspeed_mps
        # the designed total laws ...
        bank = -(g.kp_lateral * err[:, 1] + g.kd_lateral * derr[:, 1] + g.ki_lateral * integ[:, 1])
        pitch = (g.kp_vertical * err[:, 2] + g.kd_vertical * derr[:, 2] + g.ki_vertical * integ[:, 2]
                 + g.kw_vertical * wind[:, 2] / v)
        # ... minus what the thesis loops already demand at zero offset (tracker PID on the off-track
        # error through the heading P on the ground track; altitude PD), so the offset carries the rest
        own_bank = -ap.Kp_heading * (tr.Kp_offtrack * err[:, 1] + tr.Ki_offtrack * cstate[:, 5]
                                     + (tr.Kd_offtrack + 1.0 / v) * derr[:, 1])
        own_pitch = -ap.Kp_altitude * err[:, 2] - ap.Kd_altitude * derr[:, 2]
        dy = (bank - own_bank) / self.bank_per_m
        # energy trade beyond the dead band, both ways: behind, descend (height into speed); ahead, climb
        # (speed into height: the only brake once the throttle is closed)
        excess = np.maximum(np.abs(err[:, 0]) - g.lag_deadband_m, 0.0) * np.sign(-err[:, 0])
        dz = (pitch - own_pitch) / self.pitch_per_m + g.k_energy * excess
        # separation guard: once the nearest other UAV is less than guard_m ahead along the track (the
        # slot is 2 spans behind), the demand moves away from it across the track, k_guard m per m inside
        # the guard, and the speed demand drops as much: overtaking beside the leader stays clear of it
        nb = groups.get("neighbours")
        if nb is not None and nb.shape[1] >= 6 and g.k_guard > 0:
            rel = inverse_slog(nb.reshape(nb.shape[0], -1, 6)[:, :, :3], NEIGHBOUR_POSITION_SCALE_M)
            j = np.argmin(np.linalg.norm(rel, axis=2), axis=1)
            near = rel[np.arange(len(j)), j]
            depth = np.clip(g.guard_m - near[:, 0], 0.0, 2.0 * g.guard_m)
            dy = dy + g.k_guard * depth * np.where(near[:, 1] > 0, -1.0, 1.0)
        else:
            depth = np.zeros(len(dy))
        dv = (-g.wind_feedforward * wind[:, 0] - g.kp_along * err[:, 0] - g.kd_along * derr[:, 0]
              - g.ki_along * integ[:, 0]) - g.k_guard * depth
        # the speed demand beyond the speed channel's range goes through the tracker's along-track P
        # (V_demand = |V_d| - Kp_alongtrack ATD: a demand dx ahead adds Kp_alongtrack dx)
        over = dv - np.clip(dv, -SETPOINT_SPEED_SCALE_MPS, SETPOINT_SPEED_SCALE_MPS)
        dx = over / tr.Kp_alongtrack
        raw = np.stack([dx / SETPOINT_POSITION_SCALE_M, dy / SETPOINT_POSITION_SCALE_M, dz / SETPOINT_POSITION_SCALE_M,
                        dv / SETPOINT_SPEED_SCALE_MPS], axis=1)
        act = np.clip(raw, -1.0, 1.0)
        free = np.abs(raw[:, [3, 1, 2]]) < 1.0
        unwind = np.sign(raw[:, [3, 1, 2]]) * err > 0
        self.integral += np.where(free | unwind, err * dt, 0.0)
        return np.nan_to_num(act).astype(np.float32)
