"""Formation simulation: ELL wake coupled to the Aerosonde dynamics, batched (no RL concepts)."""

from .formation import FormationSimulator, StepResult, WakeConfig, ell_state_from_aircraft

__all__ = ["FormationSimulator", "StepResult", "WakeConfig", "ell_state_from_aircraft"]
