"""Readable numpy definitions of the compiled decision step's observation, reward and slot
schedule features (formation_env.sim.observe, formation_env.sim.guidance); tests hold the compiled
kernels equal to these."""

from __future__ import annotations

import numpy as np

from formation_env.aircraft import air_data_of
from formation_env.aircraft.state import N_STATES
from formation_env.atmosphere.wind import WindInput
from formation_env.envs.observations import (ALTITUDE_SCALE_M, CONTROLLER_STATE_SCALE, NEIGHBOUR_POSITION_SCALE_M,
                                             OBS_CLIP, OMEGA_REF, POSITION_SCALE_M, VELOCITY_SCALE_MPS, WIND_SCALE_MPS,
                                             slog)
from formation_env.envs.rewards import huber
from formation_env.frames import dcm_body_to_ned_from_quaternion, euler_from_quaternion

_ERROR_CAP_M = 5000.0
_TERMINAL_ERROR_CAP_M = 100.0
BOX_DEPTH_CAP_SCALES = 5.0  # the compiled kernel's cap (formation_env.sim.observe), restated




def _wrap(a):
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def _to_track(vec, chi):
    """NED vectors (..., 3) into the frame rotated by the track angle chi (...)."""
    c, s = np.cos(chi), np.sin(chi)
    return np.stack([c * vec[..., 0] + s * vec[..., 1], -s * vec[..., 0] + c * vec[..., 1], vec[..., 2]], axis=-1)


def build_observations_reference(state, induced_ned, omega_body, ambient_ned, turbulence_body, position_demand,
                                 velocity_demand, previous_action, schedule, controller_state, trim_airspeed,
                                 scenario_altitude, neighbour_count: int = 0, neighbour_wind: bool = False,
                                 neighbour_attitude: bool = False) -> np.ndarray:
    """The same observations in plain numpy (the readable definition; tests hold the compiled one to it).
    ``neighbour_count`` k > 0: the k others whose demanded positions are nearest the agent's (a stable sort:
    ties by index), a missing one 1 km behind at the agent's velocity. ``neighbour_wind``: then each of those
    neighbours' ambient wind minus the agent's, slot frame (a missing one: 0). ``neighbour_attitude``: then each of
    those neighbours' roll / 0.5, roll rate (rad/s) and pitch minus the agent's / 0.5 (a missing one: 0)."""
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
        k = v - 1 if neighbour_count == 0 else neighbour_count
        if k > 0:
            neigh = np.empty((b, v, 6 * k))
            nwind = np.zeros((b, v, 3 * k))
            natt = np.zeros((b, v, 3 * k))
            for f in range(b):
                for i in range(v):
                    others = [j for j in range(v) if j != i]
                    if neighbour_count:
                        d = np.sum((position_demand[f, others] - position_demand[f, i]) ** 2, axis=-1)
                        others = [others[q] for q in np.argsort(d, kind="stable")][:k]
                    rel_p = slog(_to_track(pos[f, others] - pos[f, i], chi[f, i]), NEIGHBOUR_POSITION_SCALE_M)
                    rel_v = slog(_to_track(vel[f, others] - vel[f, i], chi[f, i]), VELOCITY_SCALE_MPS)
                    rows = np.concatenate([rel_p, rel_v], axis=-1)
                    absent = np.zeros((k - len(others), 6))
                    absent[:, 0] = slog(-1000.0, NEIGHBOUR_POSITION_SCALE_M)
                    neigh[f, i] = np.concatenate([rows, absent]).reshape(-1)
                    rel_w = slog(_to_track(ambient_total[f, others] - ambient_total[f, i], chi[f, i]), WIND_SCALE_MPS)
                    nwind[f, i, :3 * len(others)] = rel_w.reshape(-1)
                    att = np.stack([euler[f, others, 0] / 0.5, state[f, others, 3],
                                    (euler[f, others, 1] - euler[f, i, 1]) / 0.5], -1)
                    natt[f, i, :3 * len(others)] = att.reshape(-1)
            parts.append(neigh)
            if neighbour_wind:
                parts.append(nwind)
            if neighbour_attitude:
                parts.append(natt)
        obs = np.concatenate(parts, axis=-1)
    obs = np.nan_to_num(obs, nan=0.0, posinf=OBS_CLIP, neginf=-OBS_CLIP)
    return np.clip(obs, -OBS_CLIP, OBS_CLIP)


