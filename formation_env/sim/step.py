"""One compiled, batched decision step: ``step(params, state, actions) -> StepOutput``.

Per formation (B formations over a thread pool) and per physics substep, in this order (thesis chapter 6's
loop, the Simulink model's order):

1. guidance: vehicle 0's reference path and the followers' slot demands (:mod:`.guidance`);
2. ambient wind: scenario gusts + steady wind + the turbulence at each UAV (sampled at its
   position at the end of the previous substep);
3. control: the thesis PID (:func:`formation_env.control.law.fcs_update`) for every UAV it flies,
   with the agents' actions mapped per mode: ``setpoints`` moves the PID's demands, ``residual`` adds
   to its command, ``surfaces`` replaces it;
4. ELL effective wind every ``wake_update_every``-th substep (Eqs. 4.4-4.7), Aerosonde RK4 and
   the envelope (:func:`formation_env.sim.kernels.step_one`);
5. turbulence field advanced one step and sampled at the new positions.

With the benefit on, the induced-drag saving of the decision is read off the last substep's ELL
solve (the poses and circulation the physics used), so it costs only the Kutta-Joukowski loads and
each UAV's isolated solve, not another joint solve.

A formation stops its substeps as soon as a UAV leaves the envelope (its episode ends). Then the
demands at the new state, the observation, the formation benefit and the reward are formed
(:mod:`.observe`). The state is updated in place and nothing else is kept between calls
(:func:`formation_env.sim.state.copy_state` gives functional semantics when needed).

Threads: the kernel releases the GIL; the calling thread and ``numba.get_num_threads() - 1`` pool
workers (``NUMBA_NUM_THREADS`` applies) take chunks of formations from a shared counter, one
parallel region per decision; a tuner measures serial against threaded per batch size and keeps the
faster (a preempted thread stalls a small batch; see :class:`_ThreadTuner`). numba's ``prange`` cannot take these named structs of arrays, and its OpenMP barrier is
what collapsed under a busy core (25x at B = 16); with a queue, a thread on a busy core simply takes
fewer chunks.
"""

from __future__ import annotations

import itertools
import math
import time
from concurrent.futures import ThreadPoolExecutor

import numba as nb
import numpy as np

from ..aircraft.kernels import _air
from ..atmosphere.frozen_field import _advance_one, _sample_one, N_STREAMS_PER_LANE
from ..control.law import fcs_update
from ..frames import quaternion_dcm_terms
from .guidance import formation_demands, gust_wind_ned, reference_path, schedule_features
from ..wake.benefit import induced_drag_saving_one
from ..wake.arrays import evaluate_formation
from .kernels import ell_inputs, step_one
from .kernels import position_finite as _position_finite
from .kernels import separation_each_known as _separation_each_known
from .kernels import step_separation as _step_separation
from .observe import box_depth_each, observe_formation, min_separation_each, reward_formation, slot_error
from .params import RESIDUAL, SETPOINTS, SURFACES, StepParams
from .state import SimState, StepOutput

__all__ = ["step", "refresh", "observe", "PARALLEL_MIN_BATCH"]

PARALLEL_MIN_BATCH = 2  # a single formation runs serially (no thread start-up)


@nb.njit(cache=True, error_model="numpy")
def _velocity_ned(x, out):
    for a in range(x.shape[0]):
        xa = x[a]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = quaternion_dcm_terms(xa[6], xa[7], xa[8], xa[9])
        out[a, 0] = r00 * xa[0] + r01 * xa[1] + r02 * xa[2]
        out[a, 1] = r10 * xa[0] + r11 * xa[1] + r12 * xa[2]
        out[a, 2] = r20 * xa[0] + r21 * xa[1] + r22 * xa[2]


