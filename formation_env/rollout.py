"""One batched rollout and one policy protocol: every caller that flies whole episodes (the evaluation, the
wake-surfing evaluation, replay, the scenario runner) runs :func:`rollout` with its own recorders.

Policy protocol (SB3 loaders, RLlib loaders, the thesis PID, ``pid_formation``, extremum seeking):

* ``reset(n_rows)``: called once before the first decision with the number of observation rows
  (formations x agents); a stateful policy starts its state here (a PID's integrators, a recurrent policy's
  memory), which ``act`` then carries from one decision to the next, row by row;
* ``act(obs) -> actions``: ``obs`` (N, D) float32, the agents' rows in formation-major order (row
  ``f * A + k`` is agent ``k`` of formation ``f``); actions (N, 4) in [-1, 1] (clipped here);
* optional ``observe(decision)``: a policy that needs more of the step output than the observation
  (extremum seeking climbs the measured saving) gets a :class:`Decision` before each ``act``.

Episode semantics: one episode per seed, all in one batch. A formation whose episode ends is no longer
recorded (its rows get zero actions); one that ended early (terminated) is restarted with its seed so the
batch stays finite while the others fly on. An early end is recorded as such: recorders see the step that
ended it and its reason (collision / crash).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, Sequence, runtime_checkable

import numpy as np

from .sim import SimOutput, Simulation

__all__ = ["Policy", "Decision", "Recorder", "RolloutResult", "rollout", "ZeroPolicy", "FunctionPolicy"]


@runtime_checkable
class Policy(Protocol):
    """What :func:`rollout` flies (see the module docstring)."""

    def reset(self, n_rows: int) -> None: ...

    def act(self, obs: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class Decision:
    """Per-row view of the step output given to a policy's ``observe`` before each ``act`` (rows as ``obs``)."""

    saving: np.ndarray  # (N,) induced-drag saving of the last decision (0 at the start and for ended episodes)
    steady_wind_ned_mps: np.ndarray  # (N, 3) each row's episode steady wind, m/s NED
    leader_velocity_demand_ned_mps: np.ndarray  # (N, 3) vehicle 0's demanded ground velocity, m/s NED
    alive: np.ndarray  # (N,) bool: the row's episode is still being flown


class Recorder:
    """Base of the rollout's recorders: override what you need. ``alive`` (B,) is the formations still
    flown before the step's ends are applied; ``k`` the decisions taken so far."""

    def start(self, sim: Simulation, out: SimOutput) -> None:
        """After the reset, before the first decision."""

    def before_step(self, sim: Simulation, alive: np.ndarray, k: int) -> None:
        """Just before decision ``k + 1`` is stepped (the state it starts from)."""

    def after_step(self, sim: Simulation, out: SimOutput, actions: np.ndarray, alive: np.ndarray, k: int) -> None:
        """After decision ``k``, before finished formations are restarted."""

    def ended(self, sim: Simulation, out: SimOutput, formations: np.ndarray, k: int) -> None:
        """``formations`` ended their episodes at decision ``k`` (read their final state now)."""


@dataclass
class RolloutResult:
    """Per formation: its seed, decisions flown and how its episode ended."""

    seeds: list
    decisions: np.ndarray  # (B,) int64
    terminated: np.ndarray  # (B,) bool: ended early (collision or envelope)
    collided: np.ndarray  # (B,) bool
    crashed: np.ndarray  # (B,) bool: a UAV left the envelope or diverged
    recorders: tuple = field(default=())


class FunctionPolicy:
    """A policy from an ``act(obs) -> actions`` function (and an optional ``reset(n_rows)``)."""

    def __init__(self, act, reset=None, name: str = "function") -> None:
        self._act, self._reset, self.name = act, reset, name

    def reset(self, n_rows: int) -> None:
        if self._reset is not None:
            self._reset(n_rows)

    def act(self, obs: np.ndarray) -> np.ndarray:
        return self._act(obs)


class ZeroPolicy:
    """Zero actions: in ``setpoints`` and ``residual`` modes the thesis PID flies unchanged (the ``pid`` baseline)."""

    name = "pid"

    def reset(self, n_rows: int) -> None:
        pass

    def act(self, obs: np.ndarray) -> np.ndarray:
        return np.zeros((obs.shape[0], 4), dtype=np.float32)


def rollout(sim: Simulation, policy, seeds: Sequence[int], *, recorders: Sequence[Recorder] = (),
            options: dict | None = None, restart_terminated: bool = True) -> RolloutResult:
    """Fly one episode per seed on ``sim`` (its batch size must equal ``len(seeds)``) with ``policy``.

    ``options``: reset options of :meth:`Simulation.reset` (e.g. a steady wind for every episode).
    ``restart_terminated``: restart a formation that ended early so the batch stays finite (False: leave it)."""
    seeds = [None if s is None else int(s) for s in seeds]
    if not seeds:
        raise ValueError("seeds must not be empty")
    if len(seeds) != sim.batch_size:
        raise ValueError(f"rollout: {len(seeds)} seeds for a simulation of {sim.batch_size} formations")
    b, agents = sim.batch_size, list(sim.agent_indices)
    a_n = len(agents)
    out = sim.reset(None, seeds, options)
    for r in recorders:
        r.start(sim, out)
    if callable(getattr(policy, "reset", None)):
        policy.reset(b * a_n)
    observe = getattr(policy, "observe", None)
    alive = np.ones(b, dtype=bool)
    decisions = np.zeros(b, dtype=np.int64)
    terminated = np.zeros(b, dtype=bool)
    collided = np.zeros(b, dtype=bool)
    crashed = np.zeros(b, dtype=bool)
    saving_rows = np.zeros(b * a_n)
    k = 0
    while alive.any():
        obs = out.observation[:, agents].reshape(b * a_n, sim.obs_size).astype(np.float32)
        if observe is not None:
            st = sim.state
            observe(Decision(saving=saving_rows.copy(), steady_wind_ned_mps=np.repeat(st.steady_wind, a_n, axis=0),
                             leader_velocity_demand_ned_mps=np.repeat(st.velocity_demand[:, 0], a_n, axis=0),
                             alive=np.repeat(alive, a_n)))
        act = np.clip(np.asarray(policy.act(obs), dtype=float).reshape(b, a_n, 4), -1.0, 1.0)
        act[~alive] = 0.0
        for r in recorders:
            r.before_step(sim, alive, k)
        with np.errstate(all="ignore"):
            out = sim.step(act)
        k += 1
        saving_rows = np.where(np.repeat(alive, a_n), out.info.induced_drag_saving[:, agents].reshape(-1), 0.0)
        for r in recorders:
            r.after_step(sim, out, act, alive, k)
        done = (out.terminated | out.truncated) & alive
        if done.any():
            idx = np.nonzero(done)[0]
            collided[idx] = out.info.collision[idx]
            crashed[idx] = out.info.crashed[idx].any(axis=1)
            terminated[idx] = out.terminated[idx]
            decisions[idx] = k
            for r in recorders:
                r.ended(sim, out, idx, k)
            alive &= ~done
            early = idx[out.terminated[idx]]
            if restart_terminated and len(early) and alive.any():  # keep the batch finite
                out = sim.reset(early, [seeds[i] for i in early], options)
    return RolloutResult(seeds, decisions, terminated, collided, crashed, tuple(recorders))
