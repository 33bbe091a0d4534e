"""One physics step of a chunk of formations after its control (:func:`formation_env.sim.step.decide_chunk`):
:func:`physics_before_wake` (per formation: the pre-step state, what the step does with the wake, the ELL inputs),
:func:`solve_chunk` (the ELL of the chunk's formations: across the vector lanes, :mod:`formation_env.wake.across`, or
one formation at a time), :func:`physics_after_wake` (per formation: the solve taken over and coupled, RK4, the
envelope). Together, the operations of :func:`formation_env.sim.kernels.step_one`, bit for bit. Arguments as in
:mod:`.stages`; ``ell`` an :class:`EllChunk` (a view of it), ``l`` a formation's lane in the chunk.
"""

from __future__ import annotations

from typing import NamedTuple

import numba as nb
import numpy as np

from ..wake.across import LANES, ChunkScratch, chunk_scratch, field_chunk, solve_chunk_lanes
from ..wake.across_loads import induced_drags_chunk
from ..wake.arrays import evaluate_formation
from ..wake.benefit import AIR_DENSITY_SL
from ..wake.biot_savart import sheet_on
from ..wake.coupling import couple_solved
from .kernels import (WAKE_CLEAR, WAKE_SOLVE, clear_if_not_finite, clear_wake, ell_inputs, integrate_one,
                      wake_action)
from .views import struct_view

__all__ = ["EllChunk", "ell_chunk", "physics_before_wake", "solve_chunk", "physics_after_wake", "drags_chunk"]

_jit = nb.njit(cache=True, error_model="numpy")
# inlined into the decision at numba IR level (formation_env.sim.stages says why)
_jit_inline = nb.njit(cache=True, error_model="numpy", inline="always")


class EllChunk(NamedTuple):
    """The ELL of a chunk of up to LANES formations solved together (:func:`formation_env.wake.across.evaluate_chunk`):
    each lane's inputs (the poses of the formations that solve this physics step), outputs and what the step does
    with the wake (V vehicles, N panels); allocated once per decision kernel call."""

    c: ChunkScratch
    act: np.ndarray  # (LANES,) int64 WAKE_HOLD | WAKE_SOLVE | WAKE_CLEAR of each lane's formation this physics step
    pos: np.ndarray  # (LANES, V, 3) wing origins, m NED
    euler: np.ndarray  # (LANES, V, 3) rad
    speed: np.ndarray  # (LANES, V) airspeed relative to the ambient air, m/s
    alpha: np.ndarray  # (LANES, V) rad
    beta: np.ndarray  # (LANES, V) rad
    gamma: np.ndarray  # (LANES, N) circulation, m^2/s
    vpts: np.ndarray  # (LANES, N, 3) the other vehicles' induced velocity at the evaluation points, m/s NED
    wind_ned: np.ndarray  # (LANES, V, 3) effective wind, m/s NED
    wind_b: np.ndarray  # (LANES, V, 3) m/s body
    omega_b: np.ndarray  # (LANES, V, 3) rotational wind, rad/s body
    omega_ned: np.ndarray  # (LANES, V, 3) rad/s NED
    keep: np.ndarray  # (LANES, N, N + 1) the AIC and right-hand side before elimination (benefit on), else (0, N, N + 1)
    no_keep: np.ndarray  # (0, N, N + 1): the substeps whose AIC nothing reads
    no_keep_one: np.ndarray  # (0, N + 1): the same for one lane
    drag_formation: np.ndarray  # (LANES, V) induced drag in formation, N (benefit on, chunked)
    drag_alone: np.ndarray  # (LANES, V) induced drag alone, N


