"""Counter-based random numbers of the frozen turbulence field (see :mod:`.frozen_field`).

The 64-bit uniform of (formation key, filter-step counter, stream) is splitmix64 applied twice (the
key's splitmix sequence at counter + 1, then that value's sequence at stream + 1); two uniforms give
two normals by Box-Muller. Stream 6 j + m, m = 0..5, is lane j's m-th normal. The key of a formation
is ``SeedSequence(seed).generate_state(1, dtype=np.uint64)[0]`` (:func:`formation_key`).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["N_STREAMS_PER_LANE", "counter_bits", "counter_normal_pair", "formation_key", "reset_keys"]

_jit = nb.njit(cache=True, error_model="numpy")

N_STREAMS_PER_LANE = 6  # normals drawn per lane per filter step (5 used)

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_S11 = np.uint64(11)
_S27 = np.uint64(27)
_S30 = np.uint64(30)
_S31 = np.uint64(31)
_ONE_U64 = np.uint64(1)
_TWO_M53 = 2.0 ** -53
_TWO_PI = 2.0 * math.pi


def formation_key(seed: int) -> np.uint64:
    """The 64-bit key of a formation: SeedSequence(seed).generate_state(1, uint64)[0]."""
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or int(seed) < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    return np.random.SeedSequence(int(seed)).generate_state(1, dtype=np.uint64)[0]


def reset_keys(batch_size: int, indices, seeds) -> tuple[np.ndarray, np.ndarray]:
    """Checked reset arguments of a batched field: ``indices`` (1-D integers in [0, batch_size)) as int64
    and the :func:`formation_key` of each of ``seeds`` (one non-negative integer per index) as uint64."""
    idx = np.atleast_1d(np.asarray(indices))
    if idx.ndim != 1 or (idx.size and not np.issubdtype(idx.dtype, np.integer)):
        raise ValueError(f"indices must be a 1-D integer array, got {indices!r}")
    idx = idx.astype(np.int64)
    if idx.size and (idx.min() < 0 or idx.max() >= batch_size):
        raise ValueError(f"indices must lie in [0, {batch_size}), got {indices!r}")
    seed_list = [seeds] if np.isscalar(seeds) else list(seeds)
    if len(seed_list) != idx.size:
        raise ValueError(f"{len(seed_list)} seeds for {idx.size} indices")
    return idx, np.array([formation_key(s) for s in seed_list], dtype=np.uint64)

@_jit
def _mix64(z):
    """splitmix64 finaliser (uint64, wrap-around arithmetic)."""
    z = (z ^ (z >> _S30)) * _MIX1
    z = (z ^ (z >> _S27)) * _MIX2
    return z ^ (z >> _S31)


@_jit
def counter_bits(key, counter, stream):
    """64 random bits of (key, counter, stream), all uint64."""
    s = _mix64(key + (counter + _ONE_U64) * _GOLDEN)
    return _mix64(s + (stream + _ONE_U64) * _GOLDEN)


@_jit
def counter_normal_pair(key, counter, pair):
    """Two independent standard normals from streams 2 pair, 2 pair + 1 (Box-Muller)."""
    stream = np.uint64(2) * pair
    b1 = counter_bits(key, counter, stream)
    b2 = counter_bits(key, counter, stream + _ONE_U64)
    u1 = (np.float64(b1 >> _S11) + 1.0) * _TWO_M53  # (0, 1]
    u2 = np.float64(b2 >> _S11) * _TWO_M53  # [0, 1)
    rad = math.sqrt(-2.0 * math.log(u1))
    ang = _TWO_PI * u2
    return rad * math.cos(ang), rad * math.sin(ang)


@_jit
def _lane_normals(key, counter, lane, n):
    """The 6 normals of one lane at one filter step into n (6,)."""
    base = np.uint64(lane) * np.uint64(N_STREAMS_PER_LANE // 2)
    for p in range(N_STREAMS_PER_LANE // 2):
        a, b = counter_normal_pair(key, np.uint64(counter), base + np.uint64(p))
        n[2 * p] = a
        n[2 * p + 1] = b
