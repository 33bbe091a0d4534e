"""Geometry: lifting surfaces, vehicles, presets and their body-axis horseshoe meshes."""

from .mesh import SurfaceMesh, VehicleMesh, mesh_surface, mesh_vehicle, span_stations
from .presets import PRESETS, aerosonde, delta_wing, verification_wing
from .surface import LiftingSurface, Vehicle

__all__ = [
    "LiftingSurface", "Vehicle", "SurfaceMesh", "VehicleMesh", "mesh_surface", "mesh_vehicle",
    "span_stations", "PRESETS", "aerosonde", "delta_wing", "verification_wing",
]