def reward_terms(w: RewardWeights, error, previous_error, action, previous_action, saving, separation, collided,
                 crashed, collision_separation_m: float, span_m: float, remaining_decisions=0, box_depth_m=None,
                 hold_remaining=None) -> dict:
    """Reward components (B, V) and their sum under ``"total"`` (see :class:`RewardWeights`).

    error, previous_error: distance from the slot now and at the previous decision (m); separation:
    distance to the nearest other UAV (m, inf alone); remaining_decisions (B,): decisions left until
    the time limit; box_depth_m (B, V): distance outside the safe box (default 0: inside). Non-finite
    inputs count as a crash: a diverged UAV is treated as 5 km from its slot. hold_remaining (V,): the
    decisions of each UAV's hold phase (after its slot's last keyframe; -1: none; default none).

    A collision or crash ends the episode, which would also end the slot costs still to come: with
    costs per decision, ending early could pay. So the terminal penalty also charges the slot cost
    at the error the UAV had before the end (at most 100 m) for every decision left: ending an
    episode is never cheaper than flying on where the UAV is."""
    with np.errstate(all="ignore"):
        # 5 km is beyond any distance a UAV can reach in an episode (25 m/s for minutes): the cap only
        # bounds the reward of a diverged (non-finite) UAV, whose episode ends with the crash penalty
        err = np.where(np.isfinite(error), np.minimum(error, _ERROR_CAP_M), _ERROR_CAP_M)
        prev = np.where(np.isfinite(previous_error), np.minimum(previous_error, _ERROR_CAP_M), _ERROR_CAP_M)
        cost, cost_prev = huber(err / w.slot_scale_m), huber(prev / w.slot_scale_m)
        d_safe = w.barrier_separation_b * span_m
        sep = np.where(np.isnan(separation), 0.0, separation)
        depth = np.clip((d_safe - sep) / max(d_safe - collision_separation_m, 1e-9), 0.0, 1.0)
        remaining = np.asarray(remaining_decisions, dtype=float)
        remaining = remaining[:, None] if remaining.ndim == 1 else remaining
        forfeit = w.terminal_forfeit * w.slot * huber(np.minimum(prev, _TERMINAL_ERROR_CAP_M) / w.slot_scale_m) * remaining
        hold_remaining = np.full(err.shape[-1], -1.0) if hold_remaining is None else np.asarray(hold_remaining, float)
        in_hold = remaining <= hold_remaining  # (B, V)
        hold_left = w.terminal_forfeit * w.hold * np.maximum(0.0, np.minimum(remaining, hold_remaining))  # forfeited with the episode
        terms = {
            "slot": -w.slot * cost,
            "progress": w.progress * (cost_prev - w.shaping_gamma * cost),  # gamma * Phi(s') - Phi(s), Phi = -cost
            "separation": -w.separation * depth * depth,
            "effort": -w.effort * np.sum(action * action, axis=-1) / 4.0,
            "rate": -w.rate * np.sum((action - previous_action) ** 2, axis=-1) / 4.0,
            "benefit": w.benefit * np.where(np.isfinite(saving), np.minimum(saving, w.benefit_cap), 0.0),
            "collision": -(w.collision + forfeit + hold_left) * collided.astype(float),
            "crash": -(w.crash + forfeit + hold_left) * crashed.astype(float),
        }
        q = np.zeros_like(err) if box_depth_m is None else np.asarray(box_depth_m, dtype=float)
        box_scale_m = w.box_scale_b * span_m
        terms["box"] = np.where(q > 0.0, -w.box * (1.0 + huber(np.minimum(q / box_scale_m, BOX_DEPTH_CAP_SCALES))), 0.0)
        terms["hold"] = np.where(in_hold & ~(err < w.hold_radius_b * span_m), -w.hold, 0.0) * np.ones_like(err)
    terms["total"] = sum(terms.values())
    return terms


def slot_schedule_features(scenario, time_s, slot_jitter):
    """(B, V, 10) each follower's slot schedule as observed (see formation_env.envs.observations)."""
    b, v = len(time_s), scenario.n_vehicles
    out = np.zeros((b, v, 10))
    out[..., 9] = 1.0
    t = np.asarray(time_s, float)
    schedules = ((scenario.leader_schedule,) if scenario.leader_schedule is not None else (None,)) + tuple(scenario.slots)
    for j1, slot in enumerate(schedules):
        if slot is None:  # vehicle 0 without its own schedule: zeros and 1
            continue
        j = j1 - 1
        off, rate = slot.offset_and_rate(t)
        off = off + slot_jitter[:, j + 1]
        times = np.array([k[0] for k in slot.keyframes])
        offs = np.array([k[1] for k in slot.keyframes]) * slot.span_m
        nxt = np.searchsorted(times, t, side="right")
        has = nxt < len(times)
        nxt_c = np.minimum(nxt, len(times) - 1)
        next_off = np.where(has[:, None], offs[nxt_c] + slot_jitter[:, j + 1], off)
        out[:, j + 1, 0:3] = off / slot.span_m
        out[:, j + 1, 3:6] = slog(rate, 1.0)
        out[:, j + 1, 6:9] = (next_off - off) / slot.span_m
        out[:, j + 1, 9] = np.where(has, np.minimum(times[nxt_c] - t, 10.0) / 10.0, 1.0)
    return out
