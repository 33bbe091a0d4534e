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
                                                                 (agents.fcs CSTATE_NAMES; 0 when the PID is off)
neighbours                  6(V-1)  slog 3 m, 1 m/s   m, m/s     each other UAV (index order): relative position, then
                                                                 relative velocity, in the agent's slot frame
==========================  ======  ================  =========  ==================================================
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

__all__ = ["OBS_CLIP", "GROUPS", "SCHEDULE_SIZE", "CONTROLLER_STATE_SIZE", "observation_size", "group_sizes",
           "build_observations", "build_observations_reference", "to_dict", "slog"]

OBS_CLIP = 10.0
OMEGA_REF = 545.0
SCHEDULE_SIZE = 10
CONTROLLER_STATE_SIZE = 7
GROUPS = ("air_data", "attitude", "rates", "altitude", "slot_position_error", "slot_velocity_error",
          "induced_wind", "induced_rotation", "ambient_wind", "engine", "previous_action", "slot_schedule",
          "controller_state", "neighbours")
# signed-log scales (see the module docstring)
ALTITUDE_SCALE_M = 10.0
POSITION_SCALE_M = 1.0
VELOCITY_SCALE_MPS = 1.0
WIND_SCALE_MPS = 1.0
NEIGHBOUR_POSITION_SCALE_M = 3.0
CONTROLLER_STATE_SCALE = 1.0


def group_sizes(n_vehicles: int) -> dict[str, int]:
    return {"air_data": 3, "attitude": 3, "rates": 3, "altitude": 1, "slot_position_error": 3,
            "slot_velocity_error": 3, "induced_wind": 3, "induced_rotation": 3, "ambient_wind": 3, "engine": 1,
            "previous_action": 4, "slot_schedule": SCHEDULE_SIZE, "controller_state": CONTROLLER_STATE_SIZE,
            "neighbours": 6 * (n_vehicles - 1)}


def observation_size(n_vehicles: int) -> int:
    return sum(group_sizes(n_vehicles).values())


def slog(x, scale):
    """Signed log: sign(x) ln(1 + |x| / scale) (x / scale near zero, logarithmic far out)."""
    return np.sign(x) * np.log1p(np.abs(x) / scale)


def _wrap(a):
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def _to_track(vec, chi):
    """NED vectors (..., 3) into the frame rotated by the track angle chi (...)."""
    c, s = np.cos(chi), np.sin(chi)
    return np.stack([c * vec[..., 0] + s * vec[..., 1], -s * vec[..., 0] + c * vec[..., 1], vec[..., 2]], axis=-1)


def build_observations(state, induced_ned, omega_body, ambient_ned, turbulence_body, position_demand, velocity_demand,
                       previous_action, schedule, controller_state, trim_airspeed, scenario_altitude) -> np.ndarray:
    """Observation vectors of every vehicle, (B, V, D) float64, normalised and clipped (compiled).

    state (B, V, 16); induced_ned, ambient_ned (B, V, 3) m/s NED; omega_body (B, V, 3) rad/s;
    turbulence_body (B, V, 3) m/s body; position/velocity_demand (B, V, 3) NED; previous_action (B, V, 4);
    schedule (B, V, 10) (already scaled, see the table); controller_state (B, V, 7) raw SI."""
    b, v = state.shape[:2]
    out = np.empty((b, v, observation_size(v)))
    f = np.ascontiguousarray
    _obs_kernel(f(state), f(induced_ned), f(omega_body), f(ambient_ned), f(turbulence_body), f(position_demand),
                f(velocity_demand), f(previous_action), f(schedule), f(controller_state), float(trim_airspeed),
                float(scenario_altitude), _AIR_PARAMS, out)
    return out


def build_observations_reference(state, induced_ned, omega_body, ambient_ned, turbulence_body, position_demand,
                                 velocity_demand, previous_action, schedule, controller_state, trim_airspeed,
                                 scenario_altitude) -> np.ndarray:
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
        ambient_total = ambient_ned + np.einsum("bvij,bvj->bvi", r_bn, turbulence_body)
        parts = [
            np.stack([(ad["airspeed_raw"].reshape(b, v) - trim_airspeed) / 5.0, ad["alpha_raw"].reshape(b, v) / 0.1,
                      ad["beta_raw"].reshape(b, v) / 0.1], -1),
            np.stack([euler[..., 0] / 0.5, euler[..., 1] / 0.5, _wrap(euler[..., 2] - chi) / 0.5], -1),
            state[..., 3:6],
            slog(-pos[..., 2] - scenario_altitude, ALTITUDE_SCALE_M)[..., None],
            slog(_to_track(pos - position_demand, chi), POSITION_SCALE_M),
            slog(_to_track(vel - velocity_demand, chi), VELOCITY_SCALE_MPS),
            np.einsum("bvji,bvj->bvi", r_bn, induced_ned),
            omega_body,
            slog(_to_track(ambient_total, chi), WIND_SCALE_MPS),
            (state[..., 14] / OMEGA_REF - 1.0)[..., None],
            previous_action,
            schedule,
            slog(controller_state, CONTROLLER_STATE_SCALE),
        ]
        if v > 1:
            neigh = np.empty((b, v, 6 * (v - 1)))
            for i in range(v):
                others = [j for j in range(v) if j != i]
                rel_p = slog(_to_track(pos[:, others] - pos[:, i:i + 1], chi[:, i:i + 1]), NEIGHBOUR_POSITION_SCALE_M)
                rel_v = slog(_to_track(vel[:, others] - vel[:, i:i + 1], chi[:, i:i + 1]), VELOCITY_SCALE_MPS)
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
def _slog(x, scale):
    if x >= 0.0:
        return math.log1p(x / scale)
    return -math.log1p(-x / scale)


