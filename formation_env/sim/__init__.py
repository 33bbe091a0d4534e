"""The formation simulation: ELL wake coupled to the Aerosonde dynamics and the thesis PID, batched.

:class:`Simulation` is the public engine (B formations, ``reset(indices, seeds, options)`` and
``step(actions)`` returning a complete :class:`SimOutput`); it is built from an :class:`EnvConfig`.
"""

from .config import ACTION_MODES, EnvConfig, Randomisation, RewardWeights
from .formation import WakeConfig, ell_state_from_aircraft
from .simulation import INFO_REWARD_KEYS, RESET_OPTIONS, InfoArrays, SimOutput, Simulation, separation_each

__all__ = ["Simulation", "SimOutput", "InfoArrays", "EnvConfig", "RewardWeights", "Randomisation", "ACTION_MODES",
           "WakeConfig", "ell_state_from_aircraft", "INFO_REWARD_KEYS", "RESET_OPTIONS", "separation_each"]
