"""The separation guard: the station keeper's overtaking protection, shared with the learned policies as a
filter on their ``setpoints`` actions (a shield in the safe-RL sense: it moves what the policy commands only
inside the guard zone, and the policy trains with it in the loop).

Geometry (:func:`guard_terms`, slot frame: along the demanded track, starboard, down; m): the nearest other UAV
ahead of the *slot* and in line with it across the track (its lateral position within ``window_m`` of the
slot: in a vee not the follower abeam or behind) that is less than ``guard_m`` ahead of the follower along the
track puts the follower ``depth = guard_m - ahead`` m inside the guard (clipped to [0, 2 guard_m]); the shift
grows as ``ramp = min(depth / guard_m, 1)^2``. In ``close_formation`` the slot is 2 spans = 5.8 m behind the
leader, so the guard starts 0.8 m ahead of the slot and the square keeps the small forward excursions of
ordinary station keeping nearly free of it (1 m ahead: ramp 0.0016; 3 m: 0.19; abeam: 1).

The response (:class:`SeparationGuard`), the station keeper's: the target moves ``lateral_m`` away from the
guarded UAV across the track and ``vertical_m`` down, times the ramp, and the speed demand drops ``k_speed``
m/s per m of depth, the part beyond the speed channel's +-2 m/s going to the along-track offset through the
tracker's ``Kp_alongtrack`` (as the keeper sends its own excess): an overtaking follower passes beside and below
the leader and is braked. Why a filter and not a reward term: the committed close_formation policies trained with a
separation barrier (25 per unit below 1.5 spans) still collided in 5 of 300 held-out sigma-1 episodes, every
one a gust-driven surge of 6-8 m to abeam of the leader followed by a saturated lateral swing into it; the
keeper, whose only protection is this guard, had none in 100.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from formation_env.control.gains import TrackerGains
from formation_env.sim.params import SETPOINT_POSITION_SCALE_M, SETPOINT_SPEED_SCALE_MPS
from formation_env.envs.observations import NEIGHBOUR_POSITION_SCALE_M, POSITION_SCALE_M
from formation_env.sim.layout import ObservationLayout

from .common import agent_layout, check_gains, observation_groups
from .pid_formation import inverse_slog

__all__ = ["GuardGains", "SeparationGuard", "guard_terms", "speed_excess_offset_m"]


def guard_terms(err: np.ndarray, rel: np.ndarray | None, guard_m: float, window_m: float):
    """``(side, depth, ramp)``, each (N,), of the guard for followers with slot errors ``err`` (N, 3) (follower minus
    slot, m, slot frame) and neighbours at ``rel`` (N, K, 3) (neighbour minus follower, m, slot frame; None: no
    neighbour). ``side``: +1 to move starboard (the guarded UAV is to port), -1 to move port; ``depth``: m inside the
    guard (0 outside it or with nobody in line ahead); ``ramp``: ``min(depth / guard_m, 1)^2``."""
    n = err.shape[0]
    if rel is None or rel.shape[1] == 0:
        zero = np.zeros(n)
        return np.ones(n), zero, zero.copy()
    # judged about the slot, not the aircraft, so the guard's own shift never releases it (with one leader 2 spans
    # ahead of the slot, as in close_formation, the leader is always the one guarded)
    to_slot = rel + err[:, None, :]  # the neighbour from the slot, slot frame
    in_line = (to_slot[:, :, 0] > 0.0) & (np.abs(to_slot[:, :, 1]) < window_m)
    dist = np.where(in_line, np.linalg.norm(rel, axis=2), np.inf)
    j = np.argmin(dist, axis=1)
    rows = np.arange(n)
    near = rel[rows, j]
    depth = np.where(np.isfinite(dist[rows, j]), np.clip(guard_m - near[:, 0], 0.0, 2.0 * guard_m), 0.0)
    ramp = np.minimum(depth / guard_m, 1.0) ** 2
    side = np.where(near[:, 1] > 0, -1.0, 1.0)
    return side, depth, ramp


def speed_excess_offset_m(dv_mps: np.ndarray, kp_alongtrack: float) -> np.ndarray:
    """Along-track set-point offset (m) carrying the part of a speed demand ``dv_mps`` beyond the +-2 m/s speed
    channel: the tracker demands V = |V_d| - Kp_alongtrack ATD, so an offset dx ahead adds Kp_alongtrack dx."""
    over = dv_mps - np.clip(dv_mps, -SETPOINT_SPEED_SCALE_MPS, SETPOINT_SPEED_SCALE_MPS)
    return over / kp_alongtrack


def neighbour_positions(groups: dict) -> np.ndarray | None:
    """(N, K, 3) neighbours minus the follower (m, slot frame) from the observation groups, None without any."""
    nb = groups.get("neighbours")
    if nb is None or nb.shape[1] < 6:
        return None
    return inverse_slog(nb.reshape(nb.shape[0], -1, 6)[:, :, :3], NEIGHBOUR_POSITION_SCALE_M)


@dataclass(frozen=True)
class GuardGains:
    """The guard's zone and response; the station keeper's ``guard_*`` and ``k_guard`` gains default to these
    (:class:`agents.station_keeper.StationKeeperGains`; docs/close_formation.md has how they were chosen)."""

    guard_m: float = 5.0  # m ahead of the follower along the track where the guard starts
    window_m: float = 4.5  # m across the track about the slot within which a UAV ahead is guarded
    lateral_m: float = 2.0  # m the target moves away across the track at full depth
    vertical_m: float = 1.0  # m the target moves down at full depth
    k_speed: float = 1.5  # m/s of speed demand taken off per m of depth
    # from this ramp on (0: never) the lateral set-point is never nearer the guarded UAV than the guard's own shift:
    # what the policy adds toward it is clipped away (filter only; the keeper steers to the shifted target itself).
    # 0.25 is depth >= 2.5 m, i.e. more than 3.3 m ahead of a close_formation slot (docs/close_formation.md, "The
    # guard as a clip")
    clip_ramp: float = 0.0

    def __post_init__(self) -> None:
        check_gains(self)
        if self.guard_m <= 0:
            raise ValueError(f"GuardGains.guard_m must be > 0, got {self.guard_m!r}")
        if self.clip_ramp > 1:
            raise ValueError(f"GuardGains.clip_ramp must be in [0, 1] (0: no clip; the ramp is at most 1), got "
                             f"{self.clip_ramp!r}")


class SeparationGuard:
    """``filter(obs (N, D), actions (N, 4)) -> (N, 4)``: ``setpoints`` actions (the +-5 m position and +-2 m/s speed
    ranges of a scenario without a safe box) with the guard's shift added (and, with ``clip_ramp`` > 0, the lateral
    set-point clipped to the far side of the shift deep in the guard); stateless, so one instance serves every row
    and episode. Rows outside the guard zone pass through unchanged (bit for bit). ``layout``: the
    optional groups the observations hold (an :class:`~formation_env.sim.layout.ObservationLayout`: the env's or the
    policy's), which their length alone does not say."""

    action_mode = "setpoints"

    def __init__(self, gains: GuardGains | None = None, *, tracker: TrackerGains | None = None,
                 layout: ObservationLayout | None = None) -> None:
        self.layout = agent_layout(layout, "SeparationGuard")
        self.gains = GuardGains() if gains is None else gains
        if not isinstance(self.gains, GuardGains):
            raise ValueError(f"SeparationGuard: gains must be a GuardGains, got {type(gains).__name__}")
        self.kp_alongtrack = float((TrackerGains() if tracker is None else tracker).Kp_alongtrack)
        if not (math.isfinite(self.kp_alongtrack) and self.kp_alongtrack > 0):
            raise ValueError(f"SeparationGuard: the tracker's Kp_alongtrack must be > 0, got {self.kp_alongtrack!r}")

    def filter(self, obs, actions) -> np.ndarray:
        obs, groups = observation_groups(obs, "SeparationGuard", self.layout)
        act = np.asarray(actions)
        if act.shape != (obs.shape[0], 4):
            raise ValueError(f"SeparationGuard.filter: actions must have shape ({obs.shape[0]}, 4), got {act.shape}")
        g = self.gains
        err = inverse_slog(groups["slot_position_error"], POSITION_SCALE_M)
        side, depth, ramp = guard_terms(err, neighbour_positions(groups), g.guard_m, g.window_m)
        active = depth > 0.0
        if not active.any():
            return act
        out = np.array(act, dtype=float)
        a = np.clip(out[active], -1.0, 1.0)
        dy = g.lateral_m * ramp[active] * side[active]
        dz = g.vertical_m * ramp[active]
        dv = a[:, 3] * SETPOINT_SPEED_SCALE_MPS - g.k_speed * depth[active]
        a[:, 0] += speed_excess_offset_m(dv, self.kp_alongtrack) / SETPOINT_POSITION_SCALE_M
        a[:, 1] += dy / SETPOINT_POSITION_SCALE_M
        a[:, 2] += dz / SETPOINT_POSITION_SCALE_M
        a[:, 3] = dv / SETPOINT_SPEED_SCALE_MPS
        if g.clip_ramp > 0:
            # deep in the guard the lateral set-point stays on the far side of the shift: an overtaking policy
            # commanding toward the UAV it passes (out of its training distribution: ahead of the leader, throttle
            # closed) cannot undo the shift (the collisions of the additive guard at sigma 1.5)
            on = ramp[active] >= g.clip_ramp
            sd = side[active]
            a[:, 1] = np.where(on, sd * np.maximum(sd * a[:, 1], np.abs(dy) / SETPOINT_POSITION_SCALE_M), a[:, 1])
        out[active] = np.clip(a, -1.0, 1.0)
        return out.astype(act.dtype, copy=False)
