"""What the batched classical agents share: the gains check, the per-row integrators' reset, and the
observation decoding (the formation size from the observation length, its groups)."""

from __future__ import annotations

import math
from dataclasses import fields

import numpy as np

from formation_env.envs.observations import observation_size, to_dict

__all__ = ["check_gains", "RowIntegrators", "observation_groups"]


def check_gains(gains) -> None:
    """Every field of the gains dataclass ``gains`` a finite number >= 0 (never bool); a ValueError naming the
    first that is not (``<Class>.<field>``)."""
    for f in fields(gains):
        v = getattr(gains, f.name)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
            raise ValueError(f"{type(gains).__name__}.{f.name} must be a finite number >= 0, got {v!r}")


def observation_groups(obs, owner: str, neighbour_wind: bool = False,
                       neighbour_attitude: bool = False) -> tuple[np.ndarray, dict]:
    """``(obs as float (N, D), its groups)`` for any formation size (the observation length fixes V); a
    ValueError naming ``owner`` for another shape or a length no formation has. ``neighbour_wind``: the observation
    ends with the neighbours' winds (EnvConfig.neighbour_wind), 9 values per observed neighbour instead of 6; the
    length alone cannot say so (47 + 6 x 3 = 47 + 9 x 2), so the agent must be told; ``neighbour_attitude``
    (EnvConfig.neighbour_attitude) 3 more per neighbour."""
    obs = np.asarray(obs, dtype=float)
    if obs.ndim != 2:
        raise ValueError(f"{owner}.act: obs must have shape (N, D), got {obs.shape}")
    if neighbour_wind or neighbour_attitude:
        base = observation_size(1)  # no neighbour
        per = 6 + 3 * bool(neighbour_wind) + 3 * bool(neighbour_attitude)
        k, rem = divmod(obs.shape[1] - base, per)
        if rem or k < 1:
            what = " and ".join(n for n, on in (("winds", neighbour_wind), ("attitudes", neighbour_attitude)) if on)
            raise ValueError(f"{owner}.act: observation length {obs.shape[1]} is not that of an observation with "
                             f"neighbours' {what} ({base} + {per} k, k >= 1)")
        return obs, to_dict(obs, k + 1, k, bool(neighbour_wind), bool(neighbour_attitude))
    n_vehicles = next((v for v in range(1, 65) if observation_size(v) == obs.shape[1]), None)
    if n_vehicles is None:
        raise ValueError(f"{owner}.act: observation length {obs.shape[1]} matches no formation size")
    return obs, to_dict(obs, n_vehicles)


class RowIntegrators:
    """Per-row integrators ``self.integral`` (n_rows, 3) of a batched agent: zeroed by ``reset(n_rows)`` (every
    row) and ``reset_rows(rows)`` (the rows whose episodes restarted)."""

    integral: np.ndarray

    def reset(self, n_rows: int) -> None:
        if isinstance(n_rows, bool) or not isinstance(n_rows, (int, np.integer)) or n_rows < 1:
            raise ValueError(f"{type(self).__name__}.reset: n_rows must be an integer >= 1, got {n_rows!r}")
        self.integral = np.zeros((int(n_rows), 3))

    def reset_rows(self, rows) -> None:
        """Zero the integrators of the given rows (their episodes restarted)."""
        self.integral[np.asarray(rows)] = 0.0

    def _rows_for(self, obs: np.ndarray) -> None:
        """Re-size the integrators to a batch of another size (a fresh start for every row)."""
        if self.integral.shape[0] != obs.shape[0]:
            self.reset(obs.shape[0])
