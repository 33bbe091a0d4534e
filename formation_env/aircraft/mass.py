"""Mass, CG and inertia as functions of the fuel on board (AeroSim Aircraft Inertia block)."""

from __future__ import annotations

import numpy as np

from .params import AerosondeParams

__all__ = ["mass_properties"]


def mass_properties(fuel_kg, params: AerosondeParams):
    """Return ``(mass (B,), cg_body (B, 3), inertia (B, 4) = [Jx, Jy, Jz, Jxz])``.

    CG and inertia are interpolated linearly in mass between the empty and gross values; the
    fuel is clipped to [0, capacity] as the AeroSim fuel integrator is.
    """
    fuel = np.clip(np.asarray(fuel_kg, dtype=float), 0.0, params.fuel_capacity)
    frac = (fuel / params.fuel_capacity)[..., None]
    mass = params.mass_empty + fuel
    cg = params.cg_empty_body + frac * (params.cg_gross_body - params.cg_empty_body)
    inertia = params.inertia_empty + frac * (params.inertia_gross - params.inertia_empty)
    return mass, cg, inertia
