"""Thin adapters for other RL tools: the AEC env that checks each action at the step receiving it, and
the SuperSuit route to Stable-Baselines3.

* :func:`checked_parallel_to_aec` (what :func:`formation_env.env` returns): PettingZoo's
  ``parallel_to_aec`` stores each agent's action and steps the parallel env only at the last agent, so a
  NaN or wrongly shaped action would be rejected one agent later, naming another agent. Here the
  ``step`` that receives it raises ``ValueError`` naming its agent, and nothing is stored.
* :func:`supersuit_vec_env`: SuperSuit's ``concat_vec_envs_v1(pettingzoo_env_to_vec_env_v1(env), n,
  base_class="stable_baselines3")`` as a Stable-Baselines3 ``VecEnv`` that (1) marks time-outs as
  truncations (``infos[i]["TimeLimit.truncated"]``: SuperSuit's SB3 wrapper folds truncations into
  ``dones`` without it, so SB3 treats every time-out as terminal and never bootstraps), (2) supports
  ``seed()`` (``PPO(..., seed=0)`` calls it; SuperSuit's ``ConcatVecEnv`` has none) and (3) gives every copy
  of the env its own seed (the copies are pickled from one env, so unseeded they would fly the same
  episodes). :class:`formation_env.envs.FormationVecEnv` does the same job natively (B formations in one
  compiled call) and is the recommended route; this one is for pipelines built on SuperSuit.
"""

from __future__ import annotations

import numpy as np
from pettingzoo.utils.conversions import parallel_to_aec_wrapper
from pettingzoo.utils.wrappers import OrderEnforcingWrapper

from .parallel import check_action

__all__ = ["CheckedParallelToAEC", "checked_parallel_to_aec", "supersuit_vec_env", "SuperSuitVecEnv"]


class CheckedParallelToAEC(parallel_to_aec_wrapper):
    """PettingZoo's ``parallel_to_aec_wrapper`` whose ``step`` checks the action it receives (a live
    agent's action: 4 finite real numbers, see :func:`formation_env.envs.parallel.check_action`)."""

    def step(self, action):
        agent = self.agent_selection
        if not (self.terminations[agent] or self.truncations[agent]):  # a dead agent steps with None
            check_action(agent, action)
        return super().step(action)


def checked_parallel_to_aec(par_env):
    """As ``pettingzoo.utils.conversions.parallel_to_aec`` (with its ``OrderEnforcingWrapper``; its
    ``aec_to_parallel`` still unwraps it), each action checked by the ``step`` that receives it."""
    return OrderEnforcingWrapper(CheckedParallelToAEC(par_env))


def _vec_env_base():
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv

    return VecEnv


def supersuit_vec_env(env, num_vec_envs: int = 1, *, num_cpus: int = 0, seed: int | None = None):
    """An SB3 ``VecEnv`` of ``num_vec_envs`` copies of the PettingZoo parallel ``env`` (one SB3 index per
    agent and copy), through SuperSuit, with truncations and seeding SB3 understands (module docstring).

    >>> venv = supersuit_vec_env(formation_env.parallel_env("formation_keeping", learning="followers"), 4)
    >>> PPO("MlpPolicy", venv, seed=0).learn(256)
    """
    import supersuit as ss

    if isinstance(num_vec_envs, bool) or not isinstance(num_vec_envs, (int, np.integer)) or num_vec_envs < 1:
        raise ValueError(f"num_vec_envs must be an integer >= 1, got {num_vec_envs!r}")
    inner = ss.concat_vec_envs_v1(ss.pettingzoo_env_to_vec_env_v1(env), int(num_vec_envs), num_cpus=num_cpus,
                                  base_class="gymnasium")
    return _supersuit_vec_env_class()(inner, seed=seed)


def __getattr__(name):  # the SB3 VecEnv subclass is built on first use (stable-baselines3 is optional)
    if name == "SuperSuitVecEnv":
        return _supersuit_vec_env_class()
    raise AttributeError(name)


_CLASS: list = []


def _supersuit_vec_env_class():
    if _CLASS:
        return _CLASS[0]
    VecEnv = _vec_env_base()
    from .vector import OneObjectVecEnvMethods  # imports stable-baselines3, optional: on first use

    class SuperSuitVecEnv(OneObjectVecEnvMethods, VecEnv):
        """SB3 ``VecEnv`` over SuperSuit's (Gymnasium-style) ``ConcatVecEnv`` of Markov vector envs.

        Seeding: ``seed(s)`` (or ``seed=s`` at construction) makes the next ``reset()`` reset copy ``c`` with
        seed ``s + c``; later episodes draw from each copy's stream seeded by that. Without any seed the
        first reset draws one at random (distinct copies all the same)."""

        def __init__(self, venv, seed: int | None = None) -> None:
            self.venv = venv
            self._render_mode = getattr(venv, "render_mode", None)
            super().__init__(venv.num_envs, venv.observation_space, venv.action_space)
            self._pending_seed = None if seed is None else self._check_seed(seed)
            self._was_reset = False
            self._actions = None

        @staticmethod
        def _check_seed(seed) -> int:
            from ..sim.validation import MAX_SEED, check_seed

            return check_seed(seed, allow_none=False, top=MAX_SEED - 2**16)  # copy c gets seed + c

        def seed(self, seed: int | None = None):
            if seed is None:
                seed = int(np.random.randint(0, np.iinfo(np.uint32).max, dtype=np.uint32))
            self._pending_seed = self._check_seed(seed)
            return [self._pending_seed + i for i in range(self.num_envs)]

        def reset(self):
            seed = self._pending_seed
            if seed is None and not self._was_reset:  # the pickled copies share one entropy: seed them apart
                seed = int(np.random.SeedSequence().generate_state(1)[0])
            obs, infos = self.venv.reset(seed=seed)
            self._pending_seed, self._was_reset = None, True
            self.reset_infos = list(infos)
            self._reset_seeds()
            self._reset_options()
            return obs

        def step_async(self, actions) -> None:
            self._actions = actions

        def step_wait(self):
            if self._actions is None:
                raise RuntimeError("step_wait() called without step_async()")
            if not self._was_reset:
                raise RuntimeError("step() before any reset(): call reset() first")
            obs, rewards, terms, truncs, infos = self.venv.step(self._actions)
            self._actions = None
            terms, truncs = np.asarray(terms, dtype=bool), np.asarray(truncs, dtype=bool)
            dones = terms | truncs
            infos = [dict(i) for i in infos]
            for i in np.nonzero(dones)[0]:
                infos[i]["TimeLimit.truncated"] = bool(truncs[i] and not terms[i])
            return obs, np.asarray(rewards, dtype=np.float32), dones, infos

        def close(self) -> None:
            self.venv.close()

        def get_attr(self, attr_name, indices=None):
            if attr_name == "render_mode":
                return [self._render_mode for _ in self._get_indices(indices)]
            return super().get_attr(attr_name, indices)

        def get_images(self):
            frame = self.venv.render()
            return [frame for _ in range(self.num_envs)]

    SuperSuitVecEnv.__module__ = __name__
    _CLASS.append(SuperSuitVecEnv)
    return SuperSuitVecEnv
