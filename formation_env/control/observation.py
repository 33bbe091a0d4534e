"""Observation adapter: what the PID flight control system (and later the RL env) sees.

An FCS observation is a dict of float arrays with a leading batch axis B:

=====================  ======  ==============================================================
key                    shape   meaning (SI, radians, NED = flat-earth north-east-down)
=====================  ======  ==============================================================
position_ned           (B, 3)  aircraft CG position, m
velocity_ned           (B, 3)  ground velocity, m/s
euler                  (B, 3)  phi, theta, psi (body relative to NED), rad
rates_body             (B, 3)  p, q, r, body axes, rad/s
airspeed               (B,)    speed relative to the air (ambient + induced wind), m/s
position_demand_ned    (B, 3)  demanded position, m
velocity_demand_ned    (B, 3)  demanded velocity, m/s (its direction is the demanded track)
=====================  ======  ==============================================================

:func:`fcs_observation` builds it from the aircraft state (B, 16) plus the demands;
:func:`slot_demand` makes a follower's demands from its leader (virtual-leader formation flight,
thesis chapter 6): demanded position = leader position + slot offset expressed along the
leader's track.
"""

from __future__ import annotations

import numpy as np

from formation_env import frames
from formation_env.frames import ned_to_track_frame, track_frame_offset_to_ned  # re-exported (the home is frames)
from formation_env.aircraft.eom import air_data_of
from formation_env.aircraft.state import N_STATES, POS, QUAT, VEL
from formation_env.atmosphere.wind import WindInput

__all__ = ["OBS_KEYS", "fcs_observation", "observation_from_arrays", "validate_observation", "slot_demand",
           "ned_to_track_frame",
           "track_frame_offset_to_ned"]

OBS_KEYS = ("position_ned", "velocity_ned", "euler", "rates_body", "airspeed", "position_demand_ned",
            "velocity_demand_ned")
_WIDTH = {"airspeed": None}


def validate_observation(obs: dict) -> int:
    """Check keys, shapes and finiteness; return the batch size B. Raises ValueError."""
    if not isinstance(obs, dict):
        raise ValueError(f"observation must be a dict with keys {OBS_KEYS}, got {type(obs).__name__}")
    missing = [k for k in OBS_KEYS if k not in obs]
    if missing:
        raise ValueError(f"observation is missing {missing}")
    b = np.shape(obs["airspeed"])
    if len(b) != 1:
        raise ValueError(f"observation['airspeed'] must have shape (B,), got {b}")
    n = b[0]
    for k in OBS_KEYS:
        want = (n,) if k == "airspeed" else (n, 3)
        arr = np.asarray(obs[k])
        if arr.shape != want:
            raise ValueError(f"observation[{k!r}] must have shape {want}, got {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"observation[{k!r}] contains NaN or inf")
    return n


def observation_from_arrays(position_ned, velocity_ned, euler, rates_body, airspeed, position_demand_ned,
                            velocity_demand_ned) -> dict:
    """An observation from its parts (broadcast demands to the batch)."""
    n = np.shape(airspeed)[0]
    return {
        "position_ned": np.asarray(position_ned, float), "velocity_ned": np.asarray(velocity_ned, float),
        "euler": np.asarray(euler, float), "rates_body": np.asarray(rates_body, float),
        "airspeed": np.asarray(airspeed, float),
        "position_demand_ned": np.broadcast_to(np.asarray(position_demand_ned, float), (n, 3)),
        "velocity_demand_ned": np.broadcast_to(np.asarray(velocity_demand_ned, float), (n, 3)),
    }


def fcs_observation(state, position_demand_ned, velocity_demand_ned, wind: WindInput | None = None) -> dict:
    """The FCS observation of B aircraft from their states (B, 16).

    ``wind`` is the air the aircraft flies in (ambient + ELL induced), used for the airspeed;
    None means still air. Demands are (3,) or (B, 3).
    """
    s = np.asarray(state, dtype=float)
    if s.ndim != 2 or s.shape[1] != N_STATES:
        raise ValueError(f"fcs_observation: state must have shape (B, {N_STATES}), got {s.shape}")
    r_bn = frames.dcm_body_to_ned_from_quaternion(s[:, QUAT])
    vel_ned = np.einsum("bij,bj->bi", r_bn, s[:, VEL])
    airspeed = air_data_of(s, wind)["airspeed_raw"]
    return observation_from_arrays(s[:, POS], vel_ned, frames.euler_from_quaternion(s[:, QUAT]), s[:, 3:6],
                                   airspeed, position_demand_ned, velocity_demand_ned)


def slot_demand(leader_position_ned, leader_velocity_ned, slot_offset_track, slot_rate_track=None,
                track_angle_rad=None):
    """Virtual-leader demands for followers: ``(position_demand_ned, velocity_demand_ned)``.

    The slot offset (x forward, y starboard, z down, m) is expressed along the leader's ground
    track ``atan2(v_east, v_north)``; the demanded velocity is the leader's plus the slot's own
    rate (for a moving slot, e.g. reconfiguration). All arrays (..., 3). ``track_angle_rad``
    overrides the track the slot is expressed along (e.g. the leader's *demanded* track, which
    does not swing with the leader's lateral oscillations; the scenario runner's default).
    """
    lp = np.asarray(leader_position_ned, dtype=float)
    lv = np.asarray(leader_velocity_ned, dtype=float)
    chi = np.arctan2(lv[..., 1], lv[..., 0]) if track_angle_rad is None else np.asarray(track_angle_rad, float)
    pos = lp + track_frame_offset_to_ned(slot_offset_track, chi)
    vel = lv.copy()
    if slot_rate_track is not None:
        vel = vel + track_frame_offset_to_ned(slot_rate_track, chi)
    return pos, vel
