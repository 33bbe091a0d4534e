"""Induced-wind sweeps in the thesis's style (the follower's effective induced wind as its
position relative to the leader varies), for the figures the chapter 5.4 validation sweeps
(:mod:`formation_env.plotting.wake_figures`) do not cover:

* Figs. 4.10, 4.11, 4.13 (section 4.2.4): two identical wings (b 1 m, AR 3, taper 0.8, sweep
  20 deg, dihedral 10 deg) at V 20 m/s, alpha 8 deg, for several numbers of horseshoes nseg, in
  Case A (both theta = 0) and Case B (both theta = 8 deg). Longitudinal (Fig. 4.10), lateral
  x = -2b, z = 0 (Fig. 4.11), vertical x = -b, y = b (Fig. 4.13). The Fig. 4.10 caption is cut off
  in the text we have; the sweep is drawn at y = b, z = 0 (assumed; labelled on the figure).
* Figs. 6.3-6.6 (section 6.3): two Aerosondes (Table 6.1), V 25 m/s, alpha = theta = 3 deg, wing
  only against wing + tailplane, rotational wind by Eq. 6.1: longitudinal y = b, z = b/2
  (Fig. 6.3; Fig. 6.4 with the tailplane at -5 deg incidence), lateral x = -2b, z = -0.1b
  (Fig. 6.5), vertical x = -2b, y = b (Fig. 6.6).

Positions are the follower's, relative to the leader, NED, in spans b of the leader; the wind is
in the follower's body axes (m/s, rad/s). Each ``figure_*`` returns ``(fig, data)`` where
``data`` holds the plotted numbers (JSON-serialisable).
"""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np

from ..geometry import LiftingSurface, Vehicle, aerosonde
from ..wake import FormationState, WakeModel
from . import no_offset

__all__ = ["section_4_2_4_wing", "effective_wind_sweep", "nseg_sweep_figure", "aerosonde_tailplane_figure",
           "NSEG_FIGURES", "AEROSONDE_FIGURES"]


def section_4_2_4_wing(nseg: int) -> Vehicle:
    """The wing of section 4.2.4: b 1 m, AR 3, taper 0.8, sweep 20 deg, dihedral 10 deg."""
    return Vehicle((LiftingSurface.from_degrees(span_m=1.0, aspect_ratio=3.0, taper=0.8, sweep_deg=20.0,
                                                dihedral_deg=10.0, nseg=int(nseg)),), name=f"sec_4_2_4_wing_n{nseg}")


def effective_wind_sweep(vehicle: Vehicle, offsets_b, airspeed: float, alpha_rad: float, theta_rad: float,
                         **model_kw) -> tuple[np.ndarray, np.ndarray]:
    """Follower's effective induced wind (P, 3) m/s and rotational wind (P, 3) rad/s, body axes,
    for follower offsets (P, 3) in spans (NED, relative to the leader); one batched evaluation."""
    b = vehicle.ref_span_m
    off = np.asarray(offsets_b, dtype=float)
    p = off.shape[0]
    pos = np.zeros((p, 2, 3))
    pos[:, 1] = off * b
    euler = np.zeros((p, 2, 3))
    euler[..., 1] = theta_rad
    model = WakeModel([vehicle, vehicle], **model_kw)
    sol = model.evaluate(FormationState(pos, euler, airspeed, alpha_rad, 0.0))
    return sol.wind_body[:, 1], sol.omega_body[:, 1]


def _offsets(variable: str, values, fixed: dict) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    cols = [v if c == variable else np.full_like(v, fixed[c]) for c in "xyz"]
    return np.stack(cols, -1)


# figure -> (variable, fixed coordinates in spans, full grid, caption)
NSEG_FIGURES = {
    "4.10": ("x", {"y": 1.0, "z": 0.0}, (-6.0, 2.0), "longitudinal spacing, y = b, z = 0 (assumed: caption cut off)"),
    "4.11": ("y", {"x": -2.0, "z": 0.0}, (-3.0, 3.0), "lateral spacing, x = -2b, z = 0"),
    "4.13": ("z", {"x": -1.0, "y": 1.0}, (-1.0, 1.0), "vertical spacing, x = -b, y = b"),
}
AEROSONDE_FIGURES = {
    "6.3": ("x", {"y": 1.0, "z": 0.5}, (-5.0, 2.0), 0.0, "longitudinal spacing, y = b, z = b/2"),
    "6.4": ("x", {"y": 1.0, "z": 0.5}, (-5.0, 2.0), -5.0, "longitudinal spacing, y = b, z = b/2, tailplane at -5 deg"),
    "6.5": ("y", {"x": -2.0, "z": -0.1}, (-2.0, 2.0), 0.0, "lateral spacing, x = -2b, z = -0.1b"),
    "6.6": ("z", {"x": -2.0, "y": 1.0}, (-1.0, 1.0), 0.0, "vertical spacing, x = -2b, y = b"),
}


