"""Per-agent observations: a documented, normalised feature vector (or the same groups as a Dict).

Every quantity is divided by the scale in the table and clipped to [-OBS_CLIP, OBS_CLIP], so the
Box holds every value the env emits; a non-finite value (only possible when the episode is
ending because the aircraft diverged) is replaced by 0.

The "slot frame" of an agent is its demanded track: x along the demanded ground velocity, y to
starboard of it, z down. The slot is the agent's demanded position (vehicle 0: its reference path;
followers: vehicle 0's position plus the slot offset along vehicle 0's track).

==========================  ====  ======  =========  =====================================================
group / feature             size  scale   unit       meaning
==========================  ====  ======  =========  =====================================================
air_data                    3                        airspeed - trim airspeed, alpha, beta (air-relative,
                                  5/0.1/0.1 m/s, rad   with the ambient and ELL-induced wind)
attitude                    3     0.5     rad        roll phi, pitch theta, heading psi minus demanded track
rates                       3     1.0     rad/s      body p, q, r
altitude                    1     50      m          altitude minus the scenario's altitude
slot_position_error         3     10      m          position minus slot, slot frame (along, starboard, down)
slot_velocity_error         3     5       m/s        ground velocity minus demanded velocity, slot frame
induced_wind                3     1.0     m/s        ELL effective induced translational wind, body axes
induced_rotation            3     1.0     rad/s      ELL effective induced rotational wind, body axes
engine                      1     545     rad/s      shaft speed / 545 - 1
previous_action             4     1       -          the agent's previous normalised action
neighbours                  6(V-1) 30/5   m, m/s     each other UAV (index order): relative position, then
                                                     relative velocity, in the agent's slot frame
==========================  ====  ======  =========  =====================================================
"""

from __future__ import annotations

import numpy as np

from ..aircraft import air_data_of
from ..aircraft.state import N_STATES
from ..atmosphere.wind import WindInput
from ..frames import dcm_body_to_ned_from_quaternion, euler_from_quaternion

__all__ = ["OBS_CLIP", "GROUPS", "observation_size", "group_sizes", "build_observations", "to_dict"]

OBS_CLIP = 10.0
OMEGA_REF = 545.0
GROUPS = ("air_data", "attitude", "rates", "altitude", "slot_position_error", "slot_velocity_error",
          "induced_wind", "induced_rotation", "engine", "previous_action", "neighbours")


def group_sizes(n_vehicles: int) -> dict[str, int]:
    return {"air_data": 3, "attitude": 3, "rates": 3, "altitude": 1, "slot_position_error": 3,
            "slot_velocity_error": 3, "induced_wind": 3, "induced_rotation": 3, "engine": 1,
            "previous_action": 4, "neighbours": 6 * (n_vehicles - 1)}


def observation_size(n_vehicles: int) -> int:
    return sum(group_sizes(n_vehicles).values())


def _wrap(a):
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def _to_track(vec, chi):
    """NED vectors (..., 3) into the frame rotated by the track angle chi (...)."""
    c, s = np.cos(chi), np.sin(chi)
    return np.stack([c * vec[..., 0] + s * vec[..., 1], -s * vec[..., 0] + c * vec[..., 1], vec[..., 2]], axis=-1)


def build_observations(state, induced_ned, omega_body, ambient_ned, turbulence_body, position_demand, velocity_demand,
                       previous_action, trim_airspeed, scenario_altitude) -> np.ndarray:
    """Observation vectors of every vehicle, (B, V, D) float64, normalised and clipped."""
    b, v = state.shape[:2]
    flat = state.reshape(b * v, N_STATES)
    with np.errstate(all="ignore"):
        wind = WindInput(wind_ned=(ambient_ned + induced_ned).reshape(b * v, 3), turbulence_body=turbulence_body.reshape(b * v, 3))
        ad = air_data_of(flat, wind)
        r_bn = dcm_body_to_ned_from_quaternion(state[..., 6:10])  # (B, V, 3, 3) body -> NED
        vel = np.einsum("bvij,bvj->bvi", r_bn, state[..., 0:3])
        euler = euler_from_quaternion(state[..., 6:10])
        chi = np.arctan2(velocity_demand[..., 1], velocity_demand[..., 0])
        pos = state[..., 10:13]
        parts = [
            np.stack([(ad["airspeed_raw"].reshape(b, v) - trim_airspeed) / 5.0, ad["alpha_raw"].reshape(b, v) / 0.1,
                      ad["beta_raw"].reshape(b, v) / 0.1], -1),
            np.stack([euler[..., 0] / 0.5, euler[..., 1] / 0.5, _wrap(euler[..., 2] - chi) / 0.5], -1),
            state[..., 3:6],
            ((-pos[..., 2] - scenario_altitude) / 50.0)[..., None],
            _to_track(pos - position_demand, chi) / 10.0,
            _to_track(vel - velocity_demand, chi) / 5.0,
            np.einsum("bvji,bvj->bvi", r_bn, induced_ned),
            omega_body,
            (state[..., 14] / OMEGA_REF - 1.0)[..., None],
            previous_action,
        ]
        if v > 1:
            neigh = np.empty((b, v, 6 * (v - 1)))
            for i in range(v):
                others = [j for j in range(v) if j != i]
                rel_p = _to_track(pos[:, others] - pos[:, i:i + 1], chi[:, i:i + 1]) / 30.0
                rel_v = _to_track(vel[:, others] - vel[:, i:i + 1], chi[:, i:i + 1]) / 5.0
                neigh[:, i] = np.concatenate([rel_p, rel_v], axis=-1).reshape(b, -1)
            parts.append(neigh)
        obs = np.concatenate(parts, axis=-1)
    obs = np.nan_to_num(obs, nan=0.0, posinf=OBS_CLIP, neginf=-OBS_CLIP)
    return np.clip(obs, -OBS_CLIP, OBS_CLIP)


def to_dict(vector: np.ndarray, n_vehicles: int) -> dict[str, np.ndarray]:
    """Split one agent's flat observation into the named groups."""
    out, k = {}, 0
    for name, size in group_sizes(n_vehicles).items():
        if size:
            out[name] = vector[..., k:k + size]
        k += size
    return out
