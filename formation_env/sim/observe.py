"""Compiled per-formation observation and reward: what the decision step hands to agents.

The feature table, scales and the reward's definition are documented in
:mod:`formation_env.envs.observations` and :class:`formation_env.envs.config.RewardWeights`; the
readable numpy definitions live in ``tests/oracles`` and tests hold these kernels to them.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..aircraft.kernels import air_data_kernel
from ..aircraft.state import POS_D, POS_E, POS_N
from ..frames import ned_to_track_xy, quaternion_dcm_terms
from .kernels import min_separation_each  # noqa: F401  (re-exported: the one separation kernel lives there)

__all__ = ["observe_formation", "reward_formation", "REWARD_TERMS", "OBS_CLIP", "OMEGA_REF", "min_separation_each", "signed_log",
           "box_depth_each", "slot_error"]

_jit = nb.njit(cache=True, error_model="numpy")

# the optional groups' places in observe_formation's ``switches`` tuple: formation_env.sim.layout.OPTIONS's order
# (StepParams.observation_switches, from ObservationLayout.switch_flags(); a test holds the two equal)
NEIGHBOUR_WIND_SWITCH = 0
NEIGHBOUR_ATTITUDE_SWITCH = 1

OBS_CLIP = 10.0
OMEGA_REF = 545.0  # rad/s, engine shaft speed scale
SCHEDULE_SIZE = 10
CONTROLLER_STATE_SIZE = 7
ALTITUDE_SCALE_M = 10.0
POSITION_SCALE_M = 1.0
VELOCITY_SCALE_MPS = 1.0
WIND_SCALE_MPS = 1.0
NEIGHBOUR_POSITION_SCALE_M = 3.0
CONTROLLER_STATE_SCALE = 1.0
REWARD_TERMS = ("slot", "progress", "separation", "effort", "rate", "benefit", "collision", "crash", "box", "hold")
_ERROR_CAP_M = 5000.0  # beyond any reachable distance: only bounds a diverged UAV's reward
_TERMINAL_ERROR_CAP_M = 100.0
ABSENT_NEIGHBOUR_M = 1000.0  # where an observed neighbour the formation lacks reads (m behind, same velocity)
BOX_DEPTH_CAP_SCALES = 5.0  # the box cost's depth (in box_scale units) stops growing here


@_jit
def _clean(x):
    if x != x:
        return 0.0
    return min(OBS_CLIP, max(-OBS_CLIP, x))


@_jit
def signed_log(x, scale):
    """sign(x) ln(1 + |x| / scale), one number (the observation's signed-log scaling)."""
    if x >= 0.0:
        return math.log1p(x / scale)
    return -math.log1p(-x / scale)


@_jit
def observe_formation(x, induced, omega, amb, pd, vd, prev, schedule, cstate, trim_airspeed, altitude, air_params,
                      vel, chi, out, neighbour_count, switches):
    """Observation rows (V, D) of one formation into ``out``. x (V, 16); induced, amb (V, 3) NED m/s;
    omega (V, 3) body rad/s; pd, vd (V, 3) demands; prev (V, 4); schedule (V, 10); cstate (V, 7);
    vel (V, 3), chi (V,) scratch. ``neighbour_count`` 0: the neighbours group holds every other UAV in
    index order; k > 0: the k UAVs whose demanded positions (slots) are nearest the agent's, nearest first
    (ties by index), and :data:`ABSENT_NEIGHBOUR_M` behind for each of the k that the formation lacks.
    ``switches``: a bool per optional group (:data:`formation_env.sim.layout.OPTIONS` order). Neighbour wind
    on: then the ``neighbour_wind`` group, each observed neighbour's ambient wind minus the
    agent's own (the neighbours' order; slot frame; zero for a missing one). Neighbour attitude on: then the
    ``neighbour_attitude`` group, each observed neighbour's roll / 0.5 rad, roll rate (rad/s) and pitch minus the
    agent's / 0.5 rad (the neighbours' order; zero for a missing one)."""
    nv = x.shape[0]
    neighbour_wind = switches[NEIGHBOUR_WIND_SWITCH]
    neighbour_attitude = switches[NEIGHBOUR_ATTITUDE_SWITCH]
    wind = np.zeros(12)
    for a in range(nv):
        xa = x[a]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = quaternion_dcm_terms(xa[6], xa[7], xa[8], xa[9])
        vel[a, 0] = r00 * xa[0] + r01 * xa[1] + r02 * xa[2]
        vel[a, 1] = r10 * xa[0] + r11 * xa[1] + r12 * xa[2]
        vel[a, 2] = r20 * xa[0] + r21 * xa[1] + r22 * xa[2]
        chi[a] = math.atan2(vd[a, 1], vd[a, 0])
    for a in range(nv):
        xa = x[a]
        o = out[a]
        for k in range(3):
            wind[k] = amb[a, k] + induced[a, k]
        va, al, be = air_data_kernel(xa, wind, air_params)[:3]
        e0, ex, ey, ez = xa[6], xa[7], xa[8], xa[9]
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
        o[6], o[7], o[8] = xa[3], xa[4], xa[5]
        o[9] = signed_log(-xa[POS_D] - altitude, ALTITUDE_SCALE_M)
        dx, dy, dz = xa[POS_N] - pd[a, 0], xa[POS_E] - pd[a, 1], xa[POS_D] - pd[a, 2]
        tx, ty = ned_to_track_xy(c, s, dx, dy)
        o[10] = signed_log(tx, POSITION_SCALE_M)
        o[11] = signed_log(ty, POSITION_SCALE_M)
        o[12] = signed_log(dz, POSITION_SCALE_M)
        dx, dy, dz = vel[a, 0] - vd[a, 0], vel[a, 1] - vd[a, 1], vel[a, 2] - vd[a, 2]
        tx, ty = ned_to_track_xy(c, s, dx, dy)
        o[13] = signed_log(tx, VELOCITY_SCALE_MPS)
        o[14] = signed_log(ty, VELOCITY_SCALE_MPS)
        o[15] = signed_log(dz, VELOCITY_SCALE_MPS)
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = quaternion_dcm_terms(e0, ex, ey, ez)
        w0, w1, w2 = induced[a, 0], induced[a, 1], induced[a, 2]
        o[16] = r00 * w0 + r10 * w1 + r20 * w2  # body = R^T ned
        o[17] = r01 * w0 + r11 * w1 + r21 * w2
        o[18] = r02 * w0 + r12 * w1 + r22 * w2
        o[19], o[20], o[21] = omega[a, 0], omega[a, 1], omega[a, 2]
        dx, dy, dz = amb[a, 0], amb[a, 1], amb[a, 2]
        tx, ty = ned_to_track_xy(c, s, dx, dy)
        o[22] = signed_log(tx, WIND_SCALE_MPS)
        o[23] = signed_log(ty, WIND_SCALE_MPS)
        o[24] = signed_log(dz, WIND_SCALE_MPS)
        o[25] = xa[14] / OMEGA_REF - 1.0
        o[26], o[27], o[28], o[29] = prev[a, 0], prev[a, 1], prev[a, 2], prev[a, 3]
        k = 30
        for m in range(SCHEDULE_SIZE):
            o[k + m] = schedule[a, m]
        k += SCHEDULE_SIZE
        for m in range(CONTROLLER_STATE_SIZE):
            o[k + m] = signed_log(cstate[a, m], CONTROLLER_STATE_SCALE)
        k += CONTROLLER_STATE_SIZE
        m_n = nv - 1 if neighbour_count <= 0 else neighbour_count
        kw = k + 6 * m_n  # the neighbour_wind group (with neighbour_wind) follows the neighbours, in their order
        ka = kw + 3 * m_n if neighbour_wind else kw  # then the neighbour_attitude group (with neighbour_attitude)
        for m in range(m_n):
            j = _neighbour(pd, a, m, neighbour_count)
            if neighbour_attitude:
                # where the neighbour's wingtip vortices lie: its roll moves its tips +-b/2 sin(phi) up and down
                # (3.3 deg RMS for the air-relative leader at sigma 1: 0.08 m, half the followers' vertical error),
                # which no other group carries (a memoryless policy cannot differentiate the relative velocities)
                if j < 0:
                    o[ka], o[ka + 1], o[ka + 2] = 0.0, 0.0, 0.0
                else:
                    xj = x[j]
                    f0, f1, f2, f3 = xj[6], xj[7], xj[8], xj[9]
                    nj = f0 * f0 + f1 * f1 + f2 * f2 + f3 * f3
                    phj = math.atan2(2.0 * (f0 * f1 + f2 * f3), f0 * f0 - f1 * f1 - f2 * f2 + f3 * f3)
                    thj = math.asin(min(1.0, max(-1.0, 2.0 * (f0 * f2 - f1 * f3) / nj)))
                    o[ka] = phj / 0.5
                    o[ka + 1] = xj[3]
                    o[ka + 2] = (thj - theta) / 0.5
                ka += 3
            if neighbour_wind:
                # the gust the neighbour meets against the agent's own: what moves it (and its wake) relative to
                # the agent; in a frozen field the one ahead meets now what the agent meets a fraction of a second on
                if j < 0:
                    o[kw], o[kw + 1], o[kw + 2] = 0.0, 0.0, 0.0
                else:
                    dx, dy, dz = amb[j, 0] - amb[a, 0], amb[j, 1] - amb[a, 1], amb[j, 2] - amb[a, 2]
                    tx, ty = ned_to_track_xy(c, s, dx, dy)
                    o[kw] = signed_log(tx, WIND_SCALE_MPS)
                    o[kw + 1] = signed_log(ty, WIND_SCALE_MPS)
                    o[kw + 2] = signed_log(dz, WIND_SCALE_MPS)
                kw += 3
            if j < 0:  # fewer UAVs than the policy observes: a far one behind, at the agent's velocity
                o[k] = signed_log(-ABSENT_NEIGHBOUR_M, NEIGHBOUR_POSITION_SCALE_M)
                for q in range(1, 6):
                    o[k + q] = 0.0
                k += 6
                continue
            dx, dy, dz = x[j, POS_N] - xa[POS_N], x[j, POS_E] - xa[POS_E], x[j, POS_D] - xa[POS_D]
            tx, ty = ned_to_track_xy(c, s, dx, dy)
            o[k] = signed_log(tx, NEIGHBOUR_POSITION_SCALE_M)
            o[k + 1] = signed_log(ty, NEIGHBOUR_POSITION_SCALE_M)
            o[k + 2] = signed_log(dz, NEIGHBOUR_POSITION_SCALE_M)
            dx, dy, dz = vel[j, 0] - vel[a, 0], vel[j, 1] - vel[a, 1], vel[j, 2] - vel[a, 2]
            tx, ty = ned_to_track_xy(c, s, dx, dy)
            o[k + 3] = signed_log(tx, VELOCITY_SCALE_MPS)
            o[k + 4] = signed_log(ty, VELOCITY_SCALE_MPS)
            o[k + 5] = signed_log(dz, VELOCITY_SCALE_MPS)
            k += 6
        for k in range(o.shape[0]):
            o[k] = _clean(o[k])


@_jit
def _neighbour(pd, a, m, neighbour_count):
    """The UAV in place ``m`` of agent ``a``'s neighbours (-1: none): with ``neighbour_count`` 0 the m-th other
    UAV by index; else the m-th nearest by demanded position (slot) to the agent's, ties by index (the order
    is the slots', so it holds while the UAVs move about them)."""
    nv = pd.shape[0]
    if neighbour_count <= 0:
        return m if m < a else m + 1
    if m >= nv - 1:
        return -1
    # selection by rank: j is in place m when exactly m others come before it (nearer, or as near with a
    # lower index); V is small (<= 9 in the tasks), so O(V^2) per place is cheaper than sorting
    for j in range(nv):
        if j == a:
            continue
        dj = (pd[j, 0] - pd[a, 0]) ** 2 + (pd[j, 1] - pd[a, 1]) ** 2 + (pd[j, 2] - pd[a, 2]) ** 2
        before = 0
        for i in range(nv):
            if i == a or i == j:
                continue
            di = (pd[i, 0] - pd[a, 0]) ** 2 + (pd[i, 1] - pd[a, 1]) ** 2 + (pd[i, 2] - pd[a, 2]) ** 2
            if di < dj or (di == dj and i < j):
                before += 1
        if before == m:
            return j
    return -1


@_jit
def slot_error(dn, de, dd, chi, axes):
    """Distance (m) from the slot of a UAV displaced (dn, de, dd) NED from it, its slot-frame components
    (along the track at angle ``chi``, starboard, down) weighted by ``axes`` (3,): (1, 1, 1) the
    Euclidean distance; (1, 0, 0) the along-track distance only (a safe-box task: the follower is free
    across and up/down within its box)."""
    tx, ty = ned_to_track_xy(math.cos(chi), math.sin(chi), dn, de)
    ex, ey, ez = axes[0] * tx, axes[1] * ty, axes[2] * dd
    return math.sqrt(ex * ex + ey * ey + ez * ez)


@_jit
def box_depth_each(x, chi, low, high, out):
    """(V,) distance (m) of each UAV outside its safe box, 0 inside: the box is ``low``..``high`` (V, 3)
    relative to vehicle 0 in the slot frame (x along the track at angle ``chi`` rad from north, y
    starboard, z down). Non-finite positions count as 0 here (the episode is ending; the crash term
    charges it)."""
    c, s = math.cos(chi), math.sin(chi)
    for a in range(x.shape[0]):
        dn, de, dd = x[a, POS_N] - x[0, POS_N], x[a, POS_E] - x[0, POS_E], x[a, POS_D] - x[0, POS_D]
        tx, ty = ned_to_track_xy(c, s, dn, de)
        rel = (tx, ty, dd)
        depth2 = 0.0
        for k in range(3):
            over = max(low[a, k] - rel[k], rel[k] - high[a, k], 0.0)
            depth2 += over * over
        out[a] = math.sqrt(depth2) if depth2 == depth2 else 0.0


@_jit
def _huber(x):
    ax = abs(x)
    return 0.5 * ax * ax if ax <= 1.0 else ax - 0.5


@_jit
def _capped(e):
    return min(e, _ERROR_CAP_M) if math.isfinite(e) else _ERROR_CAP_M


@_jit
def reward_formation(w, error, previous_error, action, previous_action, saving, separation, collided, crashed,
                     remaining_decisions, box_depth, out):
    """Reward terms (V, 10) in :data:`REWARD_TERMS` order of one formation (the definition:
    :class:`formation_env.envs.config.RewardWeights`). error, previous_error (V,) m; separation (V,)
    m to the nearest UAV; collided bool; crashed (V,) bool; remaining_decisions until the time limit;
    box_depth (V,) m outside the safe box (0 inside)."""
    d_safe = w.barrier_separation_m
    for a in range(error.shape[0]):
        err, prev = _capped(error[a]), _capped(previous_error[a])
        cost, cost_prev = _huber(err / w.slot_scale_m), _huber(prev / w.slot_scale_m)
        sep = separation[a]
        if sep != sep:
            sep = 0.0
        depth = min(1.0, max(0.0, (d_safe - sep) / max(d_safe - w.collision_separation_m, 1e-9)))
        forfeit = w.terminal_forfeit * w.slot * _huber(min(prev, _TERMINAL_ERROR_CAP_M) / w.slot_scale_m) * remaining_decisions
        # the hold phase's costs still to come go with the episode's end (a step each, whatever the error)
        hold_left = w.terminal_forfeit * w.hold * max(0.0, min(remaining_decisions, w.hold_remaining[a]))
        effort = 0.0
        rate = 0.0
        for k in range(4):
            effort += action[a, k] * action[a, k]
            rate += (action[a, k] - previous_action[a, k]) ** 2
        out[a, 0] = -w.slot * cost
        out[a, 1] = w.progress * (cost_prev - w.shaping_gamma * cost)  # gamma Phi(s') - Phi(s), Phi = -cost
        out[a, 2] = -w.separation * depth * depth
        out[a, 3] = -w.effort * effort / 4.0
        out[a, 4] = -w.rate * rate / 4.0
        out[a, 5] = w.benefit * min(saving[a], w.benefit_cap) if math.isfinite(saving[a]) else 0.0
        out[a, 6] = -(w.collision + forfeit + hold_left) if collided else 0.0
        out[a, 7] = -(w.crash + forfeit + hold_left) if crashed[a] else 0.0
        # capped at BOX_DEPTH_CAP_SCALES: far outside the box the cost stays bounded (the returns'
        # scale), and the step at the wall already outweighs any saving the ELL reports beyond it
        depth_scales = min(box_depth[a] / w.box_scale_m, BOX_DEPTH_CAP_SCALES)
        out[a, 8] = -w.box * (1.0 + _huber(depth_scales)) if box_depth[a] > 0.0 else 0.0
        in_hold = remaining_decisions <= w.hold_remaining[a]
        out[a, 9] = -w.hold if (w.hold > 0.0 and in_hold and not err < w.hold_radius_m) else 0.0
