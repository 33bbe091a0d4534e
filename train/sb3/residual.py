"""Residual policies on a classical agent: the learner's action is a correction added to ``agents.station_keeper``'s
set-points, ``clip(keeper(obs) + scale * a, -1, 1)`` (residual policy learning: Silver et al. 2018, Johannink et al.
2019). The keeper is part of the environment in training (:class:`ResidualVecEnv`; SB3 stores the learner's own
action) and part of the policy wherever it flies (:func:`residual_policy`; the sidecar's ``env.residual_on``).

Why: the keeper holds the slot across the track about as well as the learnt N-UAV policies (vee5 lateral RMS 0.36 m
against 0.31-0.38 m at sigma 1), and their gain over it comes from the vertical axis and the energy. A residual
starts from the keeper's precision and learns what to add to it, instead of re-learning the station keeping.

The keeper is stateful (per-row integrators): its rows restart with their episodes (the VecEnv's ``done``), and in
an evaluation with the batch (``reset(n_rows)``)."""

from __future__ import annotations

import math

import numpy as np
from stable_baselines3.common.vec_env import VecEnvWrapper

__all__ = ["RESIDUAL_AGENTS", "check_residual_on", "residual_policy", "ResidualVecEnv"]

#: the classical agents (:data:`train.evaluation.policy_loader.CLASSICAL_AGENTS`) a residual may be learnt on: those
#: that fly ``setpoints``
RESIDUAL_AGENTS = ("station_keeper",)


def check_residual_on(spec) -> dict:
    """The validated ``residual_on`` setting ``{"agent": name, "scale": s}`` (``scale`` in (0, 2]: the learner's
    action in [-1, 1] times ``scale`` is added to the agent's); a ValueError naming the bad value and its range."""
    if not isinstance(spec, dict) or set(spec) != {"agent", "scale"}:
        raise ValueError(f"residual_on must be a mapping {{agent: one of {sorted(RESIDUAL_AGENTS)}, scale: a number in "
                         f"(0, 2]}}, got {spec!r}")
    agent, scale = spec["agent"], spec["scale"]
    if agent not in RESIDUAL_AGENTS:
        raise ValueError(f"residual_on.agent must be one of {sorted(RESIDUAL_AGENTS)}, got {agent!r}")
    if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not math.isfinite(scale) or not 0 < scale <= 2:
        raise ValueError(f"residual_on.scale must be a number in (0, 2], got {scale!r}")
    return {"agent": agent, "scale": float(scale)}


def _agent(spec: dict, layout=None):
    from agents.registry import classical_agent

    agent = classical_agent(spec["agent"], layout=layout)  # told the observation's layout
    if agent.action_mode != "setpoints":  # pragma: no cover - RESIDUAL_AGENTS lists set-point agents only
        raise ValueError(f"residual_on: {spec['agent']} flies {agent.action_mode!r}, not set-points")
    return agent


def _combine(base: np.ndarray, a: np.ndarray, scale: float) -> np.ndarray:
    return np.clip(np.asarray(base, dtype=float) + scale * np.asarray(a, dtype=float), -1.0, 1.0)


def residual_policy(act, spec, layout=None):
    """``(act', reset)``: the evaluation's and the validation's policy of a residual learner ``act(obs) -> a``;
    ``reset(n_rows)`` restarts the agent's integrators (every batch of episodes); ``layout``: the observations'
    :class:`~formation_env.sim.layout.ObservationLayout` (the policy's; None: no optional group)."""
    spec = check_residual_on(spec)
    agent = _agent(spec, layout)

    def combined(obs):
        return _combine(agent.act(obs), act(obs), spec["scale"])

    return combined, agent.reset


class ResidualVecEnv(VecEnvWrapper):
    """``venv`` (set-point actions) whose actions are the agent's set-points plus ``scale`` times the learner's,
    the agent acting on the last observations (after an episode's end, the next episode's first: the VecEnv resets
    automatically, and the agent's rows restart with it). ``layout``: the observations' ObservationLayout."""

    def __init__(self, venv, spec, layout=None) -> None:
        super().__init__(venv)
        self.spec = check_residual_on(spec)
        self.agent = _agent(self.spec, layout)
        self._obs: np.ndarray | None = None

    def reset(self):
        self._obs = self.venv.reset()
        self.agent.reset(self.num_envs)
        return self._obs

    def step_async(self, actions) -> None:
        if self._obs is None:
            raise RuntimeError("ResidualVecEnv: step before reset")
        self.venv.step_async(_combine(self.agent.act(self._obs), actions, self.spec["scale"]))

    def step_wait(self):
        obs, rew, done, infos = self.venv.step_wait()
        self._obs = obs
        if np.any(done):
            self.agent.reset_rows(np.nonzero(done)[0])
        return obs, rew, done, infos
