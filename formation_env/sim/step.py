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
5. turbulence field advanced one step and sampled at the new positions;
6. the manoeuvring reference path integrated, the step's separation checked (collision, envelope).

:func:`decide_one` is that chain; the stages are named functions in :mod:`.stages`, sharing one
:class:`~formation_env.sim.stages.DecisionScratch` per decision.

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
from numba.core import types as nbt
from numba.experimental import structref
from numba.extending import overload

from .params import StepParams
from .stages import (advance_turbulence, ambient_wind, control, crash_and_slot_error, decision_over, decision_scratch,
                     demands, episode_flags, field_scratch, formation_benefit, formation_saving, integrate_reference,
                     nearest_separations, observe_one, physics_and_events, reward_output, sample_turbulence,
                     slot_frame_angle, step_separation_check)
from .stages import setpoint_shift as _setpoint_shift  # noqa: F401  (tests/envs reads it here)
from .state import SimState, StepOutput

__all__ = ["step", "refresh", "observe", "PARALLEL_MIN_BATCH", "decide_one", "refresh_formation", "formation_benefit",
           "observe_one"]

PARALLEL_MIN_BATCH = 2  # a single formation runs serially (no thread start-up)


@nb.njit(cache=True, error_model="numpy")
def refresh_formation(p, s, b):
    """Demands and turbulence of formation b at its current state and time (after a reset)."""
    nv = s.aircraft.shape[1]
    demands(p.scenario, s, b, s.step[b] * p.dt_s, np.empty((nv, 3)))
    if p.turbulence != 0:
        sample_turbulence(p.turbulence, p.field, s, b, field_scratch(nv), s.step[b] * p.dt_s)


@nb.njit(cache=True, error_model="numpy")
def decide_one(p, s, b, actions, o):
    """One decision of formation b with ``actions`` (V, 4): substeps, then observation, reward and
    events into ``o`` (the stages: :mod:`formation_env.sim.stages`).

    Collision: the smallest CG separation over the decision's physics steps below the collision
    separation (a step that also made a state non-finite is judged from its pre-step positions and
    velocities, :func:`formation_env.sim.kernels.step_separation`). A UAV whose state went non-finite
    is measured (slot error, separation) at its last finite position, so ``o`` never carries NaN."""
    sc = decision_scratch(s, b, p.benefit_on)
    min_sep = np.inf
    # formation benefit: read off the last substep's ELL solve (its poses and circulation), which
    # the physics needs anyway; a fresh solve only when that substep had none
    solved_last = False
    for sub in range(p.substeps):
        t = s.step[b] * p.dt_s
        demands(p.scenario, s, b, t, sc.velocity)
        ambient_wind(p.scenario, s, b, t, sc.ambient, sc.gust3)
        control(p, s, b, actions, sc)
        solved_last = physics_and_events(p, s, b, sub == p.substeps - 1, sc)
        advance_turbulence(p.turbulence, p.field, s, b, sc.field)
        integrate_reference(p.scenario, p.dt_s, s, b, t, sc.pd3, sc.vd3)
        s.step[b] += 1
        d = step_separation_check(p.dt_s, s, b, sc)
        if d < min_sep:
            min_sep = d
        if decision_over(p.reward.collision_separation_m, sc.status_any, d):
            break
    # the demands at the new state: what the observation and the reward measure against
    demands(p.scenario, s, b, s.step[b] * p.dt_s, sc.velocity)
    chi_slot = slot_frame_angle(p.scenario, s, b, sc.velocity)
    crashed_any = crash_and_slot_error(p.reward.slot_error_axes, s, b, chi_slot, sc, o)
    nearest_separations(s.aircraft[b], sc.last_pos, sc.known, o.separation_m[b])
    collided = episode_flags(p.reward.collision_separation_m, p.episode_steps, s, b, min_sep, crashed_any, o)
    formation_saving(p, s, b, crashed_any, solved_last, sc, o)
    remaining = max(p.episode_steps - s.step[b], 0) / p.substeps
    reward_output(p.reward, remaining, s, b, actions, chi_slot, collided, o)
    s.episode_decisions[b] += 1
    observe_one(p, s, b, o.observation[b])


@nb.njit(cache=True, nogil=True, error_model="numpy")
def decide_range(p, s, actions, o, start, stop):
    """:func:`decide_one` for formations start..stop-1 (releases the GIL: threads run chunks)."""
    for b in range(start, stop):
        decide_one(p, s, b, actions[b], o)


