"""Wake-surfing episodes: every controller flies the same held-out episodes (one batch, formation f is
the episode of ``seeds[f]``) on the batched rollout (:func:`formation_env.rollout.rollout`), and each episode
is measured against its reference optimum by the task's own metrics
(:mod:`formation_env.tasks.wake_surfing.metrics`, whose table lists them).

A controller is a :class:`formation_env.rollout.Policy` (``reset(n_rows)``, ``act(obs) -> actions``) with a
``name``; the extremum seeker and the oracle also ``observe`` the step output (the measured saving of the
previous decision; the oracle: the episode's steady wind and the leader's demanded track). The RL policies
and the PIDs use the observation alone.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from formation_env.rollout import FunctionPolicy, ZeroPolicy

__all__ = ["fly", "pid_surfer", "pid_formation_surfer", "es_surfer", "oracle_surfer", "sb3_surfer", "OracleSetpoint"]


def _ranges():
    from formation_env.scenarios import get_scenario
    from formation_env.sim.params import setpoint_ranges, setpoint_speed_range

    sc = get_scenario("wake_surfing")
    low, high = setpoint_ranges(sc)
    return low, high, setpoint_speed_range(sc)


def pid_surfer():
    """The thesis PID flying the nominal slot (zero set-point action)."""
    return ZeroPolicy()


def pid_formation_surfer():
    """``pid_formation`` at the nominal slot (its set-point ranges mapped onto the safe box's)."""
    from agents.pid_formation import PIDFormation

    low, high, speed = _ranges()
    agent = PIDFormation(setpoint_low_m=low, setpoint_high_m=high, speed_range_mps=speed)
    agent.name = "pid_formation"
    return agent


def es_surfer(gains=None, name: str = "extremum_seeking"):
    from agents.extremum_seeking import ExtremumSeeking

    low, high, speed = _ranges()
    agent = ExtremumSeeking(low, high, speed, gains=gains)
    agent.name = name
    return agent


class OracleSetpoint:
    """Not a controller but a ceiling: the thesis PID flown to the reference optimum itself (computed from
    the episode's true steady wind, the leader's demanded track and speed: knowledge no agent has),
    ``margin_b`` spans below the box floor's optimum, with ``pid_formation``'s speed channel holding the
    along-track station. What the set-point interface can achieve under the episode's turbulence."""

    def __init__(self, margin_b: float, name: str | None = None) -> None:
        from agents.pid_formation import PIDFormation

        low, high, speed = _ranges()
        self.margin_b = float(margin_b)
        self.name = name or f"oracle_setpoint_margin{margin_b:g}"
        self.along = PIDFormation(setpoint_low_m=low, setpoint_high_m=high, speed_range_mps=speed)
        self._decision = None

    def reset(self, n_rows: int) -> None:
        self.along.reset(n_rows)

    def observe(self, decision) -> None:
        self._decision = decision

    def act(self, obs):
        from formation_env.scenarios import AEROSONDE_SPAN_M
        from formation_env.tasks.wake_surfing.optimum import crab_angle_rad, reference_optimum

        d = self._decision
        if d is None:
            raise RuntimeError("OracleSetpoint.act: needs the rollout's observe() first")
        vd0 = d.leader_velocity_demand_ned_mps
        crab = crab_angle_rad(d.steady_wind_ned_mps, np.arctan2(vd0[:, 1], vd0[:, 0]), np.linalg.norm(vd0, axis=1))
        y, z, _ = reference_optimum(crab)
        slot = np.array([1.0, 0.3])  # the nominal slot's (y, z), spans
        offset = (np.stack([y, np.asarray(z) + self.margin_b], axis=1) - slot) * AEROSONDE_SPAN_M
        a = np.zeros((obs.shape[0], 4))
        a[:, 1] = self.along.setpoint_action(offset[:, 0], 1)
        a[:, 2] = self.along.setpoint_action(offset[:, 1], 2)
        a[:, 3] = self.along.act(obs)[:, 3]
        return np.clip(a, -1.0, 1.0)


def oracle_surfer(margin_b: float, name: str | None = None) -> OracleSetpoint:
    return OracleSetpoint(margin_b, name)


def sb3_surfer(path: str, name: str | None = None):
    from pathlib import Path

    from stable_baselines3 import PPO

    model = PPO.load(path, device="cpu")
    return FunctionPolicy(lambda obs: model.predict(obs, deterministic=True)[0], name=name or Path(path).stem)


def fly(policy, seeds: Sequence[int], *, config=None, keep_series: bool = False,
        crosswind_mps: float | None = None) -> list[dict]:
    """Fly ``policy`` on the wake-surfing episodes ``seeds`` (one batch) and measure each
    (:mod:`formation_env.tasks.wake_surfing.metrics`). ``crosswind_mps`` replaces each episode's steady wind
    by this crosswind (east, m/s: the figure's demonstration episodes; a reset option)."""
    from formation_env.rollout import rollout
    from formation_env.sim import Simulation
    from formation_env.tasks.wake_surfing.metrics import WakeSurfingRecorder, episode_metrics

    from .episodes import eval_env_config

    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("seeds must not be empty")
    cfg = config if config is not None else eval_env_config("wake_surfing", "setpoints")
    sim = Simulation(cfg, batch_size=len(seeds))
    options = None if crosswind_mps is None else {"steady_wind_ned": (0.0, float(crosswind_mps), 0.0)}
    rec = WakeSurfingRecorder()
    res = rollout(sim, policy, seeds, recorders=[rec], options=options)
    return episode_metrics(rec, res, keep_series=keep_series)
