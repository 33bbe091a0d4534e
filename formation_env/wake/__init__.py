"""ELL wake model: kernels, joint solve, field velocity, effective wind and loads."""

from .model import CORES, WakeModel, WakeSolution
from .state import FormationState

__all__ = ["WakeModel", "WakeSolution", "FormationState", "CORES"]

from .loads import VehicleLoads, formation_benefit, isolated_loads, vehicle_loads  # noqa: E402

__all__ += ["VehicleLoads", "vehicle_loads", "isolated_loads", "formation_benefit"]
