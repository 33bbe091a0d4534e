"""A centralised critic for parameter-shared PPO: MAPPO with an agent-specific global state (issue 25).

Yu et al. ("The Surprising Effectiveness of PPO in Cooperative Multi-Agent Games", NeurIPS 2022) train one actor
shared by every agent on its own observation and a critic on a global state; their strongest state is agent-
specific: the agent's own observation followed by everything else. Here, over the native batched VecEnv (each
learning UAV a row, rows formation-major: row ``f * A + k`` is agent ``k`` of formation ``f``):

* :class:`GlobalStateVecEnv` appends to every row the observations of the other ``A - 1`` agents of its
  formation, in agent order (the ``state()`` of the PettingZoo env, the agent's own first): the critic sees
  every follower's slot errors, winds and neighbours, the actor still only its own;
* :class:`CentralCriticPolicy` is SB3's ``ActorCriticPolicy`` whose actor network reads only the first
  ``local_dim`` values of that row (the agent's own observation) and whose value network reads all of them.

Execution stays decentralised: the actor never reads the appended part, so :meth:`CentralCriticPolicy.predict`
accepts the plain per-agent observation as well (it pads the rest with zeros, which the actor does not read),
and the evaluation, replay and policy loaders fly a MAPPO zip exactly like a shared-PPO one.
"""

from __future__ import annotations

import numpy as np
import torch
from gymnasium import spaces
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.vec_env import VecEnvWrapper
from torch import nn

__all__ = ["GlobalStateVecEnv", "CentralCriticPolicy", "SplitMlpExtractor", "agent_specific_state"]


def agent_specific_state(obs: np.ndarray, agents_per_formation: int) -> np.ndarray:
    """(N, A * D): each row's own observation, then the other agents' of its formation in agent order, for the
    rows ``obs`` (N, D), N = formations x A, formation-major."""
    a = int(agents_per_formation)
    n, d = obs.shape
    if a < 1 or n % a:
        raise ValueError(f"agent_specific_state: {n} rows are not whole formations of {a} agents")
    f = obs.reshape(n // a, a, d)
    out = np.empty((n // a, a, a * d), dtype=obs.dtype)
    for k in range(a):
        out[:, k, :d] = f[:, k]
        others = [j for j in range(a) if j != k]
        if others:
            out[:, k, d:] = f[:, others].reshape(n // a, (a - 1) * d)
    return out.reshape(n, a * d)


class GlobalStateVecEnv(VecEnvWrapper):
    """``venv`` (a :class:`~formation_env.envs.FormationVecEnv` or a wrapper of one) with every row's
    observation extended by :func:`agent_specific_state`; ``infos[i]["terminal_observation"]`` likewise (a
    formation's agents end together, so a done row's formation has every terminal observation)."""

    def __init__(self, venv, agents_per_formation: int) -> None:
        self.agents_per_formation = a = int(agents_per_formation)
        base = venv.observation_space
        if venv.num_envs % a:
            raise ValueError(f"GlobalStateVecEnv: {venv.num_envs} rows are not whole formations of {a} agents")
        space = spaces.Box(np.tile(base.low, a), np.tile(base.high, a), (a * base.shape[0],), dtype=base.dtype)
        super().__init__(venv, observation_space=space)
        self.local_dim = int(base.shape[0])

    def reset(self):
        return agent_specific_state(self.venv.reset(), self.agents_per_formation)

    def step_wait(self):
        obs, rew, done, infos = self.venv.step_wait()
        a = self.agents_per_formation
        for f in np.unique(np.nonzero(done)[0] // a):
            rows = range(f * a, (f + 1) * a)
            if all("terminal_observation" in infos[i] for i in rows):
                final = agent_specific_state(np.stack([infos[i]["terminal_observation"] for i in rows]), a)
                for j, i in enumerate(rows):
                    infos[i]["terminal_observation"] = final[j]
        return agent_specific_state(obs, a), rew, done, infos


def _mlp(in_dim: int, widths, activation_fn) -> tuple[nn.Sequential, int]:
    layers, last = [], in_dim
    for w in widths:
        layers += [nn.Linear(last, int(w)), activation_fn()]
        last = int(w)
    return nn.Sequential(*layers), last


class SplitMlpExtractor(nn.Module):
    """SB3's ``MlpExtractor`` with separate inputs: the policy network reads ``features[..., :local_dim]``, the
    value network all of ``features`` (``net_arch`` a list for both or a dict with ``pi`` / ``vf``)."""

    def __init__(self, feature_dim: int, local_dim: int, net_arch, activation_fn) -> None:
        super().__init__()
        if not 0 < local_dim <= feature_dim:
            raise ValueError(f"SplitMlpExtractor: local_dim must be in [1, {feature_dim}], got {local_dim!r}")
        pi, vf = (net_arch.get("pi", []), net_arch.get("vf", [])) if isinstance(net_arch, dict) else (net_arch, net_arch)
        self.local_dim = int(local_dim)
        self.policy_net, self.latent_dim_pi = _mlp(self.local_dim, pi, activation_fn)
        self.value_net, self.latent_dim_vf = _mlp(int(feature_dim), vf, activation_fn)

    def forward(self, features: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.forward_actor(features), self.forward_critic(features)

    def forward_actor(self, features: torch.Tensor) -> torch.Tensor:
        return self.policy_net(features[..., : self.local_dim])

    def forward_critic(self, features: torch.Tensor) -> torch.Tensor:
        return self.value_net(features)


class CentralCriticPolicy(ActorCriticPolicy):
    """PPO's actor-critic with a decentralised actor (the first ``local_dim`` observation values) and a critic on
    the whole agent-specific global state (:class:`GlobalStateVecEnv`). The features extractor must be the
    identity (SB3's default ``FlattenExtractor`` over a flat Box), so that the split is on observation values."""

    def __init__(self, *args, local_dim: int, **kwargs) -> None:
        self._local_dim = int(local_dim)
        super().__init__(*args, **kwargs)

    def _build_mlp_extractor(self) -> None:
        self.mlp_extractor = SplitMlpExtractor(self.features_dim, self._local_dim, self.net_arch, self.activation_fn)

    def _get_constructor_parameters(self) -> dict:
        data = super()._get_constructor_parameters()
        data["local_dim"] = self._local_dim
        return data

    @property
    def local_dim(self) -> int:
        return self._local_dim

    def predict(self, observation, state=None, episode_start=None, deterministic: bool = False):
        """As SB3's, and a plain per-agent observation (last axis ``local_dim``) is accepted too: the rest of the
        global state is padded with zeros, which the actor does not read (decentralised execution)."""
        obs = np.asarray(observation)
        full = int(self.observation_space.shape[0])
        if obs.shape[-1] == self._local_dim and full != self._local_dim:
            pad = np.zeros(obs.shape[:-1] + (full - self._local_dim,), dtype=obs.dtype)
            observation = np.concatenate([obs, pad], axis=-1)
        return super().predict(observation, state, episode_start, deterministic)
