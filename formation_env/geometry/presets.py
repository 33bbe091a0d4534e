"""Vehicles used in the thesis: the verification wing (Table 5.1), the validation delta wing
(Table 5.5) and the Aerosonde (Table 6.1)."""

from __future__ import annotations

import math

from ..constants import AEROSONDE_SPAN_M
from .surface import LiftingSurface, Vehicle

__all__ = ["verification_wing", "delta_wing", "aerosonde", "AEROSONDE_TAIL_ARM_M", "PRESETS"]

# Distance from the wing's root quarter-chord point to the tailplane's, along body -x (m).
# Table 6.1 gives the surfaces but not their relative position; this is the Aerosonde's wing-to-
# tail distance from its published three-view (about 1.4 m overall length, tail at the boom end).
AEROSONDE_TAIL_ARM_M = 0.85


def verification_wing(nseg: int = 5, spacing: str = "linear") -> Vehicle:
    """Table 5.1: rectangular wing, b = 1 m, AR = 6, no sweep/dihedral/twist, 5 horseshoes."""
    wing = LiftingSurface(span_m=1.0, aspect_ratio=6.0, taper=1.0, nseg=nseg, spacing=spacing, name="wing")
    return Vehicle(surfaces=(wing,), name="verification_wing")


def delta_wing(nseg: int = 10, spacing: str = "linear") -> Vehicle:
    """Table 5.5: the 1/13-scale Lockheed tailless model as ELL sees it (65 deg delta approximated
    by b = 0.8796 m, AR = 1.7394, taper 0, quarter-chord sweep 58 deg)."""
    wing = LiftingSurface(
        span_m=0.8796, aspect_ratio=1.7394, taper=0.0, sweep_rad=math.radians(58.0),
        nseg=nseg, spacing=spacing, name="delta",
    )
    return Vehicle(surfaces=(wing,), name="delta_wing")


def aerosonde(nseg: int = 10, tailplane: bool = False, tail_arm_m: float = AEROSONDE_TAIL_ARM_M,
              tail_incidence_deg: float = 0.0, spacing: str = "linear") -> Vehicle:
    """Table 6.1: the Aerosonde's wing (b 2.9 m, AR 15, taper 0.4, sweep 4 deg, dihedral 3 deg)
    and, optionally, its inverted-V tail (b 1.1 m, AR 7.8, dihedral -43 deg).

    The body origin is the wing's root quarter-chord point (the thesis's wing origin), so ELL
    poses are given at that point.
    """
    wing = LiftingSurface.from_degrees(
        span_m=AEROSONDE_SPAN_M, aspect_ratio=15.0, taper=0.4, sweep_deg=4.0, dihedral_deg=3.0,
        nseg=nseg, spacing=spacing, name="wing",
    )
    surfaces = [wing]
    if tailplane:
        surfaces.append(
            LiftingSurface.from_degrees(
                span_m=1.1, aspect_ratio=7.8, taper=1.0, dihedral_deg=-43.0, incidence_deg=tail_incidence_deg,
                nseg=nseg, spacing=spacing, position_m=(-tail_arm_m, 0.0, 0.0), name="tailplane",
            )
        )
    return Vehicle(surfaces=tuple(surfaces), name="aerosonde")


PRESETS = {"verification_wing": verification_wing, "delta_wing": delta_wing, "aerosonde": aerosonde}
