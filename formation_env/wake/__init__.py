"""ELL wake model: kernels, joint solve, field velocity, effective wind and loads."""

from .model import CORES, WakeModel, WakeSolution
from .state import FormationState

__all__ = ["WakeModel", "WakeSolution", "FormationState", "CORES"]
