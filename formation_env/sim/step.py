"""One compiled, batched decision step: ``step(params, state, actions) -> StepOutput``.

Per formation (B formations over a thread pool, in chunks of up to :data:`formation_env.wake.across.LANES`) and
per physics substep, in this order (thesis chapter 6's loop, the Simulink model's order):

1. guidance: vehicle 0's reference path and the followers' slot demands (:mod:`.guidance`);
2. ambient wind: scenario gusts + steady wind + the turbulence at each UAV (sampled at its
   position at the end of the previous substep);
3. control: the thesis PID (:func:`formation_env.control.law.fcs_update`) for every UAV it flies,
   with the agents' actions mapped per mode: ``setpoints`` moves the PID's demands, ``residual`` adds
   to its command, ``surfaces`` replaces it;
4. ELL effective wind every ``wake_update_every``-th substep (Eqs. 4.4-4.7), Aerosonde RK4 and
   the envelope (:func:`formation_env.sim.kernels.step_one`'s stages). A chunk of at least :data:`CHUNK_MIN`
   formations of a small lattice (:func:`formation_env.wake.across.chunk_pays`) solves its ELL at once, the
   formations as the vector lanes (:mod:`formation_env.wake.across`); fewer formations (a single env, a
   batch's remainder) and larger lattices solve one formation at a time. Either way every formation's numbers
   are those of its own solve, bit for bit;
5. turbulence field advanced one step and sampled at the new positions;
6. the manoeuvring reference path integrated, the step's separation checked (collision, envelope).

:func:`decide_chunk` is that chain; the stages are named functions in :mod:`.stages`, sharing one
:class:`~formation_env.sim.stages.DecisionScratch` per decision.

With the benefit on, the induced-drag saving of the decision is read off the last substep's ELL
solve (the poses and circulation the physics used), so it costs only the Kutta-Joukowski loads and
each UAV's isolated solve, not another joint solve.

A formation stops its substeps as soon as a UAV leaves the envelope (its episode ends). Then the
demands at the new state, the observation, the formation benefit and the reward are formed
(:mod:`.observe`). The state is updated in place and nothing else is kept between calls
(:func:`formation_env.sim.state.copy_state` gives functional semantics when needed).

The kernels release the GIL; how Python calls them (serial or on a thread pool, resolved entry points,
packed structs) is :mod:`.dispatch`.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from .dispatch import PARALLEL_MIN_BATCH, EntryPoints, run_chunks
from .params import TURBULENCE_OFF, StepParams
from ..wake.across import LANES, chunk_pays
from .kernels import WAKE_HOLD
from .physics import drags_chunk, ell_chunk, physics_after_wake, physics_before_wake, solve_chunk
from .stages import (advance_turbulence, ambient_wind, control, crash_and_slot_error, decision_over, decision_scratch,
                     demands, episode_flags, field_scratch, formation_benefit, formation_saving,
                     integrate_reference, nearest_separations, observe_one, reward_output, sample_turbulence,
                     slot_frame_angle, step_separation_check)
from .stages import setpoint_shift as _setpoint_shift  # noqa: F401  (tests/envs reads it here)
from .state import SimState, StepOutput
from .views import struct_view

__all__ = ["step", "refresh", "observe", "PARALLEL_MIN_BATCH", "decide_chunk", "refresh_formation", "formation_benefit",
           "observe_one", "ENTRY_POINTS"]


# decide_chunk and refresh_formation are inlined into the kernels below at numba IR level: numba links and
# re-optimises everything a compiled function calls, so each compiled level above the decision (a function per
# formation, a loop over formations, an entry on packed structs) compiled the whole decision again; one compiled
# function per entry point compiles it once.
_jit_inline = nb.njit(cache=True, error_model="numpy", inline="always")


@_jit_inline
def refresh_formation(p, s, b):
    """Demands and turbulence of formation b at its current state and time (after a reset)."""
    nv = s.aircraft.shape[1]
    demands(p.scenario, s, b, s.step[b] * p.dt_s, np.empty((nv, 3)))
    if p.turbulence != TURBULENCE_OFF:
        sample_turbulence(p.turbulence, p.field, s, b, struct_view(field_scratch(nv)), s.step[b] * p.dt_s)


#: the fewest formations a chunk solves at once (:func:`decide_chunk`): a chunk's solve costs the same for any
#: number of formations up to LANES, and per lane about half of one formation's own solve, so from just over half
#: the lanes filled on the chunk is the cheaper
CHUNK_MIN = LANES // 2 + 1


@_jit_inline
def decide_chunk(p, s, b0, nl, actions, o, ell):
    """One decision of formations b0..b0+nl-1 (nl <= LANES) with ``actions`` (B, V, 4): each formation's substeps,
    their physics steps a chunk at a time (:mod:`formation_env.sim.physics`; ``ell`` an
    :class:`~formation_env.sim.physics.EllChunk`): where nl >= :data:`CHUNK_MIN` and ``ell`` has a chunk scratch
    the ELL of the chunk's formations solved together, else each formation's on its own; then each formation's
    observation, reward and events into ``o`` (the stages: :mod:`formation_env.sim.stages`). Every formation's
    numbers are those of its own decision alone, either way: the chunk shares the solve's instructions, not its
    values.

    Collision: the smallest CG separation over the decision's physics steps below the collision
    separation (a step that also made a state non-finite is judged from its pre-step positions and
    velocities, :func:`formation_env.sim.kernels.step_separation`). A UAV whose state went non-finite
    is measured (slot error, separation) at its last finite position, so ``o`` never carries NaN."""
    chunked = nl >= CHUNK_MIN and ell.c.piv.shape[0] > 0
    scs = [decision_scratch(s, b0 + l, p.benefit_on) for l in range(nl)]
    min_sep = np.full(nl, np.inf)
    flying = np.ones(nl, np.bool_)  # the formation's substeps go on (none of its UAVs left the envelope or collided)
    # formation benefit: read off the last substep's ELL solve (its poses and circulation), which
    # the physics needs anyway; a fresh solve only when that substep had none
    solved_last = np.zeros(nl, np.bool_)
    for sub in range(p.substeps):
        last = sub == p.substeps - 1
        for l in range(nl):
            ell.act[l] = WAKE_HOLD
            if flying[l]:
                b, sc = b0 + l, scs[l]
                t = s.step[b] * p.dt_s
                demands(p.scenario, s, b, t, sc.velocity)
                ambient_wind(p.scenario, s, b, t, sc.ambient, sc.gust3)
                control(p, s, b, actions[b], sc)
                physics_before_wake(p, s, b, last, sc, ell, l)
        solve_chunk(p, ell, nl, last, chunked)
        for l in range(nl):
            if flying[l]:
                b, sc = b0 + l, scs[l]
                t = s.step[b] * p.dt_s
                solved_last[l] = physics_after_wake(p, s, b, last, sc, ell, l)
                advance_turbulence(p.turbulence, p.field, s, b, sc.field)
                integrate_reference(p.scenario, p.dt_s, s, b, t, sc.pd3, sc.vd3)
                s.step[b] += 1
                d = step_separation_check(p.dt_s, s, b, sc)
                if d < min_sep[l]:
                    min_sep[l] = d
                if decision_over(p.reward.collision_separation_m, sc.status_any, d):
                    flying[l] = False
    if chunked and p.benefit_on:
        drags_chunk(p, s, b0, nl, solved_last, ell)
    for l in range(nl):
        b, sc = b0 + l, scs[l]
        # the demands at the new state: what the observation and the reward measure against
        demands(p.scenario, s, b, s.step[b] * p.dt_s, sc.velocity)
        chi_slot = slot_frame_angle(p.scenario, s, b, sc.velocity)
        crashed_any = crash_and_slot_error(p.reward.slot_error_axes, s, b, chi_slot, sc, o)
        nearest_separations(s.aircraft[b], sc.last_pos, sc.known, o.separation_m[b])
        collided = episode_flags(p.reward.collision_separation_m, p.episode_steps, s, b, min_sep[l], crashed_any, o)
        formation_saving(p, s, b, crashed_any, solved_last[l], chunked, ell.drag_formation[l], ell.drag_alone[l], sc,
                         o)
        remaining = max(p.episode_steps - s.step[b], 0) / p.substeps
        reward_output(p.reward, remaining, s, b, actions[b], chi_slot, collided, o)
        s.episode_decisions[b] += 1
        observe_one(p, s, b, o.observation[b])


@nb.njit(cache=True, nogil=True, error_model="numpy")
def decide_packed(ps, actions, start, stop):
    """:func:`decide_chunk` for formations start..stop-1, LANES at a time, the (params, state, out) structs packed in
    ``ps`` (a :class:`~formation_env.sim.dispatch.StepStructs`); releases the GIL (threads run chunks)."""
    p, s, o = ps.p, ps.s, ps.o
    ell = ell_chunk(p, s, stop - start >= CHUNK_MIN and chunk_pays(p.wake.lattice))
    b0 = start
    while b0 < stop:
        nl = min(LANES, stop - b0)
        decide_chunk(p, s, b0, nl, actions, o, ell)
        b0 += nl


@nb.njit(cache=True, nogil=True, error_model="numpy")
def refresh_packed(ps, indices, start, stop):
    """:func:`refresh_formation` and :func:`observe_one` for formations indices[start:stop] (structs as
    :func:`decide_packed`'s)."""
    p, s, o = ps.p, ps.s, ps.o
    for q in range(start, stop):
        b = indices[q]
        refresh_formation(p, s, b)
        observe_one(p, s, b, o.observation[b])


#: the packed structs and resolved entry points per Simulation (formation_env.sim.dispatch.EntryPoints)
ENTRY_POINTS = EntryPoints()


def step(params: StepParams, state: SimState, actions: np.ndarray, out: StepOutput) -> StepOutput:
    """Advance every formation by one decision with ``actions`` (B, V, 4) in [-1, 1] (rows of
    PID-flown vehicles are ignored); results into ``out`` (returned). Inputs are not checked here:
    the env adapters validate once per decision."""
    if not (isinstance(actions, np.ndarray) and actions.dtype == np.float64 and actions.ndim == 3
            and actions.flags.c_contiguous and actions.flags.aligned and actions.flags.writeable):
        actions = np.array(actions, dtype=np.float64, order="C")  # the one type the kernel is compiled for (read only)
    n = actions.shape[0]
    kernel, args = ENTRY_POINTS.get(decide_packed, params, state, out, (actions,), n)
    run_chunks(kernel, n, args)
    return out


def refresh(params: StepParams, state: SimState, indices: np.ndarray, out: StepOutput) -> None:
    """After resetting formations ``indices``: their demands, turbulence sample and observation."""
    n = indices.shape[0]
    kernel, args = ENTRY_POINTS.get(refresh_packed, params, state, out, (np.array(indices, dtype=np.int64),), n)
    run_chunks(kernel, n, args)


def observe(params: StepParams, state: SimState, out: StepOutput) -> np.ndarray:
    """Recompute every formation's observation at its current state into ``out.observation``."""
    refresh(params, state, np.arange(state.step.shape[0]), out)
    return out.observation
