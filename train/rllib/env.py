"""The formation env as RLlib sees it: the PettingZoo ParallelEnv through RLlib's PettingZoo wrapper.

This module imports ray at the top: only ``train.rllib.backend`` imports it, and only after checking
that Ray RLlib is installed. Env runners on other nodes unpickle ``FormationMultiAgentEnv`` and the
mapping functions by reference, so every node of a cluster needs this project installed.
"""

from __future__ import annotations

import numpy as np

from ray.rllib.env.wrappers.pettingzoo_env import ParallelPettingZooEnv

from formation_env.envs.parallel import FormationParallelEnv

from ..config import env_config_for

__all__ = ["FormationMultiAgentEnv", "shared_policy", "role_policy", "role_of", "LEADER_AGENT", "build_env_config"]

# Vehicle 0 flies the scenario's reference path in every scenario; every other vehicle holds a slot
# relative to it. That is what "leader" and "follower" mean for the per-role policies, also in
# reconfiguration, where the follower moves ahead of vehicle 0 in space but still flies a slot.
LEADER_AGENT = "uav_0"


def role_of(agent_id: str) -> str:
    return "leader" if agent_id == LEADER_AGENT else "follower"


def shared_policy(agent_id, *args, **kwargs) -> str:
    """RLlib policy_mapping_fn: one policy for every UAV (parameter sharing)."""
    return "shared"


def role_policy(agent_id, *args, **kwargs) -> str:
    """RLlib policy_mapping_fn: one policy per role (``leader`` / ``follower``)."""
    return role_of(agent_id)


def build_env_config(env_config: dict):
    """The EnvConfig of an RLlib env_config dict (``scenario``, ``action_mode``, ``learning``,
    ``env_kwargs``; flat observations, as for SB3)."""
    return env_config_for(env_config["scenario"], env_config["action_mode"], env_config.get("env_kwargs") or {},
                          learning=env_config.get("learning", "followers"))


class FormationMultiAgentEnv(ParallelPettingZooEnv):
    """``ParallelPettingZooEnv(FormationParallelEnv(...))`` built from an RLlib ``env_config`` dict.

    Three things differ from the plain wrapper:

    * the agent order is the env's own (the wrapper builds it from a set, whose order depends on the
      process's string hashing, so runs would not replay);
    * the learner's rewards are multiplied by ``env_config["reward_scale"]`` (1 by default; the run's
      progress log divides it back out);
    * a seeded reset mixes the seed with the env runner's index and the run's episode stream (0, or
      the iteration a resumed run restarted from). RLlib seeds runner ``i``'s sub-env ``j`` with
      ``seed + i + j``, so without the runner index two runners' sub-envs would share whole episode
      streams, and a resumed run would replay the episodes its first iterations saw.
    """

    def __init__(self, env_config: dict | None = None) -> None:
        self.worker_index = int(getattr(env_config, "worker_index", 0) or 0)
        env_config = dict(env_config or {})
        self.reward_scale = float(env_config.get("reward_scale", 1.0))
        self.episode_stream = int(env_config.get("episode_stream", 0))
        super().__init__(FormationParallelEnv(build_env_config(env_config)))
        self.agents = list(self.par_env.possible_agents)
        self.possible_agents = list(self.par_env.possible_agents)

    def reset(self, *, seed=None, options=None):
        if seed is not None:
            seed = int(np.random.SeedSequence([int(seed), self.worker_index, self.episode_stream]).generate_state(1)[0])
        obs, infos = super().reset(seed=seed, options=options)
        self.agents = list(self.par_env.agents)
        return obs, infos

    def step(self, action_dict):
        obs, rewards, terminateds, truncateds, infos = super().step(action_dict)
        self.agents = list(self.par_env.agents)
        if self.reward_scale != 1.0:
            rewards = {a: r * self.reward_scale for a, r in rewards.items()}
        return obs, rewards, terminateds, truncateds, infos