@structref.register
class StepStructsType(nbt.StructRef):
    """numba type of :class:`StepStructs`: one Simulation's (params, state, out) named tuples in one compiled
    object, fields ``p``, ``s``, ``o``."""

    def preprocess_fields(self, fields):
        return tuple((name, nbt.unliteral(typ)) for name, typ in fields)


class StepStructs(structref.StructRefProxy):
    """(params, state, out) packed once per Simulation (:func:`pack_structs`). Python passes one pointer a
    decision instead of numba unboxing the ~120 arrays of the three named tuples (~10 us a call measured on the
    2-core machine: 5-7 % of a single env's decision). The packed arrays are the same buffers (numba's unboxed
    array keeps the NumPy array alive and writes into its memory), so what the step writes is what Python reads.
    Serial calls only: the packed arrays' reference counts are shared, and two threads taking array views on them
    contend (:class:`_EntryPoints`)."""


structref.define_boxing(StepStructsType, StepStructs)


def _pack(p, s, o):  # typed by the overload below; only called from compiled code
    raise NotImplementedError


@overload(_pack)
def _pack_overload(p, s, o):
    typ = StepStructsType([("p", p), ("s", s), ("o", o)])

    def impl(p, s, o):
        r = structref.new(typ)
        r.p = p
        r.s = s
        r.o = o
        return r

    return impl


@nb.njit(cache=True)
def pack_structs(p, s, o):
    """:class:`StepStructs` holding ``p``, ``s``, ``o`` (their arrays shared, not copied)."""
    return _pack(p, s, o)