@_jit
def ell_chunk(p, s, chunked):
    """A view (:func:`formation_env.sim.views.struct_view`) of an :class:`EllChunk` for the formations of ``s`` and
    the wake of ``p``; ``chunked``: with a chunk scratch for the joint solve (else an empty one: the lanes are
    solved one by one)."""
    nv = s.aircraft.shape[1]
    lat = p.wake.lattice
    n = lat.panel_vehicle.shape[0]
    lanes = LANES if chunked else 0
    n_kept = LANES if p.benefit_on else 0
    return struct_view(EllChunk(
        c=chunk_scratch(nv, lat.knot_x1_b.shape[0], lat.surface_origin_b.shape[0], n, sheet_on(p.wake.sheet), lanes),
        act=np.zeros(LANES, np.int64), pos=np.zeros((LANES, nv, 3)), euler=np.zeros((LANES, nv, 3)),
        speed=np.ones((LANES, nv)), alpha=np.zeros((LANES, nv)), beta=np.zeros((LANES, nv)),
        gamma=np.empty((LANES, n)), vpts=np.empty((LANES, n, 3)), wind_ned=np.empty((LANES, nv, 3)),
        wind_b=np.empty((LANES, nv, 3)), omega_b=np.empty((LANES, nv, 3)), omega_ned=np.empty((LANES, nv, 3)),
        keep=np.empty((n_kept, n, n + 1)), no_keep=np.empty((0, n, n + 1)), no_keep_one=np.empty((0, n + 1)),
        drag_formation=np.zeros((LANES, nv)), drag_alone=np.zeros((LANES, nv))))


@_jit_inline
def physics_before_wake(p, s, b, last_substep, sc, ell, l):
    """The first part of one dt of formation b (lane l of the chunk ``ell``): the pre-step state kept in
    ``sc.pre_state``; on the ``last_substep`` with the benefit on, the ELL poses kept in ``sc``; what the step does
    with the wake into ``ell.act[l]`` (:func:`formation_env.sim.kernels.wake_action`) and, for a solve, the
    formation's ELL inputs into lane l. Returns whether the formation solves."""
    if p.benefit_on and last_substep and s.step[b] % p.wake_update_every == 0:
        ell_inputs(s.aircraft[b], sc.ambient, p.wake.wing_origin_body, sc.ell_pos, sc.ell_euler, sc.ell_speed,
                   sc.ell_alpha, sc.ell_beta)
    sc.pre_state[:, :] = s.aircraft[b]
    # turbulence is in the ambient wind (NED), so the body-axis turbulence input is zero; its rotational
    # gusts are added to the ELL's induced rotational wind (body axes) by integrate_one
    update = s.step[b] % p.wake_update_every == 0
    act = wake_action(s.aircraft[b], sc.ambient, sc.zero_turb, s.induced_wind_ned[b], s.induced_omega_body[b], update,
                      p.wake_on, p.aircraft)
    ell.act[l] = act
    if act == WAKE_SOLVE:
        ell_inputs(s.aircraft[b], sc.ambient, p.wake.wing_origin_body, ell.pos[l], ell.euler[l], ell.speed[l],
                   ell.alpha[l], ell.beta[l])
    return act == WAKE_SOLVE


@_jit_inline
def solve_chunk(p, ell, nl, last_substep, chunked):
    """The ELL of the chunk's lanes 0..nl-1 that solve (``ell.act``): ``chunked``, all LANES lanes at once
    (:mod:`formation_env.wake.across`; a lane that does not solve flies the inputs of the first that does, computed,
    never read), else lane by lane (:func:`formation_env.wake.arrays.evaluate_formation`); nothing when none
    solves. On the ``last_substep`` with the benefit on, each lane's AIC and right-hand side are kept in
    ``ell.keep``."""
    first = -1
    for l in range(nl):
        if ell.act[l] == WAKE_SOLVE:
            first = l
            break
    if first < 0:
        return
    keep = ell.keep if last_substep else ell.no_keep
    if not chunked:
        for l in range(nl):
            if ell.act[l] == WAKE_SOLVE:
                kept = ell.no_keep_one
                if keep.shape[0] > 0:
                    kept = keep[l]
                evaluate_formation(p.wake, ell.pos[l], ell.euler[l], ell.speed[l], ell.alpha[l], ell.beta[l],
                                   ell.gamma[l], ell.vpts[l], ell.wind_ned[l], ell.wind_b[l], ell.omega_b[l],
                                   ell.omega_ned[l], kept)
        return
    for l in range(LANES):
        if l >= nl or ell.act[l] != WAKE_SOLVE:
            ell.pos[l] = ell.pos[first]
            ell.euler[l] = ell.euler[first]
            ell.speed[l] = ell.speed[first]
            ell.alpha[l] = ell.alpha[first]
            ell.beta[l] = ell.beta[first]
    lat = p.wake.lattice
    solve_chunk_lanes(lat, p.wake.sheet, ell.pos, ell.euler, ell.speed, ell.alpha, ell.beta, 0, LANES, ell.c,
                      ell.gamma, keep)
    field_chunk(lat, ell.pos, 0, LANES, ell.c, ell.vpts, ell.wind_ned, ell.wind_b, ell.omega_b, ell.omega_ned)


