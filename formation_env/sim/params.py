"""Named parameter structs of the batched decision step (NamedTuples of scalars and arrays that
numba compiles against): what never changes during a run. Built once per environment from an
:class:`~formation_env.envs.config.EnvConfig` by :class:`formation_env.envs.engine.FormationEpisode`.

Shapes: V vehicles, K slot keyframes (padded), G scenario gusts, N lattice panels. Units SI,
angles rad, frames NED (earth) and body (x forward, y starboard, z down).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..aircraft import AEROSONDE, DEFAULT_OPTIONS
from ..aircraft.envelope import DEFAULT_LIMITS
from ..aircraft.kernels import pack as pack_aircraft
from ..atmosphere.dryden import DrydenConfig
from ..atmosphere.frozen_field import FrozenFieldParams, frozen_field_params
from ..control.law import FCSParams
from ..wake.arrays import WakeArrays, wake_arrays
from .kernels import pack_limits

__all__ = ["AircraftArrays", "WakeArrays", "ScenarioArrays", "ActionParams", "RewardParams", "StepParams",
           "ACTION_MODE_CODES", "wake_arrays", "scenario_arrays", "SURFACES", "RESIDUAL", "SETPOINTS", "safe_box_arrays",
           "setpoint_ranges", "setpoint_speed_range", "slot_error_axes"]

SURFACES, RESIDUAL, SETPOINTS = 0, 1, 2
ACTION_MODE_CODES = {"surfaces": SURFACES, "residual": RESIDUAL, "setpoints": SETPOINTS}
RESIDUAL_SCALE = (0.1, 0.1, 0.1, 0.2)  # rad, rad, rad, throttle fraction per unit action
SETPOINT_POSITION_SCALE_M = 5.0  # m per unit action, slot frame (along, starboard, down)
SETPOINT_SPEED_SCALE_MPS = 2.0  # m/s per unit action along the demanded track
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
    slot_times_s: np.ndarray  # (V, K) keyframe times (row 0 unused), padded with +inf
    slot_offsets_m: np.ndarray  # (V, K, 3) keyframe offsets, track frame, m
    slot_keyframes: np.ndarray  # (V,) int64 keyframes per follower (0 for vehicle 0)
    span_m: float  # slot spans are measured in this (the follower's schedule span), m
    slot_along_leader_demand: bool  # slot offsets along vehicle 0's demanded (True) or measured track
    gusts: np.ndarray  # (G, 7) amplitude N, E, D m/s, start, rise, hold, decay s
    manoeuvres: bool  # randomised leader manoeuvres on


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


class RewardParams(NamedTuple):
    """:class:`~formation_env.envs.config.RewardWeights` plus the distances it needs."""

    slot: float
    slot_scale_m: float
    effort: float
    rate: float
    benefit: float
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


class StepParams(NamedTuple):
    """Everything constant of one environment (B formations share it)."""

    dt_s: float
    substeps: int  # physics steps per decision
    episode_steps: int  # physics steps until the time limit
    wake_on: bool
    wake_update_every: int  # physics steps between ELL solves
    turbulence: int  # 0 off, 1 frozen field, 2 independent streams per UAV
    benefit_on: bool  # compute the induced-drag saving each decision
    aircraft: AircraftArrays
    wake: WakeArrays
    wake_alone: WakeArrays  # one vehicle alone (the isolated induced drag of the formation benefit)
    scenario: ScenarioArrays
    fcs: FCSParams
    action: ActionParams
    reward: RewardParams
    field: FrozenFieldParams
    trim_airspeed_mps: float


def aircraft_arrays(params=AEROSONDE, options=DEFAULT_OPTIONS, limits=DEFAULT_LIMITS) -> AircraftArrays:
    return AircraftArrays(*pack_aircraft(params, options), pack_limits(limits))


def scenario_arrays(sc, manoeuvres: bool) -> ScenarioArrays:
    v = sc.n_vehicles
    k = max([len(s.keyframes) for s in sc.slots] + [1])
    times = np.full((v, k), np.inf)
    offs = np.zeros((v, k, 3))
    count = np.zeros(v, dtype=np.int64)
    span = sc.slots[0].span_m if sc.slots else 2.9
    for j, slot in enumerate(sc.slots):
        kf = slot.keyframes
        count[j + 1] = len(kf)
        for m, (t, off) in enumerate(kf):
            times[j + 1, m] = t
            offs[j + 1, m] = np.asarray(off) * slot.span_m
    gusts = np.array([[*g.amplitude_ned, g.start_s, g.rise_s, g.hold_s, g.decay_s] for g in sc.gusts]).reshape(-1, 7)
    return ScenarioArrays(float(sc.airspeed_mps), float(sc.altitude_m), np.asarray(sc.reference_offset_ned, float),
                          times, offs, count, float(span), sc.slot_frame == "leader_demand", gusts, bool(manoeuvres))


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


def setpoint_ranges(sc) -> tuple[np.ndarray, np.ndarray]:
    """(3,) set-point offsets (m, slot frame: along, starboard, down) of the ``setpoints`` action at -1 and
    +1 per axis (piecewise linear, the slot at 0): +-5 m on every axis, or, in a scenario with a safe
    box, the box around the first follower's starting slot with the along-track offset fixed (0).
    The speed set-point's range is :func:`setpoint_speed_range`."""
    if sc.safe_box_b is None:
        return np.full(3, -SETPOINT_POSITION_SCALE_M), np.full(3, SETPOINT_POSITION_SCALE_M)
    slot = np.asarray(sc.slots[0].keyframes[0][1], float)
    box = np.asarray(sc.safe_box_b, float)
    span = sc.slots[0].span_m
    low, high = (box[:, 0] - slot) * span, (box[:, 1] - slot) * span
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


def turbulence_params(sc, sigma_mps: float) -> FrozenFieldParams:
    """The Dryden field of the scenario (MIL-F-8785C low-altitude scale lengths) at ``sigma_mps``
    (any value > 0 when turbulence is off: the arrays must exist for the kernel)."""
    scales = DrydenConfig.low_altitude(sc.altitude_m, 1.0, sc.airspeed_mps, sc.dt).length_scale_m
    s = sigma_mps if sigma_mps > 0 else 1.0
    return frozen_field_params((s,) * 3, scales, sc.airspeed_mps, sc.dt)