@nb.njit(cache=True, nogil=True, error_model="numpy")
def decide_packed(ps, actions, start, stop):
    """:func:`decide_range` on packed structs: the same compiled step, called with one pointer."""
    decide_range(ps.p, ps.s, actions, ps.o, start, stop)


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
    threaded. Each (kernel, B) keeps a moving average of the wall time of both settings and uses the
    faster; the setting not in use is re-measured now and then, so throughput follows the machine's load.
    Such a call costs a whole kernel call in the slower setting (at B = 1,024 on the 2-core machine a serial
    decision takes twice a threaded one; with a fixed re-measurement every 32 calls, issue 26 measured it as
    the slowest decision of every window of 40, 2.0-2.3x the fastest), so re-measuring is rationed:

    * threaded in use: the serial setting only every ``EXPLORE_MAX`` calls. More load shows at once without
      it: the threads' own average rises above the serial one and the tuner switches;
    * serial in use: the threaded setting after ``EXPLORE`` calls, the interval doubling up to
      ``EXPLORE_MAX`` each time the re-measurement confirms serial (a machine that became idle shows only
      this way: the threaded average is stale).

    Results do not depend on the choice (formations are independent: bit-identical)."""

    EXPLORE = 32
    EXPLORE_MAX = 1024
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
        # [serial s, threaded s, calls, call of the next re-measurement, serial's re-measurement interval]
        st = self.stats.setdefault((kernel, n, threads), [math.inf, math.inf, 0, 0, self.EXPLORE])
        st[2] += 1
        calls = st[2]
        exploring = False
        if calls <= 5:  # warm-up: serial, threaded, serial, threaded (the first call may compile)
            use_threads = calls % 2 == 0
        else:
            use_threads = st[1] < st[0]
            if calls == st[3]:
                use_threads, exploring = not use_threads, True
        t0 = time.perf_counter()
        if use_threads:
            _run_parallel(kernel, n, args, threads)
        else:
            kernel(*args, 0, n)
        dt = time.perf_counter() - t0
        if calls > 1:
            k = 1 if use_threads else 0
            before = st[1] < st[0]
            st[k] = dt if st[k] == math.inf else (1.0 - self.ALPHA) * st[k] + self.ALPHA * dt
            after = st[1] < st[0]
            if calls >= 5 and (exploring or after != before or calls == 5):
                if not after:  # serial in use: back off while re-measurements confirm it
                    st[4] = min(2 * st[4], self.EXPLORE_MAX) if exploring and after == before else self.EXPLORE
                st[3] = calls + (self.EXPLORE_MAX if after else st[4])


_TUNER = _ThreadTuner()


def _run_chunks(kernel, n: int, args: tuple) -> None:
    _TUNER.run(kernel, n, args)


class _EntryPoints:
    """The decision's compiled call per (params, state, out) objects, resolved once: ``get`` returns
    ``(kernel, args)`` for ``kernel(*args, start, stop)``.

    numba's dispatcher finds the compiled version for the argument types on every call; for the step's
    nested structs of arrays that costs ~32 us a call (measured on the 2-core machine with no formation to
    step), and unboxing the ~120 arrays of the three named tuples another ~10 us: together ~20 % of a single
    env's decision. The structs are immutable named tuples of arrays and a Simulation passes the same objects
    every decision, so the entry point of :func:`decide_range` for their types is resolved once per set of
    objects (``typeof`` of each, ~2 ms) and called directly; for a serial call (``packed``) the structs are
    also packed once (:func:`pack_structs`) and :func:`decide_packed`'s entry point takes the one pointer
    (~2 us).

    Threads take the unpacked call: every thread's unboxing gives it its own reference counts for the arrays,
    while the packed structs' arrays have one count each, which every array view the step takes per formation
    increments and decrements; two threads doing so on the same counts slowed B = 1,024 by ~15 % (measured in
    one process, alternating: 63.7 against 55.9 ms a decision, serial calls equal).

    Keyed by the objects' ids and checked by identity (the cache holds them, so an id cannot be reused while its
    entry lives; the oldest of ``SIZE`` entries is dropped). ``actions`` is not part of the key (a caller may
    pass a new array each decision): only a C-contiguous, aligned, writeable float64 array of 3 dimensions, the
    type the entry points were resolved with, takes the fast paths; anything else goes through the dispatcher.
    Any failure to resolve falls back to the dispatcher: results never depend on it (tested bit for bit)."""

    SIZE = 8

    def __init__(self) -> None:
        self.cache: dict = {}

    def get(self, params, state, actions, out, packed: bool = True) -> tuple:
        a = actions
        if not (isinstance(a, np.ndarray) and a.dtype == np.float64 and a.ndim == 3 and a.flags.c_contiguous
                and a.flags.aligned and a.flags.writeable):
            return decide_range, (params, state, actions, out)
        key = (id(params), id(state), id(out))
        hit = self.cache.get(key)
        if hit is None or hit[3] is not params or hit[4] is not state or hit[5] is not out:
            hit = self._resolve(key, params, state, actions, out)
        if packed and hit[1] is not None:
            return hit[1], (hit[2], actions)
        return hit[0], (params, state, actions, out)

    def _resolve(self, key, params, state, actions, out) -> tuple:
        direct, packed_entry, packed = decide_range, None, None
        try:
            decide_range(params, state, actions, out, 0, 0)  # compiles or loads it (no formation stepped)
            sig = tuple(decide_range.typeof_pyval(x) for x in (params, state, actions, out)) + (nb.types.int64,) * 2
            direct = decide_range.overloads[sig].entry_point
            packed = pack_structs(params, state, out)
            decide_packed(packed, actions, 0, 0)
            sig = tuple(decide_packed.typeof_pyval(x) for x in (packed, actions)) + (nb.types.int64,) * 2
            packed_entry = decide_packed.overloads[sig].entry_point
        except Exception:  # noqa: BLE001 - an unexpected numba layout: the dispatcher (or the direct entry) serves
            packed_entry, packed = None, None
        if len(self.cache) >= self.SIZE:
            self.cache.pop(next(iter(self.cache)))
        hit = self.cache[key] = (direct, packed_entry, packed, params, state, out)
        return hit


_ENTRY = _EntryPoints()


def step(params: StepParams, state: SimState, actions: np.ndarray, out: StepOutput) -> StepOutput:
    """Advance every formation by one decision with ``actions`` (B, V, 4) in [-1, 1] (rows of
    PID-flown vehicles are ignored); results into ``out`` (returned). Inputs are not checked here:
    the env adapters validate once per decision."""
    n = actions.shape[0]
    serial = n < PARALLEL_MIN_BATCH or _threads() <= 1  # (the threaded path takes the unpacked call: _EntryPoints)
    kernel, args = _ENTRY.get(params, state, actions, out, packed=serial)
    _run_chunks(kernel, n, args)
    return out


def refresh(params: StepParams, state: SimState, indices: np.ndarray, out: StepOutput) -> None:
    """After resetting formations ``indices``: their demands, turbulence sample and observation."""
    _run_chunks(refresh_range, indices.shape[0], (params, state, np.ascontiguousarray(indices, dtype=np.int64),
                                                  out.observation))


def observe(params: StepParams, state: SimState, out: StepOutput) -> np.ndarray:
    """Recompute every formation's observation at its current state into ``out.observation``."""
    refresh(params, state, np.arange(state.step.shape[0]), out)
    return out.observation
