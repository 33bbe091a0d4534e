"""Lifting surfaces and vehicles: the planform description ELL meshes (thesis 4.3.3, Tables 5.1, 5.5, 6.1).

All angles are in radians and lengths in metres. A surface's own frame is body-like
(x forward, y starboard, z down) with its origin at the root quarter-chord point; it is placed
on its vehicle by ``position_m`` (body axes) and ``orientation_rad`` (3-2-1 Euler angles of the
surface frame relative to the body frame), so fins and canted surfaces need no special case.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["LiftingSurface", "Vehicle"]

_SPACINGS = ("linear", "cosine")


def _check_finite(owner: str, name: str, value) -> None:
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{owner}: {name} must be finite, got {value!r}")


@dataclass(frozen=True)
class LiftingSurface:
    """One flat lifting surface modelled by ``nseg`` 5-branch horseshoe vortices.

    Parameters
    ----------
    span_m:
        Tip-to-tip span b (for a single, unmirrored surface: root-to-tip length).
    aspect_ratio:
        b^2 / S with S the planform area of this surface. (The thesis's printed (2b)^2/S is a
        misprint: it does not reproduce Table 5.2.)
    taper:
        Tip chord / root chord; the chord varies linearly along the span; 0 gives a pointed tip.
    sweep_rad:
        Quarter-chord sweep (positive swept back); |sweep| < 90 deg.
    dihedral_rad:
        Dihedral of the quarter-chord line (positive tips up).
    incidence_rad:
        Root chord incidence relative to the surface's x axis (positive leading edge up).
    twist_rad:
        Tip incidence minus root incidence (washout negative), linear along the span.
    symmetric:
        True: mirrored about its own root (a wing, a tailplane); False: a single panel from the
        root outwards along +y of its frame (a fin, when rolled by 90 deg or given 90 deg dihedral).
    nseg:
        Number of horseshoe vortices.
    spacing:
        "linear" (reproduces the thesis tables) or "cosine" (clustered at the tips).
    position_m:
        Root quarter-chord point in the vehicle's body axes.
    orientation_rad:
        3-2-1 Euler angles (phi, theta, psi) of the surface frame relative to the body frame.
    name:
        Label used in plots and reports.
    """

    span_m: float
    aspect_ratio: float
    taper: float = 1.0
    sweep_rad: float = 0.0
    dihedral_rad: float = 0.0
    incidence_rad: float = 0.0
    twist_rad: float = 0.0
    symmetric: bool = True
    nseg: int = 10
    spacing: str = "linear"
    position_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    orientation_rad: tuple[float, float, float] = (0.0, 0.0, 0.0)
    name: str = "wing"

    def __post_init__(self) -> None:
        owner = f"LiftingSurface {self.name!r}"
        for fname in ("span_m", "aspect_ratio", "taper", "sweep_rad", "dihedral_rad", "incidence_rad", "twist_rad"):
            value = getattr(self, fname)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
                raise ValueError(f"{owner}: {fname} must be a number, got {value!r}")
            _check_finite(owner, fname, value)
            object.__setattr__(self, fname, float(value))
        if self.span_m <= 0.0:
            raise ValueError(f"{owner}: span_m must be > 0, got {self.span_m!r}")
        if self.aspect_ratio <= 0.0:
            raise ValueError(f"{owner}: aspect_ratio must be > 0, got {self.aspect_ratio!r}")
        if self.taper < 0.0:
            raise ValueError(f"{owner}: taper must be >= 0, got {self.taper!r}")
        if abs(self.sweep_rad) >= 0.5 * math.pi:
            raise ValueError(f"{owner}: |sweep_rad| must be < pi/2 (90 deg), got {self.sweep_rad!r}")
        if abs(self.dihedral_rad) > 0.5 * math.pi:
            raise ValueError(f"{owner}: |dihedral_rad| must be <= pi/2, got {self.dihedral_rad!r}")
        if isinstance(self.nseg, bool) or not isinstance(self.nseg, (int, np.integer)) or self.nseg < 1:
            raise ValueError(f"{owner}: nseg must be an integer >= 1, got {self.nseg!r}")
        object.__setattr__(self, "nseg", int(self.nseg))
        if self.spacing not in _SPACINGS:
            raise ValueError(f"{owner}: spacing must be one of {_SPACINGS}, got {self.spacing!r}")
        if not isinstance(self.symmetric, (bool, np.bool_)):
            raise ValueError(f"{owner}: symmetric must be a bool, got {self.symmetric!r}")
        for fname in ("position_m", "orientation_rad"):
            value = np.asarray(getattr(self, fname), dtype=float)
            if value.shape != (3,):
                raise ValueError(f"{owner}: {fname} must have 3 components, got {getattr(self, fname)!r}")
            _check_finite(owner, fname, value)
            object.__setattr__(self, fname, tuple(float(v) for v in value))

    @classmethod
    def from_degrees(cls, *, sweep_deg: float = 0.0, dihedral_deg: float = 0.0, incidence_deg: float = 0.0,
                     twist_deg: float = 0.0, orientation_deg=(0.0, 0.0, 0.0), **kwargs) -> "LiftingSurface":
        """Build a surface from angles in degrees (as the thesis tables print them)."""
        return cls(
            sweep_rad=math.radians(sweep_deg),
            dihedral_rad=math.radians(dihedral_deg),
            incidence_rad=math.radians(incidence_deg),
            twist_rad=math.radians(twist_deg),
            orientation_rad=tuple(math.radians(a) for a in orientation_deg),
            **kwargs,
        )

    @property
    def area_m2(self) -> float:
        """Planform area S = b^2 / AR."""
        return self.span_m**2 / self.aspect_ratio

    @property
    def root_chord_m(self) -> float:
        """Root chord such that the linear chord law gives area S: c_root = 2 S / (b (1 + taper))."""
        return 2.0 * self.area_m2 / (self.span_m * (1.0 + self.taper))

    @property
    def mean_aerodynamic_chord_m(self) -> float:
        """MAC of a linearly tapered planform: (2/3) c_root (1 + t + t^2) / (1 + t)."""
        t = self.taper
        return (2.0 / 3.0) * self.root_chord_m * (1.0 + t + t * t) / (1.0 + t)


@dataclass(frozen=True)
class Vehicle:
    """A rigid set of lifting surfaces; its body origin is the reference point for poses and moments.

    The first surface is the reference surface for force and moment coefficients unless
    ``reference_area_m2`` / ``reference_span_m`` / ``reference_chord_m`` are given.
    """

    surfaces: tuple[LiftingSurface, ...]
    name: str = "vehicle"
    reference_area_m2: float | None = None
    reference_span_m: float | None = None
    reference_chord_m: float | None = None

    def __post_init__(self) -> None:
        surfaces = tuple(self.surfaces) if not isinstance(self.surfaces, LiftingSurface) else (self.surfaces,)
        if not surfaces:
            raise ValueError(f"Vehicle {self.name!r}: surfaces must contain at least one LiftingSurface")
        for s in surfaces:
            if not isinstance(s, LiftingSurface):
                raise ValueError(f"Vehicle {self.name!r}: surfaces must be LiftingSurface objects, got {s!r}")
        object.__setattr__(self, "surfaces", surfaces)
        for fname in ("reference_area_m2", "reference_span_m", "reference_chord_m"):
            value = getattr(self, fname)
            if value is not None:
                _check_finite(f"Vehicle {self.name!r}", fname, value)
                if value <= 0:
                    raise ValueError(f"Vehicle {self.name!r}: {fname} must be > 0, got {value!r}")

    @property
    def nseg(self) -> int:
        """Total number of horseshoe vortices on the vehicle."""
        return sum(s.nseg for s in self.surfaces)

    @property
    def ref_area_m2(self) -> float:
        return self.reference_area_m2 if self.reference_area_m2 is not None else self.surfaces[0].area_m2

    @property
    def ref_span_m(self) -> float:
        return self.reference_span_m if self.reference_span_m is not None else self.surfaces[0].span_m

    @property
    def ref_chord_m(self) -> float:
        return self.reference_chord_m if self.reference_chord_m is not None else self.surfaces[0].mean_aerodynamic_chord_m
