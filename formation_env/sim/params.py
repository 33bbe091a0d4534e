"""Named parameter structs of the batched decision step (NamedTuples of scalars and arrays that
numba compiles against): what never changes during a run. Built once per environment from an
:class:`~formation_env.sim.config.EnvConfig` by :class:`formation_env.sim.Simulation`.

Shapes: V vehicles, K slot keyframes (padded), G scenario gusts, N lattice panels. Units SI,
angles rad, frames NED (earth) and body (x forward, y starboard, z down).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np

from ..aircraft import AEROSONDE, DEFAULT_OPTIONS
from ..aircraft.envelope import DEFAULT_LIMITS
from ..aircraft.kernels import pack as pack_aircraft
from ..atmosphere.dryden import DrydenConfig
from ..atmosphere.frozen_field import FrozenFieldParams, frozen_field_params
from ..atmosphere.spectral_field import FIELD_KINDS, SpectralFieldParams, spectral_field_params
from ..constants import AEROSONDE_SPAN_M, RESIDUAL_SCALE, SETPOINT_POSITION_SCALE_M, SETPOINT_SPEED_SCALE_MPS
from ..control.law import FCSParams
from ..geometry.presets import AEROSONDE_TAIL_ARM_M
from ..wake.arrays import WakeArrays, wake_arrays
from ..wake.coupling import CouplingArrays
from .kernels import pack_limits

__all__ = ["AircraftArrays", "WakeArrays", "ScenarioArrays", "ActionParams", "RewardParams", "StepParams",
           "ACTION_MODE_CODES", "wake_arrays", "scenario_arrays", "SURFACES", "RESIDUAL", "SETPOINTS", "safe_box_arrays",
           "setpoint_ranges", "safe_box_offsets", "setpoint_speed_range", "slot_error_axes", "surface_scale", "RESIDUAL_SCALE",
           "TurbulenceParams", "TURBULENCE_CODES", "turbulence_params", "TURBULENCE_OFF", "TURBULENCE_LANES",
           "TURBULENCE_INDEPENDENT", "TURBULENCE_SPECTRAL",
           "SETPOINT_POSITION_SCALE_M", "SETPOINT_SPEED_SCALE_MPS"]

SURFACES, RESIDUAL, SETPOINTS = 0, 1, 2
ACTION_MODE_CODES = {"surfaces": SURFACES, "residual": RESIDUAL, "setpoints": SETPOINTS}
# RESIDUAL_SCALE, SETPOINT_POSITION_SCALE_M, SETPOINT_SPEED_SCALE_MPS: formation_env.constants (re-exported here)
# Leader manoeuvre rates of the randomised reference path: turn 3 deg/s, climb 1.5 m/s, 0.5 m/s^2.
TURN_RATE_RAD_S = math.radians(3.0)
CLIMB_RATE_MPS = 1.5
ACCEL_MPS2 = 0.5


class AircraftArrays(NamedTuple):
    """The Aerosonde model packed for :func:`formation_env.aircraft.kernels.rk4_batch`."""

    scalars: np.ndarray  # (K_NPARAMS,) coefficients, geometry, mass data, options
    prop_J: np.ndarray
    prop_CT: np.ndarray
    prop_CP: np.ndarray
    engine_rpm: np.ndarray
    engine_map: np.ndarray
    engine_power: np.ndarray
    engine_fuel: np.ndarray
    atm_T: np.ndarray
    atm_P: np.ndarray
    atm_rho: np.ndarray
    atm_a: np.ndarray
    limits: np.ndarray  # (8,) flight envelope (formation_env.sim.kernels.pack_limits)


class ScenarioArrays(NamedTuple):
    """Reference path of vehicle 0 and the followers' slot schedules."""

    airspeed_mps: float
    altitude_m: float
    reference_offset_ned: np.ndarray  # (3,) m
    slot_times_s: np.ndarray  # (V, K) keyframe times (row 0: vehicle 0's own schedule, if any), padded with +inf
    slot_offsets_m: np.ndarray  # (V, K, 3) keyframe offsets, track frame, m
    slot_keyframes: np.ndarray  # (V,) int64 keyframes per UAV (vehicle 0: 0 unless Scenario.leader_schedule)
    span_m: float  # slot spans are measured in this (the follower's schedule span), m
    slot_along_leader_demand: bool  # slot offsets along vehicle 0's demanded (True) or measured track
    gusts: np.ndarray  # (G, 7) amplitude N, E, D m/s, start, rise, hold, decay s
    manoeuvres: bool  # randomised leader manoeuvres on
    leader_air_relative: bool  # vehicle 0's reference carried by the air (Scenario.leader_air_relative)


