"""Reinforcement-learning environments: PettingZoo parallel/AEC and single-agent Gymnasium."""

from ..sim.config import ACTION_MODES, EnvConfig, Randomisation, RewardWeights
from ..sim import INFO_REWARD_KEYS
from .gym_env import GYM_IDS, FormationGymEnv, register_envs
from .parallel import FormationParallelEnv

__all__ = ["ACTION_MODES", "EnvConfig", "Randomisation", "RewardWeights", "FormationParallelEnv", "FormationGymEnv",
           "GYM_IDS", "register_envs", "parallel_env", "env", "INFO_REWARD_KEYS"]


def parallel_env(scenario: str = "formation_keeping", render_mode: str | None = None, **options) -> FormationParallelEnv:
    """The PettingZoo ParallelEnv of ``scenario`` (options: see :class:`EnvConfig`; an unknown option raises
    ``TypeError``, a bad value ``ValueError``)."""
    return FormationParallelEnv(render_mode=render_mode, scenario=scenario, **options)


def env(scenario: str = "formation_keeping", render_mode: str | None = None, **options):
    """The PettingZoo AEC version of :func:`parallel_env` (PettingZoo's ``parallel_to_aec``, except that the
    ``step`` receiving an action checks it: :func:`formation_env.envs.compat.checked_parallel_to_aec`)."""
    from .compat import checked_parallel_to_aec

    return checked_parallel_to_aec(parallel_env(scenario, render_mode=render_mode, **options))


def __getattr__(name):  # the vector envs import stable-baselines3: load them on first use
    if name in ("FormationVecEnv", "FormationVectorEnv"):
        from . import vector

        return getattr(vector, name)
    raise AttributeError(name)