@nb.njit(cache=True, error_model="numpy")
def _obs_kernel(state, induced, omega, amb, turb, pd, vd, prev, schedule, cstate, trim_airspeed, altitude, air_params,
                out):
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
            o[9] = _slog(-x[12] - altitude, ALTITUDE_SCALE_M)
            dx, dy, dz = x[10] - pd[i, a, 0], x[11] - pd[i, a, 1], x[12] - pd[i, a, 2]
            o[10] = _slog(c * dx + s * dy, POSITION_SCALE_M)
            o[11] = _slog(-s * dx + c * dy, POSITION_SCALE_M)
            o[12] = _slog(dz, POSITION_SCALE_M)
            dx, dy, dz = vel[a, 0] - vd[i, a, 0], vel[a, 1] - vd[i, a, 1], vel[a, 2] - vd[i, a, 2]
            o[13] = _slog(c * dx + s * dy, VELOCITY_SCALE_MPS)
            o[14] = _slog(-s * dx + c * dy, VELOCITY_SCALE_MPS)
            o[15] = _slog(dz, VELOCITY_SCALE_MPS)
            r00, r01, r02, r10, r11, r12, r20, r21, r22 = quaternion_dcm_terms(e0, ex, ey, ez)
            w0, w1, w2 = induced[i, a, 0], induced[i, a, 1], induced[i, a, 2]
            o[16] = r00 * w0 + r10 * w1 + r20 * w2  # body = R^T ned
            o[17] = r01 * w0 + r11 * w1 + r21 * w2
            o[18] = r02 * w0 + r12 * w1 + r22 * w2
            o[19], o[20], o[21] = omega[i, a, 0], omega[i, a, 1], omega[i, a, 2]
            t0, t1, t2 = turb[i, a, 0], turb[i, a, 1], turb[i, a, 2]  # body -> NED = R t
            dx = amb[i, a, 0] + r00 * t0 + r01 * t1 + r02 * t2
            dy = amb[i, a, 1] + r10 * t0 + r11 * t1 + r12 * t2
            dz = amb[i, a, 2] + r20 * t0 + r21 * t1 + r22 * t2
            o[22] = _slog(c * dx + s * dy, WIND_SCALE_MPS)
            o[23] = _slog(-s * dx + c * dy, WIND_SCALE_MPS)
            o[24] = _slog(dz, WIND_SCALE_MPS)
            o[25] = x[14] / OMEGA_REF - 1.0
            o[26], o[27], o[28], o[29] = prev[i, a, 0], prev[i, a, 1], prev[i, a, 2], prev[i, a, 3]
            k = 30
            for m in range(SCHEDULE_SIZE):
                o[k + m] = schedule[i, a, m]
            k += SCHEDULE_SIZE
            for m in range(CONTROLLER_STATE_SIZE):
                o[k + m] = _slog(cstate[i, a, m], CONTROLLER_STATE_SCALE)
            k += CONTROLLER_STATE_SIZE
            for j in range(nv):
                if j == a:
                    continue
                dx, dy, dz = state[i, j, 10] - x[10], state[i, j, 11] - x[11], state[i, j, 12] - x[12]
                o[k] = _slog(c * dx + s * dy, NEIGHBOUR_POSITION_SCALE_M)
                o[k + 1] = _slog(-s * dx + c * dy, NEIGHBOUR_POSITION_SCALE_M)
                o[k + 2] = _slog(dz, NEIGHBOUR_POSITION_SCALE_M)
                dx, dy, dz = vel[j, 0] - vel[a, 0], vel[j, 1] - vel[a, 1], vel[j, 2] - vel[a, 2]
                o[k + 3] = _slog(c * dx + s * dy, VELOCITY_SCALE_MPS)
                o[k + 4] = _slog(-s * dx + c * dy, VELOCITY_SCALE_MPS)
                o[k + 5] = _slog(dz, VELOCITY_SCALE_MPS)
                k += 6
            for k in range(o.shape[0]):
                o[k] = _clean(o[k])
