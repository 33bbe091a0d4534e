"""The separation guard in the training loop: :class:`GuardedVecEnv` passes every action through
:class:`agents.separation_guard.SeparationGuard` with the observation the policy acted on, so the policy learns
with the guard in the loop (SB3 stores the policy's own actions in its rollout buffer; the guard is part of the
environment from the policy's point of view, and part of the policy when it is evaluated)."""

from __future__ import annotations

import numpy as np
from stable_baselines3.common.vec_env import VecEnvWrapper

__all__ = ["GuardedVecEnv", "guard_gains", "guarded"]


def guard_gains(spec):
    """The :class:`agents.separation_guard.GuardGains` of an ``action_guard`` setting (a run's or a sidecar's): True
    (or None) the defaults, a dict their overrides (e.g. ``{"clip_ramp": 0.25}``); a ValueError naming an unknown
    gain or a bad value."""
    from agents.separation_guard import GuardGains

    if spec is None or spec is True:
        return GuardGains()
    if not isinstance(spec, dict):
        raise ValueError(f"the separation guard's gains must be a dict of GuardGains fields, got {spec!r}")
    known = set(GuardGains.__dataclass_fields__)
    unknown = sorted(set(spec) - known)
    if unknown:
        raise ValueError(f"unknown separation-guard gain(s) {unknown}; GuardGains has {sorted(known)}")
    return GuardGains(**spec)


def guarded(act, gains=None, layout=None):
    """``act(obs) -> actions`` followed by the separation guard (the evaluation's and the validation's policy);
    ``gains``: an ``action_guard`` setting (:func:`guard_gains`: None or True for the defaults, or a dict);
    ``layout``: the observations' :class:`~formation_env.sim.layout.ObservationLayout` (the policy's; None: no
    optional group)."""
    from agents.separation_guard import SeparationGuard

    guard = SeparationGuard(guard_gains(gains), layout=layout)
    return lambda obs: guard.filter(obs, act(obs))


class GuardedVecEnv(VecEnvWrapper):
    """``venv`` (a :class:`~formation_env.envs.FormationVecEnv` of set-point actions, or a wrapper of one that keeps
    its observations) whose actions pass through the separation guard, judged on the last observations (after an
    episode's end the next episode's first: the VecEnv resets automatically). ``layout``: the observations'
    ObservationLayout (None: no optional group)."""

    def __init__(self, venv, gains=None, layout=None) -> None:
        from agents.separation_guard import SeparationGuard

        super().__init__(venv)
        self.guard = SeparationGuard(guard_gains(gains), layout=layout)
        self._obs: np.ndarray | None = None

    def reset(self):
        self._obs = self.venv.reset()
        return self._obs

    def step_async(self, actions) -> None:
        if self._obs is None:
            raise RuntimeError("GuardedVecEnv: step before reset")
        self.venv.step_async(self.guard.filter(self._obs, np.asarray(actions)))

    def step_wait(self):
        obs, rew, done, infos = self.venv.step_wait()
        self._obs = obs
        return obs, rew, done, infos