@_jit_inline
def physics_after_wake(p, s, b, last_substep, sc, ell, l):
    """The rest of one dt of formation b (lane l): the chunk's solve taken over (circulation and effective wind),
    coupled (``p.coupling``: :func:`formation_env.wake.coupling.couple_solved`) and checked finite, or the wake
    cleared; RK4 and the envelope (:func:`formation_env.sim.kernels.integrate_one`); the new state, command and
    status into ``s``, the status bits accumulated in ``sc.status_any``. On the ``last_substep`` with the benefit on
    the solve's AIC is kept in ``sc``; returns whether that substep's ELL solve is there to read the formation
    benefit off. Together with :func:`physics_before_wake` and :func:`solve_chunk`, the operations of
    :func:`formation_env.sim.kernels.step_one`, bit for bit."""
    act = ell.act[l]
    gamma, held_wind, held_omega = s.circulation[b], s.induced_wind_ned[b], s.induced_omega_body[b]
    if act == WAKE_SOLVE:
        for k in range(gamma.shape[0]):
            gamma[k] = ell.gamma[l, k]
        for a in range(held_wind.shape[0]):
            for i in range(3):
                held_wind[a, i] = ell.wind_ned[l, a, i]
                held_omega[a, i] = ell.omega_b[l, a, i]
        couple_solved(p.wake, p.coupling, ell.pos[l], ell.euler[l], gamma, ell.vpts[l], held_wind, ell.wind_b[l],
                      held_omega, ell.omega_ned[l])
        clear_if_not_finite(held_wind, held_omega, gamma)
    elif act == WAKE_CLEAR:
        clear_wake(held_wind, held_omega, gamma)
    solved = False
    if p.benefit_on and last_substep and act == WAKE_SOLVE:
        sc.aic_keep[:, :] = ell.keep[l]
        # solved unless the solve came out non-finite (gamma zeroed)
        for k in range(gamma.shape[0]):
            if gamma[k] != 0.0:
                solved = True
                break
    integrate_one(s.aircraft[b], sc.command, sc.ambient, sc.zero_turb, s.gust_omega_body[b], held_wind, held_omega,
                  p.aircraft, p.dt_s, sc.new_state, sc.status)
    s.aircraft[b] = sc.new_state
    s.command[b] = sc.command
    status, status_any = sc.status, sc.status_any
    for a in range(status.shape[0]):
        s.status[b, a] = status[a]
        status_any[a] |= status[a]
    return solved


@_jit_inline
def drags_chunk(p, s, b0, nl, solved_last, ell):
    """After the last substep of a chunk solved across lanes with the benefit on: the induced drags in formation and
    alone of the lanes whose last substep's solve the benefit reads (``solved_last`` (nl,)) into
    ``ell.drag_formation`` and ``ell.drag_alone``, all lanes at once
    (:func:`formation_env.wake.across_loads.induced_drags_chunk`, off the chunk's poses and kept AIC, each
    formation's circulation as coupled: ``s.circulation``); the other lanes' are computed, never read. Bit for bit
    :func:`formation_env.wake.benefit.induced_drags_one` of each formation, as :func:`.stages.formation_saving` takes
    it otherwise."""
    any_solved = False
    for l in range(nl):
        if solved_last[l]:
            any_solved = True
            for k in range(ell.gamma.shape[1]):
                ell.gamma[l, k] = s.circulation[b0 + l, k]
    if not any_solved:
        return
    induced_drags_chunk(p.wake, p.wake_alone.lattice.panel_vehicle.shape[0], ell.c, ell.speed, ell.alpha, ell.beta,
                        ell.gamma, ell.keep, AIR_DENSITY_SL, ell.drag_formation, ell.drag_alone)