class ActionParams(NamedTuple):
    mode: int  # SURFACES | RESIDUAL | SETPOINTS
    agent_mask: np.ndarray  # (V,) bool: the vehicle is commanded by an agent (else the PID flies it)
    trim_controls: np.ndarray  # (4,) elevator, aileron, rudder rad, throttle
    surface_scale: np.ndarray  # (4,) per unit action in surfaces mode
    residual_scale: np.ndarray  # (4,) per unit action in residual mode
    setpoint_low_m: np.ndarray  # (3,) set-point offset at action -1 per axis (along, starboard, down), m (<= 0)
    setpoint_high_m: np.ndarray  # (3,) set-point offset at action +1 per axis, m (>= 0); piecewise linear, 0 at 0
    setpoint_speed_mps: float
    command_min: np.ndarray  # (4,)
    command_max: np.ndarray  # (4,)

    @classmethod
    def from_config(cls, action_mode: str, agent_mask, trim_controls, surface_limit_rad: float, throttle_limits,
                    scenario) -> "ActionParams":
        """The action mapping of an environment: ``action_mode`` a key of :data:`ACTION_MODE_CODES`;
        ``agent_mask`` (V,) bool (copied); ``trim_controls`` the trim's elevator, aileron, rudder rad and
        throttle (the first 4 values); ``surface_limit_rad`` the FCS surface limit, rad;
        ``throttle_limits`` (min, max); ``scenario`` a :class:`~formation_env.scenarios.Scenario` (the
        set-point ranges, :func:`setpoint_ranges` and :func:`setpoint_speed_range`)."""
        lim = float(surface_limit_rad)
        throttle_min, throttle_max = (float(x) for x in throttle_limits)
        low, high = setpoint_ranges(scenario)
        return cls(mode=ACTION_MODE_CODES[action_mode], agent_mask=np.array(agent_mask, dtype=bool),
                   trim_controls=np.ascontiguousarray(np.asarray(trim_controls, dtype=float).reshape(-1)[:4]),
                   surface_scale=surface_scale(lim), residual_scale=np.asarray(RESIDUAL_SCALE, float),
                   setpoint_low_m=low, setpoint_high_m=high, setpoint_speed_mps=setpoint_speed_range(scenario),
                   command_min=np.array([-lim, -lim, -lim, throttle_min]),
                   command_max=np.array([lim, lim, lim, throttle_max]))


