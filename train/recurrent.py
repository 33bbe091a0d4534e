"""Recurrent policies (sb3-contrib's ``RecurrentPPO``, ``MlpLstmPolicy``) in the project's rollout protocol.

A recurrent policy's action depends on its LSTM state as well as on the observation: :class:`RecurrentActor` holds
that state, one row per observation row, and carries it from one decision to the next. ``reset(n_rows)`` (the
:class:`formation_env.rollout.Policy` protocol's, called before an episode batch's first decision) starts every row
afresh: the next ``act`` tells the policy that each row's episode starts (sb3-contrib then zeroes that row's state).
``start(rows)`` does the same for some rows only (a caller that begins a new episode on a row while the others fly on).
The same observations after the same ``reset`` give the same actions, bit for bit.

:func:`model_policy` is how the evaluation, the validation during training and replay fly any SB3 model: an
``act`` function and its ``reset`` (None for a feed-forward model, whose action depends on the observation alone).
Its own module beside :mod:`train.config` so that the trainer (:mod:`train.sb3`) and the evaluation
(:mod:`train.evaluation`) share it without importing one another.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["RecurrentActor", "recurrent_ppo_class", "is_recurrent", "model_policy", "chain_resets", "INSTALL_HINT"]

INSTALL_HINT = "algo recurrent_ppo needs sb3-contrib: pip install -e '.[rl]' (or pip install sb3-contrib)"


def recurrent_ppo_class():
    """sb3-contrib's ``RecurrentPPO``, or a ValueError saying how to install it."""
    try:
        from sb3_contrib import RecurrentPPO
    except ModuleNotFoundError as exc:
        if exc.name != "sb3_contrib":
            raise
        raise ValueError(INSTALL_HINT) from None
    return RecurrentPPO


def is_recurrent(model) -> bool:
    """Whether ``model`` (an SB3 / sb3-contrib model) acts from an LSTM state (sb3-contrib's recurrent policies)."""
    return getattr(getattr(model, "policy", None), "lstm_actor", None) is not None


class RecurrentActor:
    """The deterministic actions of a recurrent model, its LSTM state carried across decisions (module docstring)."""

    def __init__(self, model) -> None:
        self.model = model
        self.state: tuple[np.ndarray, ...] | None = None
        self.starts: np.ndarray | None = None

    def reset(self, n_rows: int) -> None:
        """Start every one of ``n_rows`` rows afresh: the next decision is each row's episode's first."""
        if isinstance(n_rows, bool) or not isinstance(n_rows, (int, np.integer)) or n_rows < 1:
            raise ValueError(f"reset: n_rows must be a positive integer, got {n_rows!r}")
        self.state = None
        self.starts = np.ones(int(n_rows), dtype=bool)

    def start(self, rows) -> None:
        """Start the episodes of ``rows`` (indices or a boolean mask) afresh at the next decision; the other rows
        keep their state."""
        if self.starts is None:
            raise RuntimeError("start: call reset(n_rows) first")
        self.starts[np.asarray(rows)] = True

    def act(self, obs: np.ndarray) -> np.ndarray:
        obs = np.asarray(obs, dtype=np.float32)
        if self.starts is None:  # a caller that does not reset (a single act): every row starts here
            self.reset(len(obs))
        if len(obs) != len(self.starts):
            raise ValueError(f"recurrent policy: reset for {len(self.starts)} rows, asked to act on {len(obs)} "
                             "(call reset(n_rows) with the number of observation rows)")
        actions, self.state = self.model.predict(obs, state=self.state, episode_start=self.starts.copy(),
                                                 deterministic=True)
        self.starts[:] = False
        return actions


def model_policy(model) -> tuple[Callable[[np.ndarray], np.ndarray], Callable[[int], None] | None]:
    """``(act, reset)`` flying ``model`` deterministically: a recurrent model's :class:`RecurrentActor` (its
    ``reset`` starts the LSTM state), a feed-forward model's ``predict`` with no reset."""
    if is_recurrent(model):
        actor = RecurrentActor(model)
        return actor.act, actor.reset
    return (lambda obs: model.predict(obs, deterministic=True)[0]), None


def chain_resets(*resets: Callable[[int], None] | None) -> Callable[[int], None] | None:
    """One ``reset(n_rows)`` calling each given one in turn (None: none given)."""
    given = [r for r in resets if r is not None]
    if not given:
        return None
    if len(given) == 1:
        return given[0]

    def reset(n_rows: int) -> None:
        for r in given:
            r(n_rows)

    return reset
