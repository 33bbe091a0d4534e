"""The state of B formations as arrays (:class:`SimState`) and the per-decision outputs
(:class:`StepOutput`): everything that carries physics between calls of
:func:`formation_env.sim.step.step` lives here, nothing in hidden attributes.

Shapes: B formations, V vehicles, N ELL panels (all vehicles), R turbulence ring slots (lanes), M
spectral turbulence modes, D the observation size. Frames: NED earth, body x forward / y starboard / z down.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..aircraft.state import N_STATES
from ..atmosphere.frozen_field import FrozenFieldState, frozen_field_init
from ..atmosphere.spectral_field import SpectralFieldState, spectral_field_init
from ..control.law import N_CSTATE
from .observe import REWARD_TERMS

__all__ = ["SimState", "StepOutput", "init_state", "init_output", "copy_state"]


class SimState(NamedTuple):
    aircraft: np.ndarray  # (B, V, 16) Aerosonde states (formation_env.aircraft.state layout)
    controller: np.ndarray  # (B, V, 7) PID integrators and washout (formation_env.control.CSTATE_NAMES)
    command: np.ndarray  # (B, V, 4) controls of the last physics step: elevator, aileron, rudder rad, throttle
    step: np.ndarray  # (B,) int64 physics steps flown this episode
    induced_wind_ned: np.ndarray  # (B, V, 3) ELL effective induced wind held for the step, m/s NED
    induced_omega_body: np.ndarray  # (B, V, 3) ELL effective rotational wind, rad/s body
    circulation: np.ndarray  # (B, N) ELL circulation of the latest solve, m^2/s
    position_demand: np.ndarray  # (B, V, 3) demanded positions at the current state and time, m NED
    velocity_demand: np.ndarray  # (B, V, 3) demanded velocities, m/s NED
    slot_jitter: np.ndarray  # (B, V, 3) per-episode slot offset jitter, m, track frame
    steady_wind: np.ndarray  # (B, 3) per-episode steady wind, m/s NED
    manoeuvre: np.ndarray  # (B, 5) leader manoeuvre: start s, heading change rad, altitude change m, speed change m/s,
    #                        and the episode's base speed offset m/s (flown from the start)
    reference_position: np.ndarray  # (B, 3) integrated manoeuvring reference path position, m NED; for an
    # air-relative leader (Scenario.leader_air_relative) the distance north (x) and down (z), m, the air has carried its reference
    gust_ned: np.ndarray  # (B, V, 3) turbulence at each UAV now, m/s NED
    gust_omega_body: np.ndarray  # (B, V, 3) rotational gusts at each UAV now (p_g, -q_g, -r_g), rad/s body
    field: FrozenFieldState  # the lanes of the formation's turbulence (lanes or independent streams)
    modes: SpectralFieldState  # the formation's spectral turbulence field (von Karman or Dryden modes)
    status: np.ndarray  # (B, V) int64 envelope status bits after the last physics step
    previous_action: np.ndarray  # (B, V, 4) the agent's action of the last decision (0 for PID-flown UAVs)
    previous_error: np.ndarray  # (B, V) distance from the slot at the last decision, m
    episode_return: np.ndarray  # (B, V) sum of the rewards of this episode
    episode_decisions: np.ndarray  # (B,) int64 decisions taken this episode


class StepOutput(NamedTuple):
    """What one decision returns, for every vehicle (agents are selected by the adapters)."""

    observation: np.ndarray  # (B, V, D) float64
    reward: np.ndarray  # (B, V) total reward
    reward_terms: np.ndarray  # (B, V, 10) in formation_env.sim.observe.REWARD_TERMS order
    terminated: np.ndarray  # (B,) bool: collision or a UAV left the envelope
    truncated: np.ndarray  # (B,) bool: time limit reached (and not terminated)
    collided: np.ndarray  # (B,) bool: two CGs came closer than the collision separation
    crashed: np.ndarray  # (B, V) bool: the UAV left the envelope (or diverged) during the decision
    slot_error_m: np.ndarray  # (B, V) distance from the slot now, m (the reward's: along-track only with a safe box)
    separation_m: np.ndarray  # (B, V) distance to the nearest other UAV now
    min_separation_m: np.ndarray  # (B,) smallest CG separation seen during the decision
    saving: np.ndarray  # (B, V) induced-drag saving now (0 unless the benefit is on)
    box_depth_m: np.ndarray  # (B, V) distance outside the UAV's safe box now, m (0 inside, or without a box)


def init_state(batch_size: int, n_vehicles: int, n_panels: int, field_params) -> SimState:
    """Zeroed state of ``batch_size`` formations of ``n_vehicles`` UAVs (``n_panels`` ELL panels in all,
    the turbulence of ``field_params``, a :class:`~formation_env.sim.params.TurbulenceParams`); a reset fills it."""
    b, v = batch_size, n_vehicles
    z3 = lambda: np.zeros((b, v, 3))  # noqa: E731
    return SimState(
        aircraft=np.zeros((b, v, N_STATES)), controller=np.zeros((b, v, N_CSTATE)), command=np.zeros((b, v, 4)),
        step=np.zeros(b, dtype=np.int64), induced_wind_ned=z3(), induced_omega_body=z3(),
        circulation=np.zeros((b, max(n_panels, 1))), position_demand=z3(), velocity_demand=z3(), slot_jitter=z3(),
        steady_wind=np.zeros((b, 3)), manoeuvre=np.zeros((b, 5)), reference_position=np.zeros((b, 3)), gust_ned=z3(),
        gust_omega_body=z3(), field=frozen_field_init(field_params.lanes, b, v),
        modes=spectral_field_init(field_params.modes, b), status=np.zeros((b, v), dtype=np.int64),
        previous_action=np.zeros((b, v, 4)), previous_error=np.zeros((b, v)), episode_return=np.zeros((b, v)),
        episode_decisions=np.zeros(b, dtype=np.int64))


def init_output(batch_size: int, n_vehicles: int, obs_size: int) -> StepOutput:
    """Zeroed outputs of ``batch_size`` formations of ``n_vehicles`` UAVs (observations of ``obs_size``)."""
    b, v = batch_size, n_vehicles
    return StepOutput(
        observation=np.zeros((b, v, obs_size)), reward=np.zeros((b, v)),
        reward_terms=np.zeros((b, v, len(REWARD_TERMS))), terminated=np.zeros(b, dtype=np.bool_),
        truncated=np.zeros(b, dtype=np.bool_), collided=np.zeros(b, dtype=np.bool_),
        crashed=np.zeros((b, v), dtype=np.bool_), slot_error_m=np.zeros((b, v)), separation_m=np.zeros((b, v)),
        min_separation_m=np.full(b, np.inf), saving=np.zeros((b, v)), box_depth_m=np.zeros((b, v)))


def _copy_field(x):
    if isinstance(x, (FrozenFieldState, SpectralFieldState)):
        return type(x)(**{name: a.copy() for name, a in x._asdict().items()})
    return x.copy()


def copy_state(state: SimState) -> SimState:
    """A deep copy (the step updates its state in place, for speed)."""
    return SimState(**{name: _copy_field(x) for name, x in state._asdict().items()})