@nb.njit(cache=True, error_model="numpy")
def _sample_turbulence(p, s, b, scratch_n, out):
    """Turbulence (V, 3) NED at each UAV of formation b now: the frozen field read at the UAVs'
    positions (cross-correlated, transport-delayed), or independent lanes (each UAV its own stream,
    no delay). Non-finite values (a diverged UAV, episode ending) read as 0."""
    nv = out.shape[0]
    chi = math.atan2(s.velocity_demand[b, 0, 1], s.velocity_demand[b, 0, 0])
    if not math.isfinite(chi):
        chi = 0.0
    if p.turbulence == 1:
        pos = s.aircraft[:, :, 10:13]
        _sample_one(p.field, s.field, b, pos, chi, s.gust_ned, np.empty(nv), np.empty(nv), np.empty(nv),
                    np.empty(nv, dtype=np.int64), np.empty(nv, dtype=np.int64), np.empty(nv), np.empty((nv, nv)),
                    np.empty((nv, nv)), np.empty((nv, 3)))
    else:
        head = s.field.head[b]
        cs, sn = math.cos(chi), math.sin(chi)
        for i in range(nv):
            u = p.field.sigma_mps[0] * s.field.ring[b, head, 0, i]
            v = p.field.sigma_mps[1] * s.field.ring[b, head, 1, i]
            s.gust_ned[b, i, 0] = cs * u - sn * v
            s.gust_ned[b, i, 1] = sn * u + cs * v
            s.gust_ned[b, i, 2] = p.field.sigma_mps[2] * s.field.ring[b, head, 2, i]
    for i in range(nv):
        for k in range(3):
            if not math.isfinite(s.gust_ned[b, i, k]):
                s.gust_ned[b, i, k] = 0.0


@nb.njit(cache=True, error_model="numpy")
def _ambient(p, s, b, t, out, g):
    """Ambient wind (V, 3) NED m/s: scenario gusts + steady wind + turbulence at each UAV (g: (3,) scratch)."""
    gust_wind_ned(p.scenario, t, g)
    for a in range(out.shape[0]):
        for k in range(3):
            out[a, k] = g[k] + s.steady_wind[b, k] + s.gust_ned[b, a, k]


@nb.njit(cache=True, error_model="numpy")
def _setpoint_shift(a, low, high):
    """Set-point offset (m) of one axis for action a in [-1, 1]: a * high above 0, -a * low below."""
    return a * high if a >= 0.0 else -a * low


@nb.njit(cache=True, error_model="numpy")
def _control(p, s, b, actions, amb, vel, cmd, wind, pd, vd, rate, sig):
    """Commands (V, 4) of formation b: the PID (with setpoint-shifted demands) and the agents.
    wind (12,) zeroed, pd, vd (3,), rate (7,), sig (10,): scratch."""
    ap = p.action
    for a in range(cmd.shape[0]):
        agent = ap.agent_mask[a]
        if agent and ap.mode == SURFACES:
            for k in range(4):
                cmd[a, k] = min(max(ap.trim_controls[k] + actions[a, k] * ap.surface_scale[k], ap.command_min[k]),
                                ap.command_max[k])
            continue
        x = s.aircraft[b, a]
        for k in range(3):
            pd[k] = s.position_demand[b, a, k]
            vd[k] = s.velocity_demand[b, a, k]
        if agent and ap.mode == SETPOINTS:
            # shift the demands in the slot frame (along the demanded track, starboard, down)
            # (piecewise linear per axis: 0 is the slot, +-1 the set-point range's ends)
            chi = math.atan2(vd[1], vd[0])
            c, sn = math.cos(chi), math.sin(chi)
            dx, dy, dz = (_setpoint_shift(actions[a, 0], ap.setpoint_low_m[0], ap.setpoint_high_m[0]),
                          _setpoint_shift(actions[a, 1], ap.setpoint_low_m[1], ap.setpoint_high_m[1]),
                          _setpoint_shift(actions[a, 2], ap.setpoint_low_m[2], ap.setpoint_high_m[2]))
            pd[0] += c * dx - sn * dy
            pd[1] += sn * dx + c * dy
            pd[2] += dz
            speed = math.sqrt(vd[0] * vd[0] + vd[1] * vd[1] + vd[2] * vd[2])
            f = actions[a, 3] * ap.setpoint_speed_mps / max(speed, 1e-9)
            for k in range(3):
                vd[k] += vd[k] * f
        for k in range(3):
            wind[k] = amb[a, k]
            wind[6 + k] = s.induced_wind_ned[b, a, k]
        airspeed = _air(x, wind, p.aircraft.scalars)[0]
        e0, ex, ey, ez = x[6], x[7], x[8], x[9]
        n2 = e0 * e0 + ex * ex + ey * ey + ez * ez
        phi = math.atan2(2.0 * (e0 * ex + ey * ez), e0 * e0 - ex * ex - ey * ey + ez * ez)
        theta = math.asin(min(1.0, max(-1.0, 2.0 * (e0 * ey - ex * ez) / n2)))
        psi = math.atan2(2.0 * (ex * ey + e0 * ez), e0 * e0 + ex * ex - ey * ey - ez * ez)
        fcs_update(x[10:13], vel[a], phi, theta, psi, x[4], x[5], airspeed, pd, vd, s.controller[b, a], p.fcs,
                   cmd[a], rate, sig)
        if agent and ap.mode == RESIDUAL:
            for k in range(4):
                cmd[a, k] = min(max(cmd[a, k] + actions[a, k] * ap.residual_scale[k], ap.command_min[k]),
                                ap.command_max[k])