class RewardParams(NamedTuple):
    """:class:`~formation_env.envs.config.RewardWeights` plus the distances it needs."""

    slot: float
    slot_scale_m: float
    effort: float
    rate: float
    benefit: float
    benefit_cap: float  # the largest saving the benefit term pays
    progress: float
    shaping_gamma: float
    terminal_forfeit: float
    separation: float
    barrier_separation_m: float
    collision: float
    crash: float
    collision_separation_m: float
    box: float  # safe-box penalty per decision outside the box (0: off)
    box_scale_m: float  # depth scale of the box penalty (Huber of depth / scale), m
    box_low_m: np.ndarray  # (V, 3) each UAV's safe box relative to vehicle 0, slot frame, m (-inf: unbounded)
    box_high_m: np.ndarray  # (V, 3) upper corners, m (+inf: unbounded)
    slot_error_axes: np.ndarray  # (3,) weights of the slot error's slot-frame components (along, starboard, down)
    hold: float  # cost per decision outside the hold radius in the hold phase
    hold_radius_m: float
    hold_remaining: np.ndarray  # (V,) decisions from the last keyframe of each UAV's slot to the time limit (-1: none)

    @classmethod
    def from_config(cls, weights, scenario, collision_separation_b: float, *, duration_s: float,
                    control_hz: float) -> "RewardParams":
        """The reward of an environment: ``weights`` a :class:`~formation_env.envs.config.RewardWeights`
        (its distances in spans are converted to m with :data:`AEROSONDE_SPAN_M`), ``scenario`` a
        :class:`~formation_env.scenarios.Scenario` (the safe box, :func:`safe_box_arrays`, and the slot
        error's axes, :func:`slot_error_axes`), ``collision_separation_b`` the collision separation,
        spans; the episode's ``duration_s`` and ``control_hz`` place each slot's hold phase
        (:func:`hold_remaining_decisions`)."""
        w, span = weights, AEROSONDE_SPAN_M
        box_low, box_high = safe_box_arrays(scenario)
        return cls(slot=w.slot, slot_scale_m=w.slot_scale_m, effort=w.effort, rate=w.rate, benefit=w.benefit,
                   benefit_cap=w.benefit_cap,
                   progress=w.progress, shaping_gamma=w.shaping_gamma, terminal_forfeit=w.terminal_forfeit,
                   separation=w.separation, barrier_separation_m=w.barrier_separation_b * span,
                   collision=w.collision, crash=w.crash, collision_separation_m=collision_separation_b * span,
                   box=w.box, box_scale_m=w.box_scale_b * span, box_low_m=box_low, box_high_m=box_high,
                   slot_error_axes=slot_error_axes(scenario) * np.array([w.along_track_weight, 1.0, 1.0]),
                   hold=w.hold, hold_radius_m=w.hold_radius_b * span,
                   hold_remaining=hold_remaining_decisions(scenario, duration_s, control_hz))


def hold_remaining_decisions(sc, duration_s: float, control_hz: float) -> np.ndarray:
    """(V,) for each UAV the decisions from the last keyframe of its slot schedule to the time limit: its hold
    phase is every decision with at most this many left (:class:`~formation_env.envs.config.RewardWeights`);
    the leader, which has no slot, -1 (never). A schedule ending after the time limit: 0 decisions, only the
    last decision of the episode."""
    out = np.full(sc.n_vehicles, -1.0)
    for j, slot in enumerate(sc.slots):
        out[j + 1] = max(0.0, (duration_s - slot.keyframes[-1][0]) * control_hz)
    return out


class TurbulenceParams(NamedTuple):
    """Both turbulence models of an environment (``StepParams.turbulence`` picks one)."""

    lanes: FrozenFieldParams  # lanes and independent streams (formation_env.atmosphere.frozen_field)
    modes: SpectralFieldParams  # the spectral field (formation_env.atmosphere.spectral_field)


# ``StepParams.turbulence``: which turbulence model the step samples (module-level ints: numba compiles them as
# constants). Off; the lanes (cross-correlated, transport-delayed); independent lanes (each UAV its own stream, no
# delay); the spectral field (von Karman or Dryden, with rotational gusts).
TURBULENCE_OFF, TURBULENCE_LANES, TURBULENCE_INDEPENDENT, TURBULENCE_SPECTRAL = 0, 1, 2, 3
#: ``EnvConfig.turbulence_field`` -> ``StepParams.turbulence`` when sigma > 0 ("frozen": the lanes' old name)
TURBULENCE_CODES = {"von_karman": TURBULENCE_SPECTRAL, "dryden": TURBULENCE_SPECTRAL, "lanes": TURBULENCE_LANES,
                    "frozen": TURBULENCE_LANES, "independent": TURBULENCE_INDEPENDENT}


class StepParams(NamedTuple):
    """Everything constant of one environment (B formations share it)."""

    dt_s: float
    substeps: int  # physics steps per decision
    episode_steps: int  # physics steps until the time limit
    wake_on: bool
    wake_update_every: int  # physics steps between ELL solves
    turbulence: int  # TURBULENCE_OFF | TURBULENCE_LANES | TURBULENCE_INDEPENDENT | TURBULENCE_SPECTRAL
    benefit_on: bool  # compute the induced-drag saving each decision
    aircraft: AircraftArrays
    wake: WakeArrays
    wake_alone: WakeArrays  # one vehicle alone (the isolated induced drag of the formation benefit)
    scenario: ScenarioArrays
    fcs: FCSParams
    action: ActionParams
    reward: RewardParams
    field: TurbulenceParams
    trim_airspeed_mps: float
    coupling: CouplingArrays  # how the wake reaches the 6-DOF (formation_env.wake.coupling)
    neighbour_count: int = 0  # observed neighbours: 0 every other UAV in index order; k the k nearest by slot
    # a bool per optional observation group, in formation_env.sim.layout.OPTIONS order
    # (ObservationLayout.switch_flags()): whether the observation holds it
    observation_switches: tuple = ()


