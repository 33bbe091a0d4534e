"""How Python calls the compiled decision step: threads, the serial/threaded choice, resolved entry points and
packed structs. Nothing here computes physics; results never depend on any choice made here (formations are
independent, so serial, threaded, packed, direct and numba's own dispatcher give the same bits; tested).

* :func:`run_chunks` runs ``kernel(*args, start, stop)`` over formations 0..n-1, serially or on the calling
  thread plus ``numba.get_num_threads() - 1`` pool workers (``NUMBA_NUM_THREADS`` applies) taking chunks of
  formations (whole multiples of the ELL's lanes, :data:`formation_env.wake.across.LANES`, once a batch has two
  such chunks a thread) from a shared counter (:func:`formation_env.threads.run_parallel`). The kernels release
  the GIL. A queue rather than numba's ``prange``: ``prange`` cannot take the step's named structs of arrays, and
  its OpenMP barrier waits
  for the slowest thread, which collapsed under a busy core; with a queue, a thread on a busy core simply takes
  fewer chunks.
* :class:`ThreadTuner` chooses serial or threaded per (kernel, batch size) by measuring both, so a busy
  machine's small batches run serially and large ones threaded.
* :class:`EntryPoints` resolves numba's compiled entry point of the decision once per Simulation's (params,
  state, out) objects and, for serial calls, packs the three structs into one :class:`StepStructs` pointer:
  numba's dispatcher would otherwise look the types of the nested structs up and unbox their ~120 arrays on
  every call, a noticeable part of a single formation's decision.
"""

from __future__ import annotations

import math
import time

import numba as nb
import numpy as np
from numba.core import types as nbt
from numba.experimental import structref
from numba.extending import overload

from ..threads import run_parallel, threads
from ..wake.across import LANES
from .views import struct_view, view_type

__all__ = ["PARALLEL_MIN_BATCH", "threads", "run_parallel", "ThreadTuner", "run_chunks", "StepStructs",
           "pack_structs", "EntryPoints"]

PARALLEL_MIN_BATCH = 2  # a single formation runs serially (no thread start-up)

