"""Aerosonde configuration data (AeroSim ``aerosondeconfig.m``, rev 1.0, 2002).

Every number here is from section 13 of ``shared/reference/aerosonde_aerosim_model.md``.
Body axes: x nose, y right wing, z down; the airframe origin is the propeller hub.
Aerodynamic derivatives are per radian, deflections in radians.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["AerosondeParams", "AEROSONDE"]


def _ro(values) -> np.ndarray:
    """Read-only float array, so the frozen dataclass cannot be mutated through its tables."""
    arr = np.array(values, dtype=float)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class AerosondeParams:
    # --- aerodynamic reference -------------------------------------------------------------
    r_ac_body: np.ndarray = field(default_factory=lambda: _ro([0.1425, 0.0, 0.0]))
    mac: float = 0.189941
    span: float = 2.8956
    area: float = 0.55
    va_bounds: tuple[float, float] = (15.0, 50.0)
    beta_bounds: tuple[float, float] = (-0.5, 0.5)
    alpha_bounds: tuple[float, float] = (-0.1, 0.3)
    # --- lift --------------------------------------------------------------------------------
    CL0: float = 0.23
    CLa: float = 5.6106
    CLdf: float = 0.74
    CLde: float = 0.13
    CLalphadot: float = 1.9724
    CLq: float = 7.9543
    CLM: float = 0.0
    # --- drag --------------------------------------------------------------------------------
    CLmind: float = 0.23
    CDmin: float = 0.0434
    CDdf: float = 0.1467
    CDde: float = 0.0135
    CDda: float = 0.0302
    CDdr: float = 0.0303
    CDM: float = 0.0
    osw: float = 0.75
    # --- side force --------------------------------------------------------------------------
    CYbeta: float = -0.83
    CYda: float = -0.075
    CYdr: float = 0.1914
    CYp: float = 0.0
    CYr: float = 0.0
    # --- pitch -------------------------------------------------------------------------------
    Cm0: float = 0.135
    Cma: float = -2.7397
    Cmdf: float = 0.0467
    Cmde: float = -0.9918
    Cmalphadot: float = -10.3796
    Cmq: float = -38.2067
    CmM: float = 0.0
    # --- roll --------------------------------------------------------------------------------
    Clbeta: float = -0.13
    Clda: float = -0.1695
    Cldr: float = 0.0024
    Clp: float = -0.5051
    Clr: float = 0.2519
    # --- yaw ---------------------------------------------------------------------------------
    Cnbeta: float = 0.0726
    Cnda: float = 0.0108
    Cndr: float = -0.0693
    Cnp: float = -0.069
    Cnr: float = -0.0946
    # --- propeller ---------------------------------------------------------------------------
    r_hub_body: np.ndarray = field(default_factory=lambda: _ro([0.0, 0.0, 0.0]))
    prop_radius: float = 0.254
    prop_inertia: float = 0.002
    prop_J: np.ndarray = field(
        default_factory=lambda: _ro(
            [-1, 0, 0.1, 0.2, 0.3, 0.35, 0.4, 0.45, 0.5, 0.6, 0.7, 0.8, 0.9, 1, 1.2, 2]
        )
    )
    prop_CT: np.ndarray = field(
        default_factory=lambda: _ro(
            [0.0492, 0.0286, 0.0266, 0.0232, 0.0343, 0.034, 0.0372, 0.0314, 0.0254, 0.0117,
             -0.005, -0.0156, -0.0203, -0.0295, -0.04, -0.1115]
        )
    )
    prop_CP: np.ndarray = field(
        default_factory=lambda: _ro(
            [0.0199, 0.0207, 0.0191, 0.0169, 0.0217, 0.0223, 0.0254, 0.0235, 0.0212, 0.0146,
             0.0038, -0.005, -0.0097, -0.018, -0.0273, -0.0737]
        )
    )
    # --- engine ------------------------------------------------------------------------------
    engine_inertia: float = 0.0001
    T_sl: float = 291.15  # K; the power correction is sqrt(T_sl / T)
    engine_rpm: np.ndarray = field(
        default_factory=lambda: _ro([1500, 2100, 2800, 3500, 4500, 5100, 5500, 6000, 7000])
    )
    engine_map_kpa: np.ndarray = field(
        default_factory=lambda: _ro([60, 70, 80, 90, 92, 94, 96, 98, 100])
    )
    # rows: RPM, columns: MAP
    engine_power_w: np.ndarray = field(
        default_factory=lambda: _ro(
            [
                [18.85, 47.12, 65.97, 67.54, 69.12, 67.54, 67.54, 69.12, 86.39],
                [59.38, 98.96, 127.55, 149.54, 151.74, 160.54, 178.13, 200.12, 224.31],
                [93.83, 149.54, 187.66, 237.5, 249.23, 255.1, 307.88, 366.52, 398.77],
                [109.96, 161.27, 245.57, 307.88, 326.2, 351.86, 421.5, 491.14, 531.45],
                [164.93, 245.04, 339.29, 438.25, 447.68, 494.8, 565.49, 673.87, 772.83],
                [181.58, 245.67, 389.87, 496.69, 528.73, 571.46, 662.25, 822.47, 993.37],
                [184.31, 293.74, 403.17, 535.64, 570.2, 622.04, 748.75, 956.09, 1059.76],
                [163.36, 276.46, 420.97, 565.49, 609.47, 691.15, 860.8, 1130.97, 1193.81],
                [124.62, 249.23, 417.83, 586.43, 645.07, 762.36, 996.93, 1246.17, 1429.42],
            ]
        )
    )
    engine_fuel_flow_g_per_h: np.ndarray = field(
        default_factory=lambda: _ro(
            [
                [31, 32, 46, 53, 55, 57, 65, 73, 82],
                [40, 44, 54, 69, 74, 80, 92, 103, 111],
                [50, 63, 69, 92, 95, 98, 126, 145, 153],
                [66, 75, 87, 110, 117, 127, 150, 175, 190],
                [83, 98, 115, 143, 148, 162, 191, 232, 246],
                [93, 102, 130, 159, 167, 182, 208, 260, 310],
                [100, 118, 137, 169, 178, 190, 232, 287, 313],
                [104, 126, 151, 184, 191, 206, 253, 326, 337],
                [123, 144, 174, 210, 217, 244, 321, 400, 408],
            ]
        )
    )
    # --- mass and inertia --------------------------------------------------------------------
    mass_empty: float = 8.5
    mass_gross: float = 13.5
    cg_empty_body: np.ndarray = field(default_factory=lambda: _ro([0.156, 0.0, 0.079]))
    cg_gross_body: np.ndarray = field(default_factory=lambda: _ro([0.159, 0.0, 0.090]))
    # [Jx, Jy, Jz, Jxz], Jxz a positive product of inertia (Stevens & Lewis tensor convention)
    inertia_empty: np.ndarray = field(default_factory=lambda: _ro([0.7795, 1.122, 1.752, 0.1211]))
    inertia_gross: np.ndarray = field(default_factory=lambda: _ro([0.8244, 1.135, 1.759, 0.1204]))

    def __post_init__(self) -> None:
        for name in ("mac", "span", "area", "osw", "prop_radius", "prop_inertia", "engine_inertia",
                     "T_sl", "mass_empty"):
            value = getattr(self, name)
            if not np.isfinite(value) or value <= 0.0:
                raise ValueError(f"AerosondeParams.{name} must be positive and finite, got {value!r}")
        if not self.mass_gross > self.mass_empty:
            raise ValueError("AerosondeParams.mass_gross must exceed mass_empty")
        for name in ("va_bounds", "beta_bounds", "alpha_bounds"):
            lo, hi = getattr(self, name)
            if not lo < hi:
                raise ValueError(f"AerosondeParams.{name} must be (low, high) with low < high")
        if self.va_bounds[0] <= 0.0:
            raise ValueError("AerosondeParams.va_bounds must be positive (J and c/2V divide by Va)")
        for name in ("r_ac_body", "r_hub_body", "cg_empty_body", "cg_gross_body"):
            object.__setattr__(self, name, _ro(getattr(self, name)))
            if getattr(self, name).shape != (3,):
                raise ValueError(f"AerosondeParams.{name} must have shape (3,)")
        for name in ("inertia_empty", "inertia_gross"):
            object.__setattr__(self, name, _ro(getattr(self, name)))
            if getattr(self, name).shape != (4,):
                raise ValueError(f"AerosondeParams.{name} must be [Jx, Jy, Jz, Jxz]")
        for name in ("prop_J", "prop_CT", "prop_CP", "engine_rpm", "engine_map_kpa",
                     "engine_power_w", "engine_fuel_flow_g_per_h"):
            object.__setattr__(self, name, _ro(getattr(self, name)))
        if not (self.prop_J.shape == self.prop_CT.shape == self.prop_CP.shape):
            raise ValueError("AerosondeParams.prop_J, prop_CT and prop_CP must have equal shapes")
        if np.any(np.diff(self.prop_J) <= 0):
            raise ValueError("AerosondeParams.prop_J must be strictly increasing")
        shape = (self.engine_rpm.size, self.engine_map_kpa.size)
        for name in ("engine_power_w", "engine_fuel_flow_g_per_h"):
            if getattr(self, name).shape != shape:
                raise ValueError(f"AerosondeParams.{name} must have shape {shape} (RPM rows, MAP columns)")
        if np.any(np.diff(self.engine_rpm) <= 0) or np.any(np.diff(self.engine_map_kpa) <= 0):
            raise ValueError("AerosondeParams.engine_rpm and engine_map_kpa must be strictly increasing")

    @property
    def aspect_ratio(self) -> float:
        return self.span**2 / self.area

    @property
    def fuel_capacity(self) -> float:
        return self.mass_gross - self.mass_empty

    @property
    def map_min_kpa(self) -> float:
        """Manifold pressure at closed throttle: the first MAP breakpoint (AeroSim Intake block)."""
        return float(self.engine_map_kpa[0])

    @property
    def shaft_inertia(self) -> float:
        return self.engine_inertia + self.prop_inertia


AEROSONDE = AerosondeParams()