def surface_scale(limit_rad: float) -> np.ndarray:
    """Surfaces-mode scale per unit action: the FCS surface limit (rad) for the three surfaces,
    0.5 for the throttle."""
    return np.array([limit_rad, limit_rad, limit_rad, 0.5])


def aircraft_arrays(params=AEROSONDE, options=DEFAULT_OPTIONS, limits=DEFAULT_LIMITS) -> AircraftArrays:
    """The Aerosonde ``params`` with ``options`` packed for the kernels, and its flight envelope."""
    return AircraftArrays(**pack_aircraft(params, options)._asdict(), limits=pack_limits(limits))


def scenario_arrays(sc, manoeuvres: bool, leader_air_relative: bool | None = None) -> ScenarioArrays:
    """The scenario packed for the kernels; ``leader_air_relative`` None: the scenario's."""
    v = sc.n_vehicles
    # row 0: vehicle 0's own schedule (Scenario.leader_schedule; 0 keyframes without one), rows 1..: the followers'
    schedules = ((sc.leader_schedule,) if sc.leader_schedule is not None else (None,)) + tuple(sc.slots)
    k = max([len(s.keyframes) for s in schedules if s is not None] + [1])
    times = np.full((v, k), np.inf)
    offs = np.zeros((v, k, 3))
    count = np.zeros(v, dtype=np.int64)
    span = sc.slots[0].span_m if sc.slots else AEROSONDE_SPAN_M
    for j, slot in enumerate(schedules):
        if slot is None:
            continue
        kf = slot.keyframes
        count[j] = len(kf)
        for m, (t, off) in enumerate(kf):
            times[j, m] = t
            offs[j, m] = np.asarray(off) * slot.span_m
    gusts = np.array([[*g.amplitude_ned, g.start_s, g.rise_s, g.hold_s, g.decay_s] for g in sc.gusts]).reshape(-1, 7)
    return ScenarioArrays(airspeed_mps=float(sc.airspeed_mps), altitude_m=float(sc.altitude_m),
                          reference_offset_ned=np.asarray(sc.reference_offset_ned, float), slot_times_s=times,
                          slot_offsets_m=offs, slot_keyframes=count, span_m=float(span),
                          slot_along_leader_demand=sc.slot_frame == "leader_demand", gusts=gusts,
                          manoeuvres=bool(manoeuvres),
                          leader_air_relative=bool(sc.leader_air_relative if leader_air_relative is None
                                                   else leader_air_relative))


def safe_box_arrays(sc) -> tuple[np.ndarray, np.ndarray]:
    """(V, 3) low and high corners of each UAV's safe box relative to vehicle 0 in the slot frame, m
    (:attr:`formation_env.scenarios.Scenario.safe_box_b`); unbounded (+-inf) for vehicle 0 and
    for scenarios without a box."""
    v = sc.n_vehicles
    low, high = np.full((v, 3), -np.inf), np.full((v, 3), np.inf)
    if sc.safe_box_b is not None:
        span = sc.slots[0].span_m
        box = np.asarray(sc.safe_box_b, float) * span  # (3, 2)
        low[1:], high[1:] = box[:, 0], box[:, 1]
    return low, high


def safe_box_offsets(sc) -> tuple[np.ndarray, np.ndarray]:
    """(3,) the safe box's walls as offsets from the first follower's starting slot (m, slot frame: along,
    starboard, down), the along-track offsets 0 (the along-track set-point is fixed); a scenario without a box:
    a ValueError."""
    if sc.safe_box_b is None:
        raise ValueError(f"safe_box_offsets: scenario {sc.name!r} has no safe box")
    slot = np.asarray(sc.slots[0].keyframes[0][1], float)
    box = np.asarray(sc.safe_box_b, float)
    span = sc.slots[0].span_m
    low, high = (box[:, 0] - slot) * span, (box[:, 1] - slot) * span
    low[0] = high[0] = 0.0
    return low, high


