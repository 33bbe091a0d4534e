"""Single-agent Gymnasium environments: the learner flies one UAV, the others fly the PID baseline.

Registered ids (on ``import formation_env``):

=======================================  =================  ==========================
id                                       scenario           learner
=======================================  =================  ==========================
formation_env/FormationKeeping-v0        formation_keeping  follower (uav_1)
formation_env/Reconfiguration-v0         reconfiguration    follower (uav_1)
formation_env/Gust-v0                    gust               the single UAV (uav_0)
formation_env/Tracking-v0                tracking           the single UAV (uav_0)
formation_env/Echelon-v0                 echelon            first follower (uav_1)
formation_env/Vee-v0                     vee                first follower (uav_1)
formation_env/CloseFormation-v0          close_formation    follower (uav_1)
=======================================  =================  ==========================

Keyword arguments of ``gymnasium.make`` go to :class:`~formation_env.envs.config.EnvConfig`
(e.g. ``action_mode="residual"``, ``randomisation=Randomisation(...)``), plus ``learner`` (the UAV
index) and ``render_mode``.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from .config import EnvConfig
from .parallel import FormationParallelEnv, make_config

__all__ = ["FormationGymEnv", "GYM_IDS", "register_envs"]

GYM_IDS = {
    "formation_env/FormationKeeping-v0": ("formation_keeping", 1),
    "formation_env/Reconfiguration-v0": ("reconfiguration", 1),
    "formation_env/Gust-v0": ("gust", 0),
    "formation_env/Tracking-v0": ("tracking", 0),
    "formation_env/Echelon-v0": ("echelon", 1),
    "formation_env/Vee-v0": ("vee", 1),
    "formation_env/CloseFormation-v0": ("close_formation", 1),
}


class FormationGymEnv(gym.Env):
    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 10}

    def __init__(self, config: EnvConfig | None = None, learner: int = 1, render_mode: str | None = None, **options):
        cfg = make_config(config, **options)
        if isinstance(learner, bool) or not isinstance(learner, (int, np.integer)):
            raise ValueError(f"learner must be a UAV index, got {learner!r}")
        cfg = EnvConfig(**{**cfg.__dict__, "learning": (int(learner),)})
        self._par = FormationParallelEnv(cfg, render_mode=render_mode)
        self.config = cfg
        self.agent = self._par.possible_agents[0]
        self.observation_space = self._par.observation_space(self.agent)
        self.action_space = self._par.action_space(self.agent)
        self.render_mode = render_mode

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        if seed is None:
            seed = int(self.np_random.integers(2**63 - 1))
        obs, infos = self._par.reset(seed=seed, options=options)
        return obs[self.agent], infos[self.agent]

    def step(self, action):
        obs, rewards, terms, truncs, infos = self._par.step({self.agent: action})
        return obs[self.agent], rewards[self.agent], terms[self.agent], truncs[self.agent], infos[self.agent]

    def render(self):
        return self._par.render()

    def close(self):
        self._par.close()


def register_envs() -> None:
    for env_id, (scenario, learner) in GYM_IDS.items():
        if env_id not in gym.registry:
            gym.register(env_id, entry_point="formation_env.envs.gym_env:FormationGymEnv",
                         kwargs={"scenario": scenario, "learner": learner})
