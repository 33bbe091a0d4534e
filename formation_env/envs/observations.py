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

import math

import numba as nb
import numpy as np

from ..aircraft import AEROSONDE, DEFAULT_OPTIONS, air_data_of
from ..aircraft.kernels import _air
from ..aircraft.kernels import pack as _pack_aircraft
from ..aircraft.state import N_STATES
from ..atmosphere.wind import WindInput
from ..frames import dcm_body_to_ned_from_quaternion, euler_from_quaternion, quaternion_dcm_terms

__all__ = ["OBS_CLIP", "GROUPS", "observation_size", "group_sizes", "build_observations",
           "build_observations_reference", "to_dict"]

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
    """Observation vectors of every vehicle, (B, V, D) float64, normalised and clipped (compiled)."""
    b, v = state.shape[:2]
    out = np.empty((b, v, observation_size(v)))
    f = np.ascontiguousarray
    _obs_kernel(f(state), f(induced_ned), f(omega_body), f(ambient_ned), f(turbulence_body), f(position_demand),
                f(velocity_demand), f(previous_action), float(trim_airspeed), float(scenario_altitude), _AIR_PARAMS, out)
    return out


def build_observations_reference(state, induced_ned, omega_body, ambient_ned, turbulence_body, position_demand,
                                 velocity_demand, previous_action, trim_airspeed, scenario_altitude) -> np.ndarray:
    """The same observations in plain numpy (the readable definition; tests hold the compiled one to it)."""
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


_AIR_PARAMS = _pack_aircraft(AEROSONDE, DEFAULT_OPTIONS)[0]  # only the air-data bounds are read


@nb.njit(cache=True, error_model="numpy")
def _clean(x):
    if x != x:
        return 0.0
    return min(OBS_CLIP, max(-OBS_CLIP, x))


@nb.njit(cache=True, error_model="numpy")
def _obs_kernel(state, induced, omega, amb, turb, pd, vd, prev, trim_airspeed, altitude, air_params, out):
    b, nv = state.shape[0], state.shape[1]
    wind = np.zeros(12)
    vel = np.empty((nv, 3))
    chi = np.empty(nv)
    for i in range(b):
        for a in range(nv):
            x = state[i, a]
            r00, r01, r02, r10, r11, r12, r20, r21, r22 = quaternion_dcm_terms(x[6], x[7], x[8], x[9])
            vel[a, 0] = r00 * x[0] + r01 * x[1] + r02 * x[2]
            vel[a, 1] = r10 * x[0] + r11 * x[1] + r12 * x[2]
            vel[a, 2] = r20 * x[0] + r21 * x[1] + r22 * x[2]
            chi[a] = math.atan2(vd[i, a, 1], vd[i, a, 0])
        for a in range(nv):
            x = state[i, a]
            o = out[i, a]
            for k in range(3):
                wind[k] = amb[i, a, k] + induced[i, a, k]
                wind[3 + k] = turb[i, a, k]
            va, al, be = _air(x, wind, air_params)[:3]
            e0, ex, ey, ez = x[6], x[7], x[8], x[9]
            n2 = e0 * e0 + ex * ex + ey * ey + ez * ez
            phi = math.atan2(2.0 * (e0 * ex + ey * ez), e0 * e0 - ex * ex - ey * ey + ez * ez)
            theta = math.asin(min(1.0, max(-1.0, 2.0 * (e0 * ey - ex * ez) / n2)))
            psi = math.atan2(2.0 * (ex * ey + e0 * ez), e0 * e0 + ex * ex - ey * ey - ez * ez)
            c, s = math.cos(chi[a]), math.sin(chi[a])
            o[0] = (va - trim_airspeed) / 5.0
            o[1] = al / 0.1
            o[2] = be / 0.1
            o[3] = phi / 0.5
            o[4] = theta / 0.5
            o[5] = ((psi - chi[a] + math.pi) % (2.0 * math.pi) - math.pi) / 0.5
            o[6], o[7], o[8] = x[3], x[4], x[5]
            o[9] = (-x[12] - altitude) / 50.0
            dx, dy, dz = x[10] - pd[i, a, 0], x[11] - pd[i, a, 1], x[12] - pd[i, a, 2]
            o[10], o[11], o[12] = (c * dx + s * dy) / 10.0, (-s * dx + c * dy) / 10.0, dz / 10.0
            dx, dy, dz = vel[a, 0] - vd[i, a, 0], vel[a, 1] - vd[i, a, 1], vel[a, 2] - vd[i, a, 2]
            o[13], o[14], o[15] = (c * dx + s * dy) / 5.0, (-s * dx + c * dy) / 5.0, dz / 5.0
            r00, r01, r02, r10, r11, r12, r20, r21, r22 = quaternion_dcm_terms(e0, ex, ey, ez)
            w0, w1, w2 = induced[i, a, 0], induced[i, a, 1], induced[i, a, 2]
            o[16] = r00 * w0 + r10 * w1 + r20 * w2  # body = R^T ned
            o[17] = r01 * w0 + r11 * w1 + r21 * w2
            o[18] = r02 * w0 + r12 * w1 + r22 * w2
            o[19], o[20], o[21] = omega[i, a, 0], omega[i, a, 1], omega[i, a, 2]
            o[22] = x[14] / OMEGA_REF - 1.0
            o[23], o[24], o[25], o[26] = prev[i, a, 0], prev[i, a, 1], prev[i, a, 2], prev[i, a, 3]
            k = 27
            for j in range(nv):
                if j == a:
                    continue
                dx, dy, dz = state[i, j, 10] - x[10], state[i, j, 11] - x[11], state[i, j, 12] - x[12]
                o[k], o[k + 1], o[k + 2] = (c * dx + s * dy) / 30.0, (-s * dx + c * dy) / 30.0, dz / 30.0
                dx, dy, dz = vel[j, 0] - vel[a, 0], vel[j, 1] - vel[a, 1], vel[j, 2] - vel[a, 2]
                o[k + 3], o[k + 4], o[k + 5] = (c * dx + s * dy) / 5.0, (-s * dx + c * dy) / 5.0, dz / 5.0
                k += 6
            for k in range(o.shape[0]):
                o[k] = _clean(o[k])