def setpoint_ranges(sc) -> tuple[np.ndarray, np.ndarray]:
    """(3,) set-point offsets (m, slot frame: along, starboard, down) of the ``setpoints`` action at -1 and
    +1 per axis (piecewise linear, the slot at 0): +-5 m on every axis, or, in a scenario with a safe
    box, the box around the first follower's starting slot (:func:`safe_box_offsets`) widened on each side by
    the scenario's ``setpoint_reach_b`` spans per axis, with the along-track offset fixed (0).
    The speed set-point's range is :func:`setpoint_speed_range`."""
    if sc.safe_box_b is None:
        return np.full(3, -SETPOINT_POSITION_SCALE_M), np.full(3, SETPOINT_POSITION_SCALE_M)
    low, high = safe_box_offsets(sc)
    reach = np.asarray(sc.setpoint_reach_b, float) * sc.slots[0].span_m
    low, high = low - reach, high + reach
    low[0] = high[0] = 0.0
    return low, high


def slot_error_axes(sc) -> np.ndarray:
    """(3,) weights of the slot error's slot-frame components: (1, 1, 1), the distance from the slot, or
    in a scenario with a safe box (1, 0, 0), the along-track distance only (across and vertically the
    follower is free within its box, which the reward's box term bounds)."""
    return np.array([1.0, 1.0, 1.0]) if sc.safe_box_b is None else np.array([1.0, 0.0, 0.0])


def setpoint_speed_range(sc) -> float:
    """m/s of speed demand per unit ``setpoints`` action a3: 2 m/s, or 4 m/s with a safe box (the
    along-track set-point is fixed there, so the speed demand alone must hold the follower's station
    against an along-track wind: the thesis PID's airspeed hold lags 8 m per 1 m/s)."""
    return SETPOINT_SPEED_SCALE_MPS if sc.safe_box_b is None else 2.0 * SETPOINT_SPEED_SCALE_MPS


def turbulence_params(sc, sigma_mps: float, field: str = "lanes") -> TurbulenceParams:
    """The turbulence of the scenario at ``sigma_mps`` (MIL-F-8785C low-altitude scale lengths at its
    altitude; any value > 0 when turbulence is off: the arrays must exist for the kernel): the lanes
    (:mod:`formation_env.atmosphere.frozen_field`) and the spectral field of ``field`` ("von_karman" or
    "dryden"; the lanes' names build a von Karman one that is never sampled). The spectral field is
    isotropic: with ``field`` spectral and the scale lengths unequal (below 1000 ft) it is a ValueError."""
    scales = DrydenConfig.low_altitude(sc.altitude_m, 1.0, sc.airspeed_mps, sc.dt).length_scale_m
    s = sigma_mps if sigma_mps > 0 else 1.0
    kind = field if field in FIELD_KINDS else "von_karman"
    if field in FIELD_KINDS and sigma_mps > 0 and max(scales) - min(scales) > 1e-9 * max(scales):
        raise ValueError(f"turbulence_field={field!r} is isotropic, but the MIL-F-8785C low-altitude scale lengths at "
                         f"{sc.altitude_m:g} m are {tuple(round(x, 1) for x in scales)} m (equal from 1000 ft = 304.8 m "
                         "up); use turbulence_field='lanes' there")
    return TurbulenceParams(lanes=frozen_field_params((s,) * 3, scales, sc.airspeed_mps, sc.dt),
                            modes=_spectral_params(kind, s, float(scales[2]), float(sc.dt)))


@functools.lru_cache(maxsize=16)
def _spectral_params(kind: str, sigma: float, length: float, dt: float) -> SpectralFieldParams:
    # the shell tables are a quadrature, too slow to redo for every environment: built once per (spectrum, sigma,
    # L, dt) in a process
    return spectral_field_params(kind, sigma, length, dt, span_m=AEROSONDE_SPAN_M, tail_arm_m=AEROSONDE_TAIL_ARM_M)