@nb.njit(cache=True, error_model="numpy")
def _physics(p, s, b, cmd, amb, zero_turb, new_state, status):
    """ELL (when due) -> RK4 -> envelope of formation b, one dt (formation_env.sim.kernels.step_one);
    turbulence is in the ambient wind (NED), so the body-axis turbulence input is zero_turb (V, 3)."""
    update = s.step[b] % p.wake_update_every == 0
    step_one(s.aircraft[b], cmd, amb, zero_turb, s.induced_wind_ned[b], s.induced_omega_body[b],
             s.circulation[b], update, p.wake_on, p.wake, p.aircraft, p.dt_s, new_state, status)


@nb.njit(cache=True, error_model="numpy")
def formation_benefit(p, s, b, amb, out_saving):
    """Induced-drag saving (V,) of formation b at its current state: one ELL solve at the current
    poses (relative to the ambient air), then Kutta-Joukowski drag against each UAV flying alone
    (:func:`formation_env.wake.benefit.induced_drag_saving_one`). Zero for a formation with a
    non-finite UAV (its episode is ending)."""
    nv = s.aircraft.shape[1]
    for a in range(nv):
        out_saving[a] = 0.0
        for k in range(s.aircraft.shape[2]):
            if not math.isfinite(s.aircraft[b, a, k]):
                return
    w = p.wake
    pos, euler = np.empty((nv, 3)), np.empty((nv, 3))
    speed, alpha, beta = np.empty(nv), np.empty(nv), np.empty(nv)
    ell_inputs(s.aircraft[b], amb, w.wing_origin_body, pos, euler, speed, alpha, beta)
    gamma = np.empty(w.panel_left_knot.shape[0])
    evaluate_formation(w, pos, euler, speed, alpha, beta, gamma, np.empty((gamma.shape[0], 3)), np.empty((nv, 3)),
                       np.empty((nv, 3)), np.empty((nv, 3)), np.empty((nv, 3)))
    induced_drag_saving_one(w, p.wake_alone, pos, euler, speed, alpha, beta, gamma, out_saving)


@nb.njit(cache=True, error_model="numpy")
def refresh_formation(p, s, b):
    """Demands and turbulence of formation b at its current state and time (after a reset)."""
    nv = s.aircraft.shape[1]
    vel = np.empty((nv, 3))
    _velocity_ned(s.aircraft[b], vel)
    formation_demands(p.scenario, s.step[b] * p.dt_s, s.aircraft[b], vel, s.reference_position[b], s.manoeuvre[b],
                      s.slot_jitter[b], s.position_demand[b], s.velocity_demand[b])
    if p.turbulence != 0:
        _sample_turbulence(p, s, b, np.empty(N_STREAMS_PER_LANE), s.gust_ned[b])


@nb.njit(cache=True, error_model="numpy")
def observe_one(p, s, b, out_obs):
    """Observation rows (V, D) of formation b at its current state."""
    nv = s.aircraft.shape[1]
    amb = np.empty((nv, 3))
    _ambient(p, s, b, s.step[b] * p.dt_s, amb, np.empty(3))
    sched = np.empty((nv, 10))
    schedule_features(p.scenario, s.step[b] * p.dt_s, s.slot_jitter[b], sched)
    observe_formation(s.aircraft[b], s.induced_wind_ned[b], s.induced_omega_body[b], amb, s.position_demand[b],
                      s.velocity_demand[b], s.previous_action[b], sched, s.controller[b], p.trim_airspeed_mps,
                      p.scenario.altitude_m, p.aircraft.scalars, np.empty((nv, 3)), np.empty(nv), out_obs)


