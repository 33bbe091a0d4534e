"""A :class:`~formation_env.sim.Simulation` with a task's Python terms composed after the compiled decision step
(:mod:`formation_env.tasks.terms`): rewards added to the compiled reward, observation groups appended after the
compiled observation, terminations ending formations as the compiled ones do (the formation then stays frozen
until reset), each term's ``reset`` hook called after a reset. Built by
:func:`formation_env.tasks.compose.task_simulation`, never for a task without Python terms, so that the built-in
tasks fly the compiled step alone.
"""

from __future__ import annotations

import numpy as np

from .observe import OBS_CLIP
from .simulation import SimOutput, Simulation

__all__ = ["ComposedSimulation"]


class ComposedSimulation(Simulation):
    """``terms``: a :class:`formation_env.tasks.terms.TaskTerms`. ``obs_size`` is the compiled observation's
    size plus the Python groups' (``compiled_obs_size`` the first)."""

    def __init__(self, config, batch_size: int = 1, *, terms, **kwargs) -> None:
        super().__init__(config, batch_size, **kwargs)
        self.terms = terms
        self.compiled_obs_size = self.obs_size
        self.observation_layout = self.observation_layout.with_extra((t.name, t.size) for t in terms.observations)
        self.obs_size = self.observation_layout.size
        b, v = self.batch_size, self.n_vehicles
        self.observation = np.zeros((b, v, self.obs_size))
        self.term_rewards = np.zeros((b, v, len(terms.rewards)))  # the last decision's weighted Python rewards

    def reset(self, indices=None, seeds=None, options: dict | None = None) -> SimOutput:
        out = super().reset(indices, seeds, options)
        idx = np.arange(self.batch_size) if indices is None else np.asarray(indices, dtype=np.int64).reshape(-1)
        if len(idx):
            for fn in self.terms.functions():
                if callable(getattr(fn, "reset", None)):
                    fn.reset(self, idx)
            self.term_rewards[idx] = 0.0
        return self._composed(out)

    def step(self, actions=None) -> SimOutput:
        flown = ~self._ended  # the formations this decision flies (the others stay frozen)
        out = super().step(actions)
        o, s = self.output, self.state
        for j, t in enumerate(self.terms.rewards):
            r = np.asarray(t.fn(self), dtype=float)
            r = np.broadcast_to(r[:, None] if r.ndim == 1 else r, o.reward.shape)
            self.term_rewards[..., j] = np.where(flown[:, None], t.weight * r, 0.0)
        if self.terms.rewards:
            extra = self.term_rewards.sum(axis=2)
            np.add(o.reward, extra, out=o.reward)  # in place: the arrays belong to the compiled step's structs
            np.add(s.episode_return, extra, out=s.episode_return)
        if self.terms.terminations:
            ended = np.zeros(self.batch_size, dtype=bool)
            for t in self.terms.terminations:
                ended |= np.asarray(t.fn(self), dtype=bool).reshape(self.batch_size)
            ended &= flown
            np.logical_or(o.terminated, ended, out=o.terminated)
            np.logical_and(o.truncated, ~o.terminated, out=o.truncated)
            np.logical_or(o.terminated, o.truncated, out=self._ended)
            self._any_ended = bool(self._ended.any())
        return self._composed(out)

    def _composed(self, out: SimOutput) -> SimOutput:
        """``out`` with the observation the compiled one followed by the Python groups."""
        d = self.compiled_obs_size
        self.observation[..., :d] = self.output.observation
        for t in self.terms.observations:
            val = np.asarray(t.fn(self), dtype=float).reshape(self.batch_size, self.n_vehicles, t.size)
            self.observation[..., d:d + t.size] = np.clip(np.nan_to_num(val, nan=0.0, posinf=0.0, neginf=0.0),
                                                          -OBS_CLIP, OBS_CLIP)
            d += t.size
        return out._replace(observation=self.observation)

    def infos(self, i: int) -> list[dict]:
        """The compiled infos plus ``reward_<name>`` of every Python reward term (weighted; 0.0 at reset)."""
        result = super().infos(i)
        rows = self.term_rewards[i].tolist()
        for v, info in enumerate(result):
            info.update({f"reward_{t.name}": rows[v][j] for j, t in enumerate(self.terms.rewards)})
        return result
