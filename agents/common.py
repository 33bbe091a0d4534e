"""What the batched classical agents share: the gains check, the per-row integrators' reset, and the
observation decoding (the formation size from the observation length, its groups)."""

from __future__ import annotations

import math
from dataclasses import fields

import numpy as np

from formation_env.sim.layout import ObservationLayout

__all__ = ["check_gains", "RowIntegrators", "observation_groups", "agent_layout"]


def check_gains(gains) -> None:
    """Every field of the gains dataclass ``gains`` a finite number >= 0 (never bool); a ValueError naming the
    first that is not (``<Class>.<field>``)."""
    for f in fields(gains):
        v = getattr(gains, f.name)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
            raise ValueError(f"{type(gains).__name__}.{f.name} must be a finite number >= 0, got {v!r}")


def observation_groups(obs, owner: str, layout: ObservationLayout | None = None) -> tuple[np.ndarray, dict]:
    """``(obs as float (N, D), its groups)`` for any formation size (the observation length fixes the number of
    neighbours); a ValueError naming ``owner`` for another shape or a length no formation has. ``layout``: the
    optional groups the observations hold (the env's ``observation_layout``, or a policy's; None: none), which the
    length alone cannot say (47 + 6 x 3 = 47 + 9 x 2), so the agent must be told."""
    obs = np.asarray(obs, dtype=float)
    if obs.ndim != 2:
        raise ValueError(f"{owner}.act: obs must have shape (N, D), got {obs.shape}")
    fitted = (layout or ObservationLayout()).fit(obs.shape[1], f"{owner}.act")
    return obs, fitted.split(obs)


def agent_layout(layout, owner: str) -> ObservationLayout:
    """``layout`` (None: no optional group) checked: an :class:`ObservationLayout`, else a ValueError naming
    ``owner``."""
    if layout is None:
        return ObservationLayout()
    if not isinstance(layout, ObservationLayout):
        raise ValueError(f"{owner}: layout must be an ObservationLayout or None, got {type(layout).__name__}")
    return layout


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