def nseg_sweep_figure(figure: str, nsegs=(1, 2, 4, 6, 8, 10, 20), n_points: int = 121):
    """Fig. 4.10, 4.11 or 4.13: Vi components against the swept coordinate for each nseg, Case A
    (left column) and Case B (right column). Returns (fig, data)."""
    variable, fixed, (lo, hi), caption = NSEG_FIGURES[figure]
    grid = np.round(np.linspace(lo, hi, n_points), 6)
    off = _offsets(variable, grid, fixed)
    airspeed, alpha = 20.0, math.radians(8.0)
    cases = {"A": 0.0, "B": math.radians(8.0)}
    fig, axes = plt.subplots(3, 2, figsize=(10.0, 8.0), sharex=True, constrained_layout=True)
    data = {"figure": figure, "caption": caption, "variable": variable, "coordinate_b": grid.tolist(),
            "airspeed_mps": airspeed, "alpha_rad": alpha, "cases": {}}
    for col, (case, theta) in enumerate(cases.items()):
        data["cases"][case] = {"theta_rad": theta, "wind_body_mps": {}}
        for k, n in enumerate(nsegs):
            w, _ = effective_wind_sweep(section_4_2_4_wing(n), off, airspeed, alpha, theta)
            data["cases"][case]["wind_body_mps"][str(n)] = w.tolist()
            for r in range(3):
                axes[r, col].plot(grid, w[:, r], lw=1.0, color=plt.cm.viridis(k / max(1, len(nsegs) - 1)),
                                  label=f"nseg = {n}")
        axes[0, col].set_title(f"Case {case}: theta = {math.degrees(theta):g} deg")
        axes[-1, col].set_xlabel(f"{variable} / b")
        for r, lab in enumerate(("x", "y", "z")):
            axes[r, col].set_ylabel(f"Vi_{lab} (m/s)")
            axes[r, col].grid(alpha=0.3)
    axes[0, 1].legend(fontsize=7, ncol=2)
    fig.suptitle(f"Fig. {figure}: effective induced velocity on the follower (body axes) against {caption}; "
                 f"V {airspeed:g} m/s, alpha 8 deg", fontsize=10)
    return no_offset(fig), data


def aerosonde_tailplane_figure(figure: str, n_points: int = 141):
    """Fig. 6.3, 6.4, 6.5 or 6.6: Vi and omega_i on the follower Aerosonde, wing only against wing +
    tailplane (V 25 m/s, alpha = theta = 3 deg, rotational wind by Eq. 6.1). Returns (fig, data)."""
    variable, fixed, (lo, hi), incidence, caption = AEROSONDE_FIGURES[figure]
    grid = np.round(np.linspace(lo, hi, n_points), 6)
    off = _offsets(variable, grid, fixed)
    airspeed, alpha = 25.0, math.radians(3.0)
    configs = {"wing only": aerosonde(tailplane=False),
               "wing + tailplane": aerosonde(tailplane=True, tail_incidence_deg=incidence)}
    fig, axes = plt.subplots(2, 3, figsize=(12.0, 6.0), sharex=True, constrained_layout=True)
    data = {"figure": figure, "caption": caption, "variable": variable, "coordinate_b": grid.tolist(),
            "airspeed_mps": airspeed, "alpha_rad": alpha, "theta_rad": alpha, "tail_incidence_deg": incidence,
            "rotational": "eq6_1", "configs": {}}
    for (label, vehicle), ls in zip(configs.items(), ("-", "--")):
        w, om = effective_wind_sweep(vehicle, off, airspeed, alpha, alpha, rotational="eq6_1")
        data["configs"][label] = {"wind_body_mps": w.tolist(), "omega_body_rad_s": om.tolist()}
        for c in range(3):
            axes[0, c].plot(grid, w[:, c], ls, lw=1.2, label=label)
            axes[1, c].plot(grid, om[:, c], ls, lw=1.2, label=label)
    for c, lab in enumerate("xyz"):
        axes[0, c].set_ylabel(f"Vi_{lab} (m/s)")
        axes[1, c].set_ylabel(f"omega_i{lab} (rad/s)")
        axes[1, c].set_xlabel(f"{variable} / b")
        for r in range(2):
            axes[r, c].grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(f"Fig. {figure}: Aerosonde follower's effective induced wind (body axes) against {caption}; "
                 f"V 25 m/s, alpha = theta = 3 deg", fontsize=10)
    return no_offset(fig), data
