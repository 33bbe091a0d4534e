"""Per-agent observations: a documented, normalised feature vector (or the same groups as a Dict).

Quantities that grow without bound during an episode (position, velocity and wind errors, distances
to neighbours, controller integrators) are *signed-log* scaled, ``slog(x, s) = sign(x) ln(1 + |x| / s)``:
linear (x / s) near zero, so small errors keep their resolution, and logarithmic far out, so a
UAV 300 m from its slot (slog = 5.7 at s = 1 m) is still distinguished from one 30 m away (3.4)
instead of saturating. Bounded quantities are divided by a scale. Every value is finally clipped to
[-OBS_CLIP, OBS_CLIP] (10: e^10 s, ~22 km for s = 1 m, far beyond any reachable error); a non-finite
value (only possible when the episode is ending because the aircraft diverged) is replaced by 0.

The "slot frame" of an agent is its demanded track: x along the demanded ground velocity, y to
starboard of it, z down. The slot is the agent's demanded position (vehicle 0: its reference path;
followers: vehicle 0's position plus the slot offset along vehicle 0's demanded track).

==========================  ======  ================  =========  ==================================================
group / feature             size    scaling           unit       meaning
==========================  ======  ================  =========  ==================================================
air_data                    3       /5, /0.1, /0.1    m/s, rad   airspeed - trim airspeed, alpha, beta (air-relative,
                                                                 with the ambient and ELL-induced wind)
attitude                    3       /0.5              rad        roll phi, pitch theta, heading psi minus demanded track
rates                       3       /1                rad/s      body p, q, r
altitude                    1       slog 10 m         m          altitude minus the scenario's altitude
slot_position_error         3       slog 1 m          m          position minus slot, slot frame (along, starboard, down)
slot_velocity_error         3       slog 1 m/s        m/s        ground velocity minus demanded velocity, slot frame
induced_wind                3       /1                m/s        ELL effective induced translational wind, body axes
induced_rotation            3       /1                rad/s      ELL effective induced rotational wind, body axes
ambient_wind                3       slog 1 m/s        m/s        ambient wind (steady + gusts + turbulence), slot frame
engine                      1       /545 - 1          rad/s      shaft speed
previous_action             4       1                 -          the agent's previous normalised action
slot_schedule               10      spans, slog, /10  b, m/s, s  the slot offset from vehicle 0 now (3, spans, track
                                                                 frame), its rate (3, slog 1 m/s), the next keyframe's
                                                                 offset minus the current one (3, spans), the time to
                                                                 the next keyframe (min(t, 10 s) / 10; 1 when none
                                                                 is left); zeros and 1 for vehicle 0
controller_state            7       slog 1            SI         the PID's integrators and washout state
                                                                 (formation_env.control CSTATE_NAMES; 0 when the PID is off)
neighbours                  6(V-1)  slog 3 m, 1 m/s   m, m/s     each other UAV (index order): relative position, then
                            or 6k                                relative velocity, in the agent's slot frame; with
                                                                 ``neighbour_count`` k: the k UAVs whose slots are
                                                                 nearest the agent's, nearest first (a missing one:
                                                                 1 km behind, same velocity)
neighbour_wind (option)     3(V-1)  slog 1 m/s        m/s        with ``EnvConfig(neighbour_wind=True)`` only: each
                            or 3k                                neighbour of ``neighbours`` (same order): its
                                                                 ambient wind minus the agent's, slot frame (a
                                                                 missing one: 0)
neighbour_attitude          3(V-1)  /0.5, /1, /0.5    rad,       with ``EnvConfig(neighbour_attitude=True)`` only
(option)                    or 3k                     rad/s, rad (after the winds when both are on): each
                                                                 neighbour of ``neighbours`` (same order): its roll,
                                                                 roll rate and pitch minus the agent's (a missing
                                                                 one: 0)
==========================  ======  ================  =========  ==================================================
"""

from __future__ import annotations

import numpy as np

# one table of scales, read by the compiled kernel (formation_env.sim.observe) and this documentation
from ..sim.observe import (ALTITUDE_SCALE_M, CONTROLLER_STATE_SCALE, CONTROLLER_STATE_SIZE,
                           NEIGHBOUR_POSITION_SCALE_M, OBS_CLIP, OMEGA_REF, POSITION_SCALE_M, SCHEDULE_SIZE,
                           VELOCITY_SCALE_MPS, WIND_SCALE_MPS, group_sizes, observation_size)

__all__ = ["OBS_CLIP", "GROUPS", "SCHEDULE_SIZE", "CONTROLLER_STATE_SIZE", "observation_size", "group_sizes",
           "to_dict", "slog"]

GROUPS = ("air_data", "attitude", "rates", "altitude", "slot_position_error", "slot_velocity_error",
          "induced_wind", "induced_rotation", "ambient_wind", "engine", "previous_action", "slot_schedule",
          "controller_state", "neighbours", "neighbour_wind", "neighbour_attitude")
SCALES = (ALTITUDE_SCALE_M, CONTROLLER_STATE_SCALE, NEIGHBOUR_POSITION_SCALE_M, OMEGA_REF, POSITION_SCALE_M,
          VELOCITY_SCALE_MPS, WIND_SCALE_MPS)


def slog(x, scale):
    """Signed log: sign(x) ln(1 + |x| / scale) (x / scale near zero, logarithmic far out)."""
    return np.sign(x) * np.log1p(np.abs(x) / scale)


def to_dict(vector: np.ndarray, n_vehicles: int, neighbour_count: int | None = None,
            neighbour_wind: bool = False, neighbour_attitude: bool = False) -> dict[str, np.ndarray]:
    """Split one agent's flat observation into the named groups (``neighbour_count``, ``neighbour_wind``,
    ``neighbour_attitude`` as the env's)."""
    out, k = {}, 0
    for name, size in group_sizes(n_vehicles, neighbour_count, neighbour_wind, neighbour_attitude).items():
        if size:
            out[name] = vector[..., k:k + size]
        k += size
    return out
