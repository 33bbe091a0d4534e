"""Meshing of lifting surfaces into 5-branch horseshoe lattices (thesis 4.3.5), in body axes.

The mesh depends only on the geometry, so it is computed once per vehicle make-up; per time
step the wake solver only rotates and translates it (see ``formation_env.wake``).

For one surface with n horseshoes there are n + 1 knots on the quarter-chord line (X1) and
n + 1 matching three-quarter-chord points (X3 = X1 + c/2 along the local chord). Horseshoe k runs
infinity -> X3[k] -> X1[k] -> X1[k+1] -> X3[k+1] -> infinity, the trailing legs parallel to the
vehicle's air-relative velocity.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..frames import dcm_ned_to_body
from .surface import LiftingSurface, Vehicle

__all__ = ["SurfaceMesh", "VehicleMesh", "mesh_surface", "mesh_vehicle", "span_stations"]


def span_stations(surface: LiftingSurface) -> np.ndarray:
    """Signed spanwise stations s of the n + 1 knots (m), port to starboard (Eq. 4.11).

    Symmetric surfaces span [-b/2, b/2]; single surfaces [0, b].
    """
    n, b = surface.nseg, surface.span_m
    k = np.arange(n + 1)
    if surface.spacing == "linear":
        u = k / n
    else:  # cosine: clustered at both ends of the lifting line
        u = 0.5 * (1.0 - np.cos(np.pi * k / n))
    return (u - 0.5) * b if surface.symmetric else u * b


@dataclass(frozen=True)
class SurfaceMesh:
    """Body-axis lattice of one surface (metres; body x forward, y starboard, z down)."""

    x1: np.ndarray  # (n+1, 3) quarter-chord knots
    x3: np.ndarray  # (n+1, 3) three-quarter-chord knots
    control: np.ndarray  # (n, 3) control points (mid X3 segment)
    quarter_chord: np.ndarray  # (n, 3) quarter-chord midpoints (mid X1 segment)
    normal: np.ndarray  # (n, 3) unit panel normals (lift side = -z for a level wing)
    origin: np.ndarray  # (3,) root quarter-chord point
    chord: np.ndarray  # (n+1,) chord at the knots


def mesh_surface(surface: LiftingSurface) -> SurfaceMesh:
    """Mesh one surface in its vehicle's body axes (Eqs. 4.11-4.22).

    The thesis works in "modified body axes" (x aft, y starboard, z up); here the same formulas
    are written directly in body axes (x forward, z down), i.e. x and z change sign.
    """
    s = span_stations(surface)
    b = surface.span_m
    half = 0.5 * b if surface.symmetric else b
    eta = np.abs(s) / half  # 0 at the root, 1 at the tips
    sweep, dih = surface.sweep_rad, surface.dihedral_rad

    # Quarter-chord knots (Eq. 4.11): swept aft, dihedral tips up (-z).
    x1 = np.stack([-np.abs(s) * np.tan(sweep), s * np.cos(dih), -np.abs(s) * np.sin(dih)], axis=-1)

    # Linear chord law from the root chord to taper * root chord at the tips (the intended Eq. 4.12).
    chord = surface.root_chord_m * (1.0 + eta * (surface.taper - 1.0))

    # Local incidence: root incidence plus twist growing linearly to the tips (Eq. 4.15).
    inc = surface.incidence_rad + surface.twist_rad * eta
    # Chord direction: body -x (aft) tilted trailing-edge-down by the local incidence, about the
    # dihedral-rotated spanwise axis. The local "up" of the dihedral plane is
    # (0, -sign(s) sin(dih), -cos(dih)) in body axes. Thesis Eq. 4.17 prints the opposite sign on
    # the y term, which matters only with both incidence and dihedral; this is the rigid rotation.
    side = np.where(s >= 0.0, 1.0, -1.0)
    up = np.stack([np.zeros_like(s), -side * np.sin(dih), -np.full_like(s, np.cos(dih))], axis=-1)
    chord_dir = np.stack([-np.cos(inc), np.zeros_like(s), np.zeros_like(s)], axis=-1) - np.sin(inc)[:, None] * up
    x3 = x1 + 0.5 * chord[:, None] * chord_dir

    control = 0.5 * (x3[:-1] + x3[1:])
    quarter_chord = 0.5 * (x1[:-1] + x1[1:])

    # Panel normal n = a_m x d (Eq. 4.22), a_m the chord direction at the panel middle, d the
    # lifting-line direction. In body axes, with a_m pointing aft, (a_m x d) points to -z (lift side).
    d = x1[1:] - x1[:-1]
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    s_mid = 0.5 * (s[:-1] + s[1:])
    inc_mid = surface.incidence_rad + surface.twist_rad * (np.abs(s_mid) / half)
    side_m = np.where(s_mid >= 0.0, 1.0, -1.0)
    up_m = np.stack([np.zeros_like(s_mid), -side_m * np.sin(dih), -np.full_like(s_mid, np.cos(dih))], axis=-1)
    a_m = np.stack([-np.cos(inc_mid), np.zeros_like(s_mid), np.zeros_like(s_mid)], axis=-1) - np.sin(inc_mid)[:, None] * up_m
    normal = np.cross(a_m, d)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)

    # Place the surface on its vehicle: surface frame -> body frame.
    rot = dcm_ned_to_body(np.asarray(surface.orientation_rad)).T  # surface-to-body
    pos = np.asarray(surface.position_m, dtype=float)

    def place(points: np.ndarray) -> np.ndarray:
        return points @ rot.T + pos

    return SurfaceMesh(
        x1=place(x1),
        x3=place(x3),
        control=place(control),
        quarter_chord=place(quarter_chord),
        normal=normal @ rot.T,
        origin=pos.copy(),
        chord=chord,
    )


@dataclass(frozen=True)
class VehicleMesh:
    """The body-axis meshes of a vehicle's surfaces, in surface order."""

    vehicle: Vehicle
    surfaces: tuple[SurfaceMesh, ...]


def mesh_vehicle(vehicle: Vehicle) -> VehicleMesh:
    """Mesh every surface of ``vehicle`` in its body axes."""
    return VehicleMesh(vehicle=vehicle, surfaces=tuple(mesh_surface(s) for s in vehicle.surfaces))
