"""Run a compiled kernel over a batch on threads: the calling thread plus a pool of workers taking chunks of the
batch from a shared counter. The kernels release the GIL (``nogil=True``).

Why threads calling a serial kernel rather than numba's ``prange``: each call unboxes its own arrays, so every
reference count a thread's kernel takes and releases (an array slice per formation) is on memory of its own, where
inside one ``prange`` kernel all threads count on the same arrays and contend for them (a batched ELL of 1,024
formations ran no faster with two threads than with one); and a thread on a busy core simply takes fewer chunks.
"""

from __future__ import annotations

import itertools
from concurrent.futures import ThreadPoolExecutor

import numba as nb

__all__ = ["threads", "run_parallel"]

_POOL: ThreadPoolExecutor | None = None
_POOL_SIZE = 0


def threads() -> int:
    """The threads a batch may use: numba's thread count (``NUMBA_NUM_THREADS``), at least 1."""
    return max(1, int(nb.get_num_threads()))


def run_parallel(kernel, n: int, args: tuple | list, n_threads: int, granule: int = 1) -> None:
    """``kernel(*args, start, stop)`` over 0..n in chunks, on the calling thread plus ``n_threads - 1``
    pool workers taking chunks (about four per thread) from a shared counter. ``args``: one tuple for every
    thread, or a list of at least ``n_threads`` tuples, thread i taking ``args[i]`` (the calling thread 0).
    ``granule``: chunks are whole multiples of it once the batch has two such a thread (a kernel that works on
    ``granule`` items at once)."""
    global _POOL, _POOL_SIZE
    if _POOL is None or _POOL_SIZE != n_threads - 1:
        if _POOL is not None:
            _POOL.shutdown(wait=False)
        _POOL, _POOL_SIZE = ThreadPoolExecutor(n_threads - 1, thread_name_prefix="formation-step"), n_threads - 1
    chunk = max(1, -(-n // (4 * n_threads)))
    if granule > 1 and n >= 2 * granule * n_threads:
        chunk = -(-chunk // granule) * granule
    n_chunks = -(-n // chunk)
    counter = itertools.count()  # next() is atomic under the GIL

    def work(i):
        a = args[i] if isinstance(args, list) else args
        while True:
            c = next(counter)
            if c >= n_chunks:
                return
            kernel(*a, c * chunk, min((c + 1) * chunk, n))

    futures = [_POOL.submit(work, i) for i in range(1, n_threads)]
    work(0)
    for f in futures:
        f.result()
