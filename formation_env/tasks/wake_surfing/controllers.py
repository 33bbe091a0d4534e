"""The wake-surfing task's controllers besides the learned policies: the thesis PID and ``pid_formation`` at the
nominal slot, the extremum seeker, and the oracle ceilings told the reference optimum (knowledge no agent has).

Each is a :class:`formation_env.rollout.Policy` with a ``name``; the extremum seeker and the oracles also
``observe`` the step output (the measured saving of the previous decision; the oracle: the episode's steady wind
and the leader's demanded track). The agents they are built from come in an
:class:`~formation_env.tasks.evaluation.AgentKit` (``kit``): ``formation_env`` never imports ``agents``.
"""

from __future__ import annotations

import numpy as np

from ...rollout import ZeroPolicy
from ...scenarios import AEROSONDE_SPAN_M, get_scenario
from ...sim.params import safe_box_offsets, setpoint_ranges, setpoint_speed_range

__all__ = ["pid_surfer", "pid_formation_surfer", "es_surfer", "oracle_surfer", "oracle_keeper", "OracleSetpoint",
           "OracleKeeper"]


def _ranges():
    sc = get_scenario("wake_surfing")
    low, high = setpoint_ranges(sc)
    return low, high, setpoint_speed_range(sc)


def pid_surfer():
    """The thesis PID flying the nominal slot (zero set-point action)."""
    return ZeroPolicy()


class _BoxedPIDFormation:
    """``pid_formation`` with its position set-point offsets held inside the safe box: where the set-point map
    reaches beyond the box (wake_surfing since issue 24) it flies as it was evaluated before (issue 16, when the
    map ended at the walls: an episode's saving the same to 1e-8, round-off through the two maps); unclipped, on the 100 held-out episodes at sigma 0.25 it was outside the box in 24 %
    of the decisions (11.5 % clipped), held 0.140 of the optimum (0.163 clipped) and collided once."""

    name = "pid_formation"

    def __init__(self, kit) -> None:
        low, high, speed = _ranges()
        self.box_low, self.box_high = safe_box_offsets(get_scenario("wake_surfing"))
        # the agent maps its offsets onto the box (its action +-1: the walls, and its integrators stop there), as it did
        self.agent = kit.pid_formation(setpoint_low_m=self.box_low, setpoint_high_m=self.box_high, speed_range_mps=speed)
        self.low, self.high = low, high

    def reset(self, n_rows: int) -> None:
        self.agent.reset(n_rows)

    def reset_rows(self, rows) -> None:
        self.agent.reset_rows(rows)

    def act(self, obs):
        a = np.array(self.agent.act(obs), dtype=float)
        for axis in (1, 2):  # the agent's offset (on the box's map) as the env's action (on the map with the reach)
            off = np.where(a[:, axis] >= 0, a[:, axis] * self.box_high[axis], -a[:, axis] * self.box_low[axis])
            a[:, axis] = np.where(off >= 0, off / self.high[axis], -off / self.low[axis])
        return np.clip(a, -1.0, 1.0).astype(np.float32)


def pid_formation_surfer(kit):
    """``pid_formation`` at the nominal slot, its set-point offsets held inside the safe box."""
    return _BoxedPIDFormation(kit)


def es_surfer(kit, gains=None, name: str = "extremum_seeking", inner: str | None = None):
    """The extremum seeker (agents/extremum_seeking.py) on the wake-surfing box; ``inner`` what flies its set-point
    (None: the seeker's default, the baseline's)."""
    low, high, speed = _ranges()
    box_low, box_high = safe_box_offsets(get_scenario("wake_surfing"))
    kw = {} if inner is None else {"inner": inner}
    agent = kit.extremum_seeking(low, high, speed, gains=gains, box_low_m=box_low, box_high_m=box_high, **kw)
    agent.name = name
    return agent


