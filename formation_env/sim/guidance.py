"""Compiled guidance: vehicle 0's reference path, the followers' slot schedules and their demands
(virtual-leader formation flight, thesis chapter 6), one formation per call.

A follower's demanded position is vehicle 0's position plus its slot offset (x forward along the
track, y starboard, z down; m) expressed along vehicle 0's demanded track (or its measured ground
track, per scenario); its demanded velocity is vehicle 0's plus the slot's own rate. Slot offsets
move between keyframes with a raised-cosine blend (continuous rate), as
:class:`formation_env.scenarios.SlotSchedule` (tests hold the two equal).
"""

from __future__ import annotations

import math

import numba as nb

from ..aircraft.state import POS_D, POS_E, POS_N
from ..frames import track_to_ned_xy
from .observe import signed_log
from .params import ACCEL_MPS2, CLIMB_RATE_MPS, TURN_RATE_RAD_S

__all__ = ["reference_path", "slot_offset_and_rate", "formation_demands", "gust_shape", "gust_wind_ned",
           "leader_wind", "schedule_features"]

_jit = nb.njit(cache=True, error_model="numpy")


@_jit
def reference_path(sc, t, ref_pos, manoeuvre, out_pos, out_vel):
    """Vehicle 0's demanded position and velocity (NED) at time t: straight and level north at the
    trim speed, or, with randomised manoeuvres, the integrated path ``ref_pos`` turning, climbing
    and changing speed at fixed rates from manoeuvre = (start s, heading change rad, altitude change
    m, speed change m/s, base speed offset m/s): the speed is the scenario's plus the episode's base
    offset (from the start) plus the manoeuvre's change. A scenario with a leader schedule adds vehicle 0's
    own offset and rate to the straight path (never with manoeuvres: the Simulation refuses the pair)."""
    if sc.manoeuvres:
        tau = max(0.0, t - manoeuvre[0])
        dpsi, dh, dv = manoeuvre[1], manoeuvre[2], manoeuvre[3]
        psi = math.copysign(min(abs(dpsi), TURN_RATE_RAD_S * tau), dpsi)
        climb = math.copysign(CLIMB_RATE_MPS, dh) if 0.0 < tau < abs(dh) / CLIMB_RATE_MPS else 0.0
        speed = sc.airspeed_mps + manoeuvre[4] + math.copysign(min(abs(dv), ACCEL_MPS2 * tau), dv)
        for i in range(3):
            out_pos[i] = ref_pos[i]
        out_vel[0] = speed * math.cos(psi)
        out_vel[1] = speed * math.sin(psi)
        out_vel[2] = -climb
        return
    if sc.slot_keyframes[0] > 0:
        # vehicle 0's own schedule (Scenario.leader_schedule: a leader dropping back), staged in the outputs; the
        # track is north, so its x is north and z down (its y is 0 by construction)
        slot_offset_and_rate(sc, 0, t, out_pos, out_vel)
        out_pos[0] = (sc.airspeed_mps * t + sc.reference_offset_ned[0]) + out_pos[0]
        out_pos[1] = (0.0 + sc.reference_offset_ned[1]) + out_pos[1]
        out_pos[2] = (-sc.altitude_m + sc.reference_offset_ned[2]) + out_pos[2]
        out_vel[0] = sc.airspeed_mps + out_vel[0]
        return
    out_pos[0] = sc.airspeed_mps * t + sc.reference_offset_ned[0]
    out_pos[1] = 0.0 + sc.reference_offset_ned[1]
    out_pos[2] = -sc.altitude_m + sc.reference_offset_ned[2]
    out_vel[0] = sc.airspeed_mps
    out_vel[1] = 0.0
    out_vel[2] = 0.0


@_jit
def slot_offset_and_rate(sc, j, t, out_off, out_rate):
    """Follower j's slot offset (m, track frame) and its rate (m/s) at time t (raised-cosine blend
    between keyframes; constant before the first and after the last)."""
    n = sc.slot_keyframes[j]
    times, offs = sc.slot_times_s[j], sc.slot_offsets_m[j]
    for i in range(3):
        out_rate[i] = 0.0
    if t <= times[0]:
        for i in range(3):
            out_off[i] = offs[0, i]
        return
    for m in range(n - 1):
        t0, t1 = times[m], times[m + 1]
        if t < t1:
            tau = (t - t0) / (t1 - t0)
            s = 0.5 * (1.0 - math.cos(math.pi * tau))
            ds = 0.5 * math.pi * math.sin(math.pi * tau) / (t1 - t0)
            for i in range(3):
                d = offs[m + 1, i] - offs[m, i]
                out_off[i] = offs[m, i] + s * d
                out_rate[i] = ds * d
            return
    for i in range(3):
        out_off[i] = offs[n - 1, i]


