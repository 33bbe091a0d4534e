"""Environment configuration: frozen dataclasses validated on construction (ValueError names the field)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np

__all__ = ["ACTION_MODES", "OBS_MODES", "TURBULENCE_FIELDS", "RewardWeights", "Randomisation", "EnvConfig"]

ACTION_MODES = ("surfaces", "residual", "setpoints")
OBS_MODES = ("flat", "dict")
TURBULENCE_FIELDS = ("frozen", "independent")


def _finite(owner: str, name: str, value, *, minimum: float | None = None, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{owner}: {name} must be a finite number, got {value!r}")
    if positive and value <= 0:
        raise ValueError(f"{owner}: {name} must be > 0, got {value!r}")
    if minimum is not None and value < minimum:
        raise ValueError(f"{owner}: {name} must be >= {minimum}, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class RewardWeights:
    """Per-agent reward (per decision), with e the agent's distance from its slot (m; vehicle 0: from its
    reference path; in a scenario with a safe box, its along-track distance only), h the Huber function h(x) = x^2 / 2 for |x| <= 1 and |x| - 1/2 beyond, d its
    distance to the nearest other UAV and a its normalised action:

        r = - slot * h(e / slot_scale_m)                                   quadratic near the slot, linear far
            + progress * (shaping_gamma * Phi(s') - Phi(s)),  Phi = -h(e / slot_scale_m)   potential-based
            - separation * ((d_safe - d) / (d_safe - d_coll))^2   for d < d_safe        barrier before a collision
            - effort * |a|^2 / 4 - rate * |a - a_prev|^2 / 4
            + benefit * induced-drag saving
            - (collision + F) * [collision] - (crash + F) * [left the envelope or non-finite]
            - box * (1 + h(min(q / box_scale, 5))) * [q > 0]  q: distance outside the scenario's safe box

    F = terminal_forfeit * slot * h(min(e_prev, 100 m) / slot_scale_m) * (decisions left until the time
    limit): ending the episode forfeits the slot costs still to come, so a collision or crash must charge
    them, or ending early would pay (with terminal_forfeit = 1 the episode is never cheaper to end than to
    fly on at the current error).

    The safe box (:attr:`formation_env.scenarios.Scenario.safe_box_b`, relative to vehicle 0 in the slot frame)
    exists only in scenarios that define one (``wake_surfing``); q = 0 elsewhere. Its cost is a step of
    ``box`` as soon as the UAV is outside (a constraint, not a shaping: it must outweigh any saving the
    ELL reports beyond the box, up to ~0.8 in the band around the leader's wake plane the box excludes)
    plus h of the depth in ``box_scale_b`` spans (quadratic near the wall, linear far out).

    d_safe = ``barrier_separation_b`` spans, d_coll = the env's ``collision_separation_b`` spans. The slot
    term never saturates: it keeps decreasing with the error however far the UAV drifts. The shaping
    term is potential-based (Ng et al. 1999) and leaves the optimal policy unchanged when
    ``shaping_gamma`` equals the learner's discount."""

    slot: float = 1.0
    slot_scale_m: float = 5.0
    effort: float = 0.01
    rate: float = 0.05
    benefit: float = 0.0
    progress: float = 1.0
    shaping_gamma: float = 0.995
    terminal_forfeit: float = 1.0
    separation: float = 5.0
    barrier_separation_b: float = 1.2
    collision: float = 50.0
    crash: float = 50.0
    box: float = 0.0
    box_scale_b: float = 0.1

    def __post_init__(self) -> None:
        for f in fields(self):
            _finite("RewardWeights", f.name, getattr(self, f.name), minimum=0.0)
        _finite("RewardWeights", "slot_scale_m", self.slot_scale_m, positive=True)
        _finite("RewardWeights", "box_scale_b", self.box_scale_b, positive=True)
        if self.shaping_gamma > 1.0:
            raise ValueError(f"RewardWeights: shaping_gamma must be in [0, 1], got {self.shaping_gamma!r}")


@dataclass(frozen=True)
class Randomisation:
    """Per-episode randomisation for learning (all zero: the thesis scenario exactly).

    initial_offset_m: std of each follower's initial position jitter (NED, m).
    slot_offset_b: std of each slot's offset jitter (spans), applied to the whole schedule.
    steady_wind_mps: maximum steady horizontal wind speed (uniform in [0, max], random direction).
    crosswind_mps: maximum steady crosswind, perpendicular to the reference's initial track (uniform in
        +-max; added to the steady wind). A crosswind crabs the formation and turns the wake, which
        trails along the air-relative velocity, against the track (the wake-surfing task's moving optimum).
    turbulence_sigma_mps: Dryden intensity (m/s, all axes; MIL-F-8785C low-altitude scale lengths); the
        field is one frozen field per formation or independent per UAV (EnvConfig.turbulence_field).
    leader_turn_deg, leader_climb_m, leader_speed_mps: amplitude of one random manoeuvre of the
        reference (heading change, altitude change, speed change), each drawn uniformly in +-amplitude
        and started at a random time in the first half of the episode.
    """

    initial_offset_m: float = 0.0
    slot_offset_b: float = 0.0
    steady_wind_mps: float = 0.0
    crosswind_mps: float = 0.0
    turbulence_sigma_mps: float = 0.0
    leader_turn_deg: float = 0.0
    leader_climb_m: float = 0.0
    leader_speed_mps: float = 0.0

    def __post_init__(self) -> None:
        for f in fields(self):
            _finite("Randomisation", f.name, getattr(self, f.name), minimum=0.0)

    @property
    def any_manoeuvre(self) -> bool:
        return self.leader_turn_deg > 0 or self.leader_climb_m > 0 or self.leader_speed_mps > 0


@dataclass(frozen=True)
class EnvConfig:
    """Options of the formation environments.

    scenario: a name from :func:`formation_env.scenarios.scenario_names`, or a Scenario object.
    learning: which UAVs are agents: "all", "followers" (vehicle 0 flies the PID baseline on its
        path: a scripted leader) or a tuple of vehicle indices.
    action_mode: "surfaces" | "residual" | "setpoints" (see :mod:`formation_env.envs.actions`).
    control_hz: agent decision rate; the physics runs at 1 / scenario dt (50 Hz) and the action is
        held in between. Must divide the physics rate.
    wake: ELL wake coupling on or off (None: the scenario's default).
    obs_mode: "flat" (normalised Box, default) or "dict".
    collision_separation_b: minimum CG separation, spans, below which the episode ends (collision).
    duration_s: episode length (None: the scenario's).
    compute_benefit: compute each UAV's induced-drag saving (ELL Kutta-Joukowski loads against the same
        UAV alone) every decision, at the last physics step's ELL solve, for the infos (also forced on when
        the benefit weight is > 0; compiled into the decision step).
    wake_update_every: physics steps between ELL solves (1: every 50 Hz step, the default; 2: 25 Hz,
        about twice as fast; the induced wind is held in between).
    turbulence_field: "frozen" (default): one frozen (Taylor) Dryden field per formation that every
        UAV samples at its own position, so neighbours feel nearly the same gusts
        (:mod:`formation_env.atmosphere.frozen_field`); "independent": each UAV its own Dryden
        stream (uncorrelated gusts, for robustness studies).
    """

    scenario: object = "formation_keeping"  # a scenario name or a formation_env.scenarios.Scenario
    learning: str | tuple = "all"
    action_mode: str = "surfaces"
    control_hz: float = 10.0
    wake: bool | None = None
    obs_mode: str = "flat"
    collision_separation_b: float = 0.5
    duration_s: float | None = None
    compute_benefit: bool = False
    wake_update_every: int = 1
    turbulence_field: str = "frozen"
    reward: RewardWeights = field(default_factory=RewardWeights)
    randomisation: Randomisation = field(default_factory=Randomisation)

    def __post_init__(self) -> None:
        from ..scenarios import Scenario, scenario_names

        if not isinstance(self.scenario, Scenario) and self.scenario not in scenario_names():
            raise ValueError(f"EnvConfig: unknown scenario {self.scenario!r}; available: {scenario_names()}")
        if self.action_mode not in ACTION_MODES:
            raise ValueError(f"EnvConfig: action_mode must be one of {ACTION_MODES}, got {self.action_mode!r}")
        if self.obs_mode not in OBS_MODES:
            raise ValueError(f"EnvConfig: obs_mode must be one of {OBS_MODES}, got {self.obs_mode!r}")
        if self.turbulence_field not in TURBULENCE_FIELDS:
            raise ValueError(f"EnvConfig: turbulence_field must be one of {TURBULENCE_FIELDS}, got {self.turbulence_field!r}")
        _finite("EnvConfig", "control_hz", self.control_hz, positive=True)
        _finite("EnvConfig", "collision_separation_b", self.collision_separation_b, minimum=0.0)
        if self.duration_s is not None:
            _finite("EnvConfig", "duration_s", self.duration_s, positive=True)
        if isinstance(self.wake_update_every, bool) or not isinstance(self.wake_update_every, int) or self.wake_update_every < 1:
            raise ValueError(f"EnvConfig: wake_update_every must be an integer >= 1, got {self.wake_update_every!r}")
        if not (self.wake is None or isinstance(self.wake, bool)):
            raise ValueError(f"EnvConfig: wake must be True, False or None, got {self.wake!r}")
        if isinstance(self.learning, str):
            if self.learning not in ("all", "followers"):
                raise ValueError(f"EnvConfig: learning must be 'all', 'followers' or a tuple of indices, got {self.learning!r}")
        else:
            try:
                items = tuple(self.learning)
            except TypeError:
                raise ValueError(f"EnvConfig: learning must be 'all', 'followers' or a tuple of indices, got {self.learning!r}") from None
            bad = [i for i in items if isinstance(i, bool) or not isinstance(i, (int, np.integer))]
            if bad:
                raise ValueError(f"EnvConfig: learning indices must be integers (UAV indices), got {bad[0]!r} "
                                 f"in {self.learning!r}")
            idx = tuple(int(i) for i in items)
            if not idx or len(set(idx)) != len(idx):
                raise ValueError(f"EnvConfig: learning indices must be non-empty and unique, got {self.learning!r}")
            object.__setattr__(self, "learning", idx)
        if not isinstance(self.reward, RewardWeights):
            raise ValueError("EnvConfig: reward must be a RewardWeights")
        if not isinstance(self.randomisation, Randomisation):
            raise ValueError("EnvConfig: randomisation must be a Randomisation")
