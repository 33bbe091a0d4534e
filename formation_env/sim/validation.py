"""The engine's boundary: every check of what a caller hands :class:`~formation_env.sim.Simulation` and the env
adapters (actions, seeds, formation indices, batch sizes, nested option dicts), in one place.

Each check returns the value in the form the engine uses, or raises one clear error naming the value and what
is allowed: ``ValueError`` for a bad value, ``TypeError`` for an unknown option name (as Python does for an
unexpected keyword). Nothing here is compiled, and no compiled module imports it (editing it recompiles nothing).

Actions: real numbers (float or integer dtypes; ``bool``, complex, strings and other objects refused), finite
(NaN or inf is a ``ValueError`` naming the formation, env index or agent) and of the exact shape asked for;
values outside [-1, 1] are clipped to it, the action space's documented rule (the Box is [-1, 1]). Seeds: None or
integers in [0, :data:`MAX_SEED`] (numpy's int64 range, which every generator of the package accepts). A batch
is bounded by the memory its state needs (:func:`check_batch_size`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import fields

import numpy as np

__all__ = ["MAX_SEED", "batch_arrays", "MEMORY_FRACTION", "check_actions", "check_action", "clipped_values", "check_seed",
           "check_seeds", "check_indices", "check_count", "check_batch_size", "physical_memory_bytes",
           "nested_options", "format_bytes"]

#: largest seed accepted anywhere (numpy's int64 maximum; seeds are non-negative)
MAX_SEED = 2**63 - 1

#: the share of the machine's physical memory one Simulation's arrays may take (the rest: the learner, the OS)
MEMORY_FRACTION = 0.5


# ---------------------------------------------------------------------------------------------- actions
def _describe(raw: np.ndarray) -> str:
    return f"an array of dtype {raw.dtype} and shape {raw.shape}"


def _as_array(values, what: str, expected: str) -> np.ndarray:
    try:
        return np.asarray(values)
    except (TypeError, ValueError):  # ragged nested lists, objects numpy cannot hold
        raise ValueError(f"{what} must be real numbers in [-1, 1] of shape {expected}, got {values!r:.200}") from None


def _holds_bool(values) -> bool:
    """A (nested) list or tuple with a bool among its numbers (numpy would read True as 1)."""
    if isinstance(values, (list, tuple)):
        return any(isinstance(x, (bool, np.bool_)) or _holds_bool(x) for x in values)
    return False


def _real(raw: np.ndarray, what: str, expected: str, rows: str, given=None) -> np.ndarray:
    """``raw`` (numpy's array of ``given``) as float64, or the error saying why it is not real numbers (bool,
    complex, strings, objects)."""
    kind = raw.dtype.kind
    if kind in "iuf" and _holds_bool(given):
        raise ValueError(f"{what} hold booleans; actions must be real numbers in [-1, 1] of shape {expected}")
    if kind == "b":
        raise ValueError(f"{what} are boolean; actions must be real numbers in [-1, 1] of shape {expected}")
    if kind == "c":
        bad = []
        if raw.ndim:
            bad = np.nonzero(np.any(np.imag(raw).reshape(len(raw), -1) != 0, axis=1))[0].tolist()
        raise ValueError(f"{what} are complex ({raw.dtype}; {rows}(s) with an imaginary part: {bad}); actions must be "
                         "real numbers in [-1, 1]")
    if kind == "O":
        flat = raw.reshape(-1)
        if any(isinstance(x, (bool, np.bool_)) for x in flat):
            raise ValueError(f"{what} hold booleans; actions must be real numbers in [-1, 1] of shape {expected}")
        if not all(isinstance(x, (int, float, np.integer, np.floating)) for x in flat):
            raise ValueError(f"{what} must be real numbers in [-1, 1] of shape {expected}, got {_describe(raw)} "
                             f"holding {sorted({type(x).__name__ for x in flat})}")
    elif kind not in "fiu":  # strings, bytes, datetimes, structured records
        raise ValueError(f"{what} must be real numbers in [-1, 1] of shape {expected}, got {_describe(raw)}")
    return np.asarray(raw, dtype=float)


def check_actions(actions, shape: tuple[int, ...], *, what: str = "actions", rows: str = "formation") -> np.ndarray:
    """``actions`` as real numbers of exactly ``shape``, finite, clipped to [-1, 1] (the action space's rule).

    The common case (a float array of that shape already in [-1, 1]) is returned as it is, after one min and one
    max (a NaN fails both comparisons, so it takes the general path and is reported). ``rows``: what the first
    axis indexes, for the error naming the rows with NaN or inf ("formation", "env index")."""
    shape = tuple(int(n) for n in shape)
    if type(actions) is np.ndarray and actions.dtype.kind == "f" and actions.shape == shape and actions.size:
        if actions.min() >= -1.0 and actions.max() <= 1.0:
            return actions
    expected = str(shape)
    a = _real(_as_array(actions, what, expected), what, expected, rows, actions)
    if a.shape != shape:
        raise ValueError(f"{what} must have shape {shape}, got {a.shape}")
    finite = np.isfinite(a)
    if not finite.all():
        bad = np.nonzero(~finite.reshape(len(a), -1).all(axis=1))[0].tolist() if a.ndim else []
        raise ValueError(f"{what} of {rows}(s) {bad} contain NaN or inf")
    return np.clip(a, -1.0, 1.0)


def clipped_values(action) -> list | None:
    """One agent's action in the common case (a float array of 4 finite values) without the general path's numpy
    calls: the same float64 values (tolist gives a float16/32 entry's exact value) clipped the same way, as a list;
    None for anything else (:func:`check_action` decides)."""
    if type(action) is np.ndarray and action.dtype.kind == "f" and action.shape == (4,):
        vals = action.tolist()
        if all(map(math.isfinite, vals)):
            return [min(max(v, -1.0), 1.0) for v in vals]
    return None


def check_action(agent: str, action) -> np.ndarray:
    """One agent's action as 4 finite floats clipped to [-1, 1]; anything else (bool, complex, strings,
    NaN/inf, another shape) is a ``ValueError`` naming ``agent``."""
    vals = clipped_values(action)
    if vals is not None:
        return np.array(vals)
    what = f"action of {agent!r}"
    try:
        raw = np.asarray(action)
        a = _real(raw, what, "(4,)", "row", action)
    except ValueError as exc:
        if "boolean" in str(exc) or "booleans" in str(exc):
            raise ValueError(f"{what} is boolean; actions must be 4 real numbers in [-1, 1], got {action!r}") from None
        if "complex" in str(exc):
            raise ValueError(f"{what} is complex ({raw.dtype}); actions must be real numbers in [-1, 1]") from None
        raise ValueError(f"{what} must be 4 real numbers, got {action!r:.200}") from None
    if a.shape != (4,):
        raise ValueError(f"{what} must have shape (4,), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{what} contains NaN or inf: {a.tolist()}")
    return np.clip(a, -1.0, 1.0)  # the Box is [-1, 1]; out-of-range values saturate


# ---------------------------------------------------------------------------------------------- seeds, indices
def check_seed(seed, name: str = "seed", *, allow_none: bool = True, top: int = MAX_SEED) -> int | None:
    """``seed`` as an int in [0, ``top``] (None passes when ``allow_none``); bool, floats and strings refused."""
    if seed is None and allow_none:
        return None
    allowed = f"an integer in [0, {top}]" + (" or None" if allow_none else "")
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)):
        raise ValueError(f"{name} must be {allowed}, got {seed!r} ({type(seed).__name__})")
    if not 0 <= int(seed) <= top:
        raise ValueError(f"{name} must be {allowed}, got {seed!r}")
    return int(seed)


def check_seeds(seeds, n: int, name: str = "seeds") -> list[int | None]:
    """``seeds`` (None: n Nones) as a list of n seeds, each None or an int in [0, MAX_SEED]."""
    if seeds is None:
        return [None] * n
    if isinstance(seeds, (str, bytes, Mapping)) or not hasattr(seeds, "__len__"):
        raise ValueError(f"{name} must be a sequence of {n} seed(s) (each None or an integer in [0, {MAX_SEED}]), "
                         f"got {seeds!r:.200}")
    out = [check_seed(s, f"{name}[{k}]") for k, s in enumerate(seeds)]
    if len(out) != n:
        raise ValueError(f"{len(out)} {name} for {n} formations")
    return out


def check_indices(indices, batch_size: int, name: str = "indices") -> np.ndarray:
    """``indices`` (None: all) as a 1-D int64 array of distinct formation indices in [0, batch_size - 1]."""
    if indices is None:
        return np.arange(batch_size)
    allowed = f"distinct integer formation indices in [0, {batch_size - 1}]"
    try:
        raw = np.atleast_1d(np.asarray(indices))
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be {allowed}, got {indices!r:.200}") from None
    if raw.size == 0:
        return np.zeros(0, dtype=np.int64)
    if raw.ndim != 1 or raw.dtype.kind not in "iu" and not (raw.dtype == object and all(
            isinstance(i, (int, np.integer)) and not isinstance(i, (bool, np.bool_)) for i in raw.reshape(-1))):
        raise ValueError(f"{name} must be {allowed}, got {indices!r:.200}")
    idx = raw.astype(np.int64) if raw.dtype != object else np.array([int(i) for i in raw], dtype=np.int64)
    bad = idx[(idx < 0) | (idx >= batch_size)]
    if bad.size or len(np.unique(idx)) != len(idx):
        raise ValueError(f"{name} must be {allowed}, got {raw.tolist()}")
    return idx


def check_count(value, name: str, low: int, high: int) -> int:
    """``value`` as an int in [low, high] (bool and floats refused)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
        raise ValueError(f"{name} must be an integer in [{low}, {high}], got {value!r}")
    return int(value)


# ---------------------------------------------------------------------------------------------- memory
def physical_memory_bytes() -> int:
    """The machine's physical memory (bytes); 16 GiB where the OS does not say."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return 16 * 2**30


def format_bytes(n: float) -> str:
    for unit, size in (("GiB", 2**30), ("MiB", 2**20), ("kB", 2**10)):
        if n >= size:
            return f"{n / size:.1f} {unit}"
    return f"{n:.0f} B"


def check_batch_size(batch_size, bytes_per_formation: int, *, what: str = "batch_size", scenario: str = "",
                     memory_bytes: int | None = None) -> int:
    """``batch_size`` as an int >= 1 whose arrays (``bytes_per_formation`` each) fit in :data:`MEMORY_FRACTION`
    of the machine's physical memory; beyond, a ``ValueError`` stating the memory it needs and the bound."""
    if isinstance(batch_size, (bool, np.bool_)) or not isinstance(batch_size, (int, np.integer)) or batch_size < 1:
        raise ValueError(f"{what} must be an integer >= 1, got {batch_size!r}")
    total = physical_memory_bytes() if memory_bytes is None else int(memory_bytes)
    per = max(int(bytes_per_formation), 1)
    bound = max(int(total * MEMORY_FRACTION) // per, 1)
    if batch_size > bound:
        of = f" of {scenario}" if scenario else ""
        raise ValueError(f"{what} {int(batch_size):,} needs {format_bytes(batch_size * per)} of simulation state "
                         f"({format_bytes(per)} a formation{of}); at most {bound:,} formations fit in "
                         f"{MEMORY_FRACTION:.0%} of this machine's {format_bytes(total)} memory")
    return int(batch_size)


# ---------------------------------------------------------------------------------------------- nested options
def nested_options(owner: str, name: str, cls, value):
    """``value`` as a ``cls`` (a frozen dataclass of options, e.g. ``RewardWeights``): an instance passes; a dict
    of its options builds one (an unknown key is a ``TypeError`` naming it and the valid ones; a bad value the
    class's own ``ValueError`` naming the option); anything else is a ``ValueError``. A dict is exactly
    ``cls(**dict)``: the options it leaves out take their defaults."""
    if isinstance(value, cls):
        return value
    valid = [f.name for f in fields(cls)]
    if isinstance(value, Mapping):
        unknown = sorted(repr(k) for k in value if k not in valid)
        if unknown:
            raise TypeError(f"{owner}: {name} has no option {unknown[0]}"
                            + (f" (nor {', '.join(unknown[1:])})" if len(unknown) > 1 else "")
                            + f"; {name} options ({cls.__name__}): {valid}")
        return cls(**value)
    raise ValueError(f"{owner}: {name} must be a {cls.__name__} or a dict of its options {valid}, "
                     f"got {type(value).__name__}")


def batch_arrays(state, output) -> list[np.ndarray]:
    """Every array of a Simulation's ``state`` and ``output`` with the batch axis first (the turbulence fields'
    too): what :func:`check_batch_size` sizes and what a frozen formation keeps."""
    out = []
    for x in (*state, *output):
        out.extend(x if isinstance(x, tuple) else (x,))
    return out