class ThreadTuner:
    """Serial or threaded, whichever is measured faster for this kernel and batch size.

    A thread that another process preempts holds its chunk until the scheduler returns, and the decision waits
    for it: on a busy machine small batches run faster serially, large ones threaded. Each (kernel, B) keeps a
    moving average of the wall time of both settings and uses the faster; the setting not in use is re-measured
    now and then, so throughput follows the machine's load. Such a call costs a whole kernel call in the slower
    setting (for a large batch on two cores a serial decision takes about twice a threaded one, and a fixed
    re-measurement every 32 calls made it the slowest decision of every window, issue 26), so re-measuring is
    rationed:

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

    def run(self, kernel, n: int, args: tuple | list) -> None:
        """``kernel(*args, start, stop)`` over 0..n-1 (``args`` as :func:`run_parallel`'s; serially: the first)."""
        serial_args = args[0] if isinstance(args, list) else args
        if n < PARALLEL_MIN_BATCH:
            kernel(*serial_args, 0, n)
            return
        n_threads = min(threads(), n)
        if n_threads <= 1:
            kernel(*serial_args, 0, n)
            return
        # [serial s, threaded s, calls, call of the next re-measurement, serial's re-measurement interval]
        st = self.stats.setdefault((kernel, n, n_threads), [math.inf, math.inf, 0, 0, self.EXPLORE])
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
            run_parallel(kernel, n, args, n_threads, granule=LANES)  # whole chunks of the decision's ELL lanes
        else:
            kernel(*serial_args, 0, n)
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


_TUNER = ThreadTuner()


def run_chunks(kernel, n: int, args: tuple | list) -> None:
    """``kernel(*args, start, stop)`` over formations 0..n-1, serially or threaded (the process's
    :class:`ThreadTuner`); ``args`` as :func:`run_parallel`'s."""
    _TUNER.run(kernel, n, args)


@structref.register
class StepStructsType(nbt.StructRef):
    """numba type of :class:`StepStructs`: one Simulation's (params, state, out) named tuples in one compiled
    object, fields ``p``, ``s``, ``o``, each a :class:`~formation_env.sim.views.StructView` of its named tuple."""

    def preprocess_fields(self, fields):
        return tuple((name, nbt.unliteral(typ)) for name, typ in fields)


class StepStructs(structref.StructRefProxy):
    """(params, state, out) packed once per Simulation (:func:`pack_structs`). Python passes one pointer a
    decision instead of numba unboxing the ~120 arrays of the three named tuples on every call. The packed
    arrays are the same buffers (numba's unboxed array keeps the NumPy array alive and writes into its memory),
    so what the step writes is what Python reads. Serial calls only: the packed arrays' reference counts are
    shared, and two threads taking array views on them contend (:class:`EntryPoints`)."""


structref.define_boxing(StepStructsType, StepStructs)


def _pack(p, s, o):  # typed by the overload below; only called from compiled code
    raise NotImplementedError


@overload(_pack)
def _pack_overload(p, s, o):
    typ = StepStructsType([("p", view_type(p)), ("s", view_type(s)), ("o", view_type(o))])

    def impl(p, s, o):
        r = structref.new(typ)
        r.p = struct_view(p)
        r.s = struct_view(s)
        r.o = struct_view(o)
        return r

    return impl


@nb.njit(cache=True)
def pack_structs(p, s, o):
    """:class:`StepStructs` holding views of ``p``, ``s``, ``o`` (their arrays shared, not copied)."""
    return _pack(p, s, o)


class EntryPoints:
    """Packed structs and resolved entry points of the decision kernels per Simulation: ``get`` returns
    ``(entry, args)`` for :func:`run_chunks`.

    A kernel here is a compiled ``kernel(structs, *extra, start, stop)`` over formations start..stop-1, with
    ``structs`` a :class:`StepStructs` (the Simulation's (params, state, out) named tuples). Python passes one
    pointer a call instead of numba unboxing the ~120 arrays of the three structs on every call, and the
    compiled entry point for the argument types is resolved once (numba's dispatcher would look the types of
    the nested structs up on every call, which is slow for them). Both costs matter for a single formation's
    decision.

    Each thread gets structs of its own (``pack_structs`` once per thread): the packed arrays' reference counts
    belong to their structs, and every array view the step takes per formation increments and decrements them;
    threads sharing one set of counts would contend on them.

    Keyed by the objects' ids and checked by identity (the cache holds them, so an id cannot be reused while its
    entry lives; the oldest of ``SIZE`` entries is dropped). ``extra`` is not part of the key (a caller may pass
    new arrays each call); the caller passes them in the one type the kernel is compiled for (a C-contiguous,
    aligned, writeable array). Any failure to resolve falls back to numba's dispatcher with the same structs:
    results never depend on it (tested bit for bit)."""

    SIZE = 8

    def __init__(self) -> None:
        self.cache: dict = {}

    def structs(self, params, state, out, count: int = 1) -> list:
        """At least ``count`` :class:`StepStructs` of (params, state, out), packed once and kept."""
        return self._hit(params, state, out, count)[0]

    def get(self, kernel, params, state, out, extra: tuple, n: int) -> tuple:
        """``(entry, args)``: ``entry(*args[i], start, stop)`` runs ``kernel`` for thread i (of as many as
        :func:`run_chunks` may use for ``n`` formations)."""
        n_threads = max(1, min(threads(), n))
        hit = self._hit(params, state, out, n_threads)
        packs, entries = hit[0], hit[4]
        entry = entries.get(kernel)
        if entry is None:
            entry = entries[kernel] = self._resolve(kernel, packs[0], extra)
        return entry, [(pk, *extra) for pk in packs[:n_threads]]

    def _hit(self, params, state, out, count: int) -> tuple:
        key = (id(params), id(state), id(out))
        hit = self.cache.get(key)
        if hit is None or hit[1] is not params or hit[2] is not state or hit[3] is not out:
            if len(self.cache) >= self.SIZE:
                self.cache.pop(next(iter(self.cache)))
            hit = self.cache[key] = ([], params, state, out, {})
        packs = hit[0]
        while len(packs) < count:
            packs.append(pack_structs(params, state, out))
        return hit

    @staticmethod
    def _resolve(kernel, packed, extra: tuple):
        try:
            kernel(packed, *extra, 0, 0)  # compiles or loads it (no formation stepped)
            sig = tuple(kernel.typeof_pyval(x) for x in (packed, *extra)) + (nb.types.int64,) * 2
            return kernel.overloads[sig].entry_point
        except Exception:  # noqa: BLE001 - an unexpected numba layout: the dispatcher serves
            return kernel