@nb.njit(cache=True, error_model="numpy")
def decide_one(p, s, b, actions, o):
    """One decision of formation b: substeps, then observation, reward and events into ``o``.

    Collision: the smallest CG separation over the decision's physics steps below the collision
    separation (a step that also made a state non-finite is judged from its pre-step positions and
    velocities, :func:`formation_env.sim.kernels.step_separation`). A UAV whose state went non-finite is measured (slot error,
    separation) at its last finite position, so ``o`` never carries NaN."""
    nv = s.aircraft.shape[1]
    amb = np.empty((nv, 3))
    vel = np.empty((nv, 3))
    cmd = np.empty((nv, 4))
    new = np.empty((nv, s.aircraft.shape[2]))
    status = np.zeros(nv, dtype=np.int64)
    scratch_n = np.empty(N_STREAMS_PER_LANE)
    status_any = np.zeros(nv, dtype=np.int64)
    min_sep = np.inf
    # per-decision scratch (allocating inside the substep loop costs ~10 % of a step)
    g3, zero_turb = np.empty(3), np.zeros((nv, 3))
    wind12, pd3, vd3, rate7, sig10 = np.zeros(12), np.empty(3), np.empty(3), np.empty(s.controller.shape[2]), np.empty(10)
    # formation benefit: read off the last substep's ELL solve (its poses and circulation), which
    # the physics needs anyway; a fresh solve only when that substep had none
    ell_pos, ell_euler = np.empty((nv, 3)), np.empty((nv, 3))
    ell_speed, ell_alpha, ell_beta = np.empty(nv), np.empty(nv), np.empty(nv)
    solved_last = False
    # last finite CG position of each UAV (what the outputs measure a diverged UAV by) and the
    # pre-step state of each physics step (its collision check when the step goes non-finite)
    last_pos = np.empty((nv, 3))
    known = np.zeros(nv, dtype=np.bool_)
    pre = np.empty((nv, s.aircraft.shape[2]))
    for a in range(nv):
        if _position_finite(s.aircraft[b], a):
            known[a] = True
            for k in range(3):
                last_pos[a, k] = s.aircraft[b, a, 10 + k]
    for sub in range(p.substeps):
        t = s.step[b] * p.dt_s
        _velocity_ned(s.aircraft[b], vel)
        formation_demands(p.scenario, t, s.aircraft[b], vel, s.reference_position[b], s.manoeuvre[b],
                          s.slot_jitter[b], s.position_demand[b], s.velocity_demand[b])
        _ambient(p, s, b, t, amb, g3)
        _control(p, s, b, actions, amb, vel, cmd, wind12, pd3, vd3, rate7, sig10)
        solved_last = False
        if p.benefit_on and sub == p.substeps - 1 and s.step[b] % p.wake_update_every == 0:
            ell_inputs(s.aircraft[b], amb, p.wake.wing_origin_body, ell_pos, ell_euler, ell_speed, ell_alpha, ell_beta)
            solved_last = True
        pre[:, :] = s.aircraft[b]
        _physics(p, s, b, cmd, amb, zero_turb, new, status)
        if solved_last:  # step_one solved unless the formation was outside the envelope (gamma zeroed)
            solved_last = False
            for k in range(s.circulation.shape[1]):
                if s.circulation[b, k] != 0.0:
                    solved_last = True
                    break
        s.aircraft[b] = new
        s.command[b] = cmd
        for a in range(nv):
            s.status[b, a] = status[a]
            status_any[a] |= status[a]
        if p.turbulence != 0:
            _advance_one(p.field, s.field, b, scratch_n)
            _sample_turbulence(p, s, b, scratch_n, s.gust_ned[b])
        if p.scenario.manoeuvres:  # the manoeuvring reference integrates on the physics grid
            reference_path(p.scenario, t, s.reference_position[b], s.manoeuvre[b], pd3, vd3)
            for k in range(3):
                s.reference_position[b, k] += p.dt_s * vd3[k]
        s.step[b] += 1
        # never NaN: a step that overlaps two UAVs is a collision even if it also diverged one of them
        d = _step_separation(pre, vel, s.aircraft[b], p.dt_s)
        if d < min_sep:
            min_sep = d
        for a in range(nv):
            if _position_finite(s.aircraft[b], a):
                known[a] = True
                for k in range(3):
                    last_pos[a, k] = s.aircraft[b, a, 10 + k]
        stop = False
        for a in range(nv):
            if status_any[a] != 0:
                stop = True
        if stop or d < p.reward.collision_separation_m or d != d:
            break
    # the demands at the new state: what the observation and the reward measure against
    _velocity_ned(s.aircraft[b], vel)
    formation_demands(p.scenario, s.step[b] * p.dt_s, s.aircraft[b], vel, s.reference_position[b], s.manoeuvre[b],
                      s.slot_jitter[b], s.position_demand[b], s.velocity_demand[b])
    collided = min_sep < p.reward.collision_separation_m
    crashed_any = False
    if p.scenario.slot_along_leader_demand:  # the slot frame (the safe box and the slot error's axes)
        chi_slot = math.atan2(s.velocity_demand[b, 0, 1], s.velocity_demand[b, 0, 0])
    else:
        chi_slot = math.atan2(vel[0, 1], vel[0, 0])
    if not math.isfinite(chi_slot):
        chi_slot = 0.0
    for a in range(nv):
        o.crashed[b, a] = status_any[a] != 0
        crashed_any = crashed_any or status_any[a] != 0
        # a UAV whose state went non-finite (crashed) is measured at its last finite position
        px, py, pz = s.aircraft[b, a, 10], s.aircraft[b, a, 11], s.aircraft[b, a, 12]
        if not _position_finite(s.aircraft[b], a) and known[a]:
            px, py, pz = last_pos[a, 0], last_pos[a, 1], last_pos[a, 2]
        dx = px - s.position_demand[b, a, 0]
        dy = py - s.position_demand[b, a, 1]
        dz = pz - s.position_demand[b, a, 2]
        err = slot_error(dx, dy, dz, chi_slot, p.reward.slot_error_axes)
        if not math.isfinite(err):  # no finite position or demand known: the previous error, else 0
            err = s.previous_error[b, a] if math.isfinite(s.previous_error[b, a]) else 0.0
        o.slot_error_m[b, a] = err
    min_separation_each(s.aircraft[b], o.separation_m[b])
    finite_sep = True
    for a in range(nv):
        if o.separation_m[b, a] != o.separation_m[b, a]:
            finite_sep = False
    if not finite_sep:
        _separation_each_known(last_pos, known, o.separation_m[b])
    o.collided[b] = collided
    # inf (one UAV, or nothing known) stays inf as before; never NaN
    o.min_separation_m[b] = min_sep
    o.terminated[b] = collided or crashed_any
    o.truncated[b] = (not o.terminated[b]) and s.step[b] >= p.episode_steps
    if p.benefit_on:
        if crashed_any:
            for a in range(nv):
                o.saving[b, a] = 0.0
        elif solved_last:
            induced_drag_saving_one(p.wake, p.wake_alone, ell_pos, ell_euler, ell_speed, ell_alpha, ell_beta,
                                    s.circulation[b], o.saving[b])
        else:
            _ambient(p, s, b, s.step[b] * p.dt_s, amb, g3)
            formation_benefit(p, s, b, amb, o.saving[b])
    remaining = max(p.episode_steps - s.step[b], 0) / p.substeps
    box_depth_each(s.aircraft[b], chi_slot, p.reward.box_low_m, p.reward.box_high_m, o.box_depth_m[b])
    reward_formation(p.reward, o.slot_error_m[b], s.previous_error[b], actions, s.previous_action[b], o.saving[b],
                     o.separation_m[b], collided, o.crashed[b], remaining, o.box_depth_m[b], o.reward_terms[b])
    for a in range(nv):
        total = 0.0
        for k in range(o.reward_terms.shape[2]):
            total += o.reward_terms[b, a, k]
        o.reward[b, a] = total
        s.episode_return[b, a] += total
        s.previous_error[b, a] = o.slot_error_m[b, a]
        for k in range(4):
            s.previous_action[b, a, k] = actions[a, k]
    s.episode_decisions[b] += 1
    observe_one(p, s, b, o.observation[b])


