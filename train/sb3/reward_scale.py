"""The learner's reward scale: :class:`ScaleReward` multiplies the rewards an SB3 ``VecEnv`` returns by a constant
(the hyperparameter files' ``reward_scale``), leaving ``infos[i]["episode"]`` (the env's own return) unscaled."""

from __future__ import annotations

from stable_baselines3.common.vec_env import VecEnvWrapper

__all__ = ["ScaleReward"]


class ScaleReward(VecEnvWrapper):
    """``venv``'s rewards times ``scale`` (a finite number > 0)."""

    def __init__(self, venv, scale: float) -> None:
        super().__init__(venv)
        self.scale = float(scale)

    def reset(self):
        return self.venv.reset()

    def step_wait(self):
        obs, reward, done, infos = self.venv.step_wait()
        return obs, reward * self.scale, done, infos