class OracleSetpoint:
    """Not a controller but a ceiling: the thesis PID flown to the reference optimum itself (computed from
    the episode's true steady wind, the leader's demanded track and speed: knowledge no agent has),
    ``margin_b`` spans below the reference optimum, with ``pid_formation``'s speed channel holding the
    along-track station. What the set-point interface can achieve under the episode's turbulence."""

    def __init__(self, kit, margin_b: float, name: str | None = None) -> None:
        low, high, speed = _ranges()
        self.margin_b = float(margin_b)
        self.name = name or f"oracle_setpoint_margin{margin_b:g}"
        self.along = kit.pid_formation(setpoint_low_m=low, setpoint_high_m=high, speed_range_mps=speed)
        self._decision = None

    def reset(self, n_rows: int) -> None:
        self.along.reset(n_rows)

    def observe(self, decision) -> None:
        self._decision = decision

    def _target_offset_m(self, n: int) -> np.ndarray:
        """(n, 2): the target's starboard and down offsets from the nominal slot, m (the reference optimum of
        the true steady wind and the leader's demanded track and air speed, ``margin_b`` below it)."""
        from .optimum import crab_angle_rad, reference_optimum

        d = self._decision
        if d is None:
            raise RuntimeError(f"{type(self).__name__}.act: needs the rollout's observe() first")
        vd0 = d.leader_velocity_demand_ned_mps
        air = np.linalg.norm(vd0 - d.steady_wind_ned_mps, axis=1)  # the demanded air speed (the reference's)
        crab = crab_angle_rad(d.steady_wind_ned_mps, np.arctan2(vd0[:, 1], vd0[:, 0]), air)
        y, z, _ = reference_optimum(crab)
        slot = np.array([1.0, 0.3])  # the nominal slot's (y, z), spans
        out = (np.stack([y, np.asarray(z) + self.margin_b], axis=1) - slot) * AEROSONDE_SPAN_M
        if out.shape[0] != n:
            raise RuntimeError(f"{type(self).__name__}.act: {out.shape[0]} decisions observed for {n} rows")
        return out

    def act(self, obs):
        return self.along.hold_actions(self._target_offset_m(obs.shape[0]), obs)


def oracle_surfer(kit, margin_b: float, name: str | None = None) -> OracleSetpoint:
    return OracleSetpoint(kit, margin_b, name)


class OracleKeeper(OracleSetpoint):
    """The ceiling with a precise holding loop: ``station_keeper`` (agents/station_keeper.py, tuned for
    close_formation's cross-track precision) flown to the reference optimum of the episode's true steady wind,
    ``margin_b`` spans below the reference optimum, with ``pid_formation``'s speed channel along the track (the
    box's +-4 m/s: the keeper's own is 2). The keeper sees its observation with the slot error taken to that
    target (its set-point offsets then shifted back by it), and its offsets pass through the box's set-point map,
    which cannot command a set-point outside the box. Not a controller: it is told the optimum."""

    def __init__(self, kit, margin_b: float, name: str | None = None) -> None:
        super().__init__(kit, margin_b, name or f"oracle_keeper_margin{margin_b:g}")
        # the keeper's own gains: wake_surfing's optimum is on the converged wake's plane, as close_formation's slot,
        # where the tip vortex's steady sidewash needs the lateral integral (agents/station_keeper.py)
        self.keeper = kit.station_keeper(kit.station_keeper_gains())

    def reset(self, n_rows: int) -> None:
        super().reset(n_rows)
        self.keeper.reset(n_rows)

    def act(self, obs):
        obs = np.asarray(obs, dtype=float)
        demand = self.keeper.hold_offset_m(obs, self._target_offset_m(obs.shape[0]))  # (N, 2) starboard, down, m
        return self.along.hold_actions(demand, obs)


def oracle_keeper(kit, margin_b: float, name: str | None = None) -> OracleKeeper:
    return OracleKeeper(kit, margin_b, name)