@nb.njit(cache=True, nogil=True, error_model="numpy")
def decide_range(p, s, actions, o, start, stop):
    """:func:`decide_one` for formations start..stop-1 (releases the GIL: threads run chunks)."""
    for b in range(start, stop):
        decide_one(p, s, b, actions[b], o)


@nb.njit(cache=True, nogil=True, error_model="numpy")
def refresh_range(p, s, indices, observation, start, stop):
    """:func:`refresh_formation` and :func:`observe_one` for indices[start:stop]."""
    for q in range(start, stop):
        b = indices[q]
        refresh_formation(p, s, b)
        observe_one(p, s, b, observation[b])


_POOL: ThreadPoolExecutor | None = None
_POOL_SIZE = 0


def _threads() -> int:
    return max(1, int(nb.get_num_threads()))


def _run_parallel(kernel, n: int, args: tuple, threads: int) -> None:
    """``kernel(*args, start, stop)`` over 0..n in chunks, on the calling thread plus ``threads - 1``
    pool workers taking chunks (about four per thread) from a shared counter."""
    global _POOL, _POOL_SIZE
    if _POOL is None or _POOL_SIZE != threads - 1:
        if _POOL is not None:
            _POOL.shutdown(wait=False)
        _POOL, _POOL_SIZE = ThreadPoolExecutor(threads - 1, thread_name_prefix="formation-step"), threads - 1
    chunk = max(1, -(-n // (4 * threads)))
    n_chunks = -(-n // chunk)
    counter = itertools.count()  # next() is atomic under the GIL

    def work():
        while True:
            c = next(counter)
            if c >= n_chunks:
                return
            kernel(*args, c * chunk, min((c + 1) * chunk, n))

    futures = [_POOL.submit(work) for _ in range(threads - 1)]
    work()
    for f in futures:
        f.result()


class _ThreadTuner:
    """Serial or threaded, whichever is measured faster for this kernel and batch size.

    A thread that another process preempts holds its chunk until the scheduler returns (milliseconds),
    and the decision waits for it: on a busy machine small batches run faster serially, large ones
    threaded. Each (kernel, B) keeps a moving average of the wall time of both settings, uses the
    faster and re-measures the other every ``EXPLORE``-th call, so throughput follows the machine's
    load. Results do not depend on the choice (formations are independent: bit-identical)."""

    EXPLORE = 32
    ALPHA = 0.25

    def __init__(self) -> None:
        self.stats: dict = {}

    def run(self, kernel, n: int, args: tuple) -> None:
        if n < PARALLEL_MIN_BATCH:
            kernel(*args, 0, n)
            return
        threads = min(_threads(), n)
        if threads <= 1:
            kernel(*args, 0, n)
            return
        st = self.stats.setdefault((kernel, n, threads), [math.inf, math.inf, 0])
        st[2] += 1
        calls = st[2]
        if calls <= 5:  # warm-up: serial, threaded, serial, threaded (the first call may compile)
            use_threads = calls % 2 == 0
        else:
            use_threads = st[1] < st[0]
            if calls % self.EXPLORE == 0:
                use_threads = not use_threads
        t0 = time.perf_counter()
        if use_threads:
            _run_parallel(kernel, n, args, threads)
        else:
            kernel(*args, 0, n)
        dt = time.perf_counter() - t0
        if calls > 1:
            k = 1 if use_threads else 0
            st[k] = dt if st[k] == math.inf else (1.0 - self.ALPHA) * st[k] + self.ALPHA * dt


_TUNER = _ThreadTuner()


def _run_chunks(kernel, n: int, args: tuple) -> None:
    _TUNER.run(kernel, n, args)


def step(params: StepParams, state: SimState, actions: np.ndarray, out: StepOutput) -> StepOutput:
    """Advance every formation by one decision with ``actions`` (B, V, 4) in [-1, 1] (rows of
    PID-flown vehicles are ignored); results into ``out`` (returned). Inputs are not checked here:
    the env adapters validate once per decision."""
    _run_chunks(decide_range, actions.shape[0], (params, state, actions, out))
    return out


def refresh(params: StepParams, state: SimState, indices: np.ndarray, out: StepOutput) -> None:
    """After resetting formations ``indices``: their demands, turbulence sample and observation."""
    _run_chunks(refresh_range, indices.shape[0], (params, state, np.ascontiguousarray(indices, dtype=np.int64),
                                                  out.observation))


def observe(params: StepParams, state: SimState, out: StepOutput) -> np.ndarray:
    """Recompute every formation's observation at its current state into ``out.observation``."""
    refresh(params, state, np.arange(state.step.shape[0]), out)
    return out.observation