@_jit
def formation_demands(sc, t, x, vel_ned, ref_pos, manoeuvre, jitter, out_pd, out_vd):
    """Demanded positions and velocities (V, 3) NED of one formation at time t. x (V, 16) the
    aircraft states, vel_ned (V, 3) their ground velocities, jitter (V, 3) the slot offset jitter
    (track frame, m). Follower j's slot offset is staged in out_pd[j] / out_vd[j] before use."""
    reference_path(sc, t, ref_pos, manoeuvre, out_pd[0], out_vd[0])
    if x.shape[0] == 1:
        return
    if sc.slot_along_leader_demand:
        chi = math.atan2(out_vd[0, 1], out_vd[0, 0])
    else:
        chi = math.atan2(vel_ned[0, 1], vel_ned[0, 0])
    c, s = math.cos(chi), math.sin(chi)
    for j in range(1, x.shape[0]):
        off, rate = out_pd[j], out_vd[j]
        slot_offset_and_rate(sc, j, t, off, rate)
        ox, oy, oz = off[0] + jitter[j, 0], off[1] + jitter[j, 1], off[2] + jitter[j, 2]
        r0, r1, r2 = rate[0], rate[1], rate[2]
        pn, pe = track_to_ned_xy(c, s, ox, oy)
        out_pd[j, 0] = x[0, POS_N] + pn
        out_pd[j, 1] = x[0, POS_E] + pe
        out_pd[j, 2] = x[0, POS_D] + oz
        vn, ve = track_to_ned_xy(c, s, r0, r1)
        out_vd[j, 0] = vel_ned[0, 0] + vn
        out_vd[j, 1] = vel_ned[0, 1] + ve
        out_vd[j, 2] = vel_ned[0, 2] + r2


@_jit
def gust_shape(a, t):
    """Gust ``a`` = (amplitude N, E, D, start, rise, hold, decay)'s shape at t: raised-cosine onset, hold, decay."""
    tau_up = min(1.0, max(0.0, (t - a[3]) / a[4]))
    tau_dn = min(1.0, max(0.0, (t - (a[3] + a[4] + a[5])) / a[6]))
    return 0.5 * (1.0 - math.cos(math.pi * tau_up)) * 0.5 * (1.0 + math.cos(math.pi * tau_dn))


@_jit
def gust_wind_ned(sc, t, out):
    """The scenario's transient gusts (thesis section 6.4: raised-cosine onset, hold, decay) at t."""
    for i in range(3):
        out[i] = 0.0
    for g in range(sc.gusts.shape[0]):
        a = sc.gusts[g]
        shape = gust_shape(a, t)
        for i in range(3):
            out[i] += shape * a[i]


@_jit
def leader_wind(sc, steady_wind, gust_ned0, t, k):
    """Component k (NED) of the ambient wind at vehicle 0 at t (m/s): the scenario's gusts, the steady wind and the
    turbulence there. An air-relative leader's reference (Scenario.leader_air_relative) is carried by its north
    (along the track: the reference flies north) and down components."""
    w = 0.0
    for g in range(sc.gusts.shape[0]):
        w += gust_shape(sc.gusts[g], t) * sc.gusts[g, k]
    return w + steady_wind[k] + gust_ned0[k]


@_jit
def schedule_features(sc, t, jitter, out):
    """(V, 10) each follower's slot schedule as observed: offset now (spans, track frame), its rate
    (slog 1 m/s), next keyframe's offset minus the current one (spans), time to the next keyframe
    (min(dt, 10 s) / 10; 1 when none is left). Vehicle 0: its own schedule's (from the reference) if the
    scenario gives it one, else zeros and 1."""
    span = sc.span_m
    off = out[0, 0:3].copy()
    rate = out[0, 3:6].copy()
    for i in range(10):
        out[0, i] = 0.0
    out[0, 9] = 1.0
    for j in range(0 if sc.slot_keyframes[0] > 0 else 1, out.shape[0]):
        slot_offset_and_rate(sc, j, t, off, rate)
        n = sc.slot_keyframes[j]
        nxt = n
        for m in range(n):
            if sc.slot_times_s[j, m] > t:
                nxt = m
                break
        for i in range(3):
            cur = off[i] + jitter[j, i]
            out[j, i] = cur / span
            out[j, 3 + i] = signed_log(rate[i], 1.0)
            if nxt < n:
                out[j, 6 + i] = (sc.slot_offsets_m[j, nxt, i] + jitter[j, i] - cur) / span
            else:
                out[j, 6 + i] = 0.0
        out[j, 9] = min(sc.slot_times_s[j, nxt] - t, 10.0) / 10.0 if nxt < n else 1.0
