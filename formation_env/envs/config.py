"""The environment configuration (re-exported): :mod:`formation_env.sim.config` defines it, below the
simulation that is built from it."""

from ..sim.config import ACTION_MODES, OBS_MODES, TURBULENCE_FIELDS, EnvConfig, Randomisation, RewardWeights

__all__ = ["ACTION_MODES", "OBS_MODES", "TURBULENCE_FIELDS", "RewardWeights", "Randomisation", "EnvConfig"]
