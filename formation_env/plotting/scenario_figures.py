"""Scenario figures in the thesis's chapter 6 style (strip charts against time, one line per
vehicle and run): position parameters and errors, air data, Euler angles, controls, induced wind,
and the ground track. Input: runs from :func:`formation_env.runs.runner.run_scenario` (their ``time`` and
``h`` histories); this module only reads arrays."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from . import no_offset, save_figure, vehicle_label

__all__ = ["scenario_figures"]

_STYLES = {"wake_on": "-", "wake_off": "--"}


def _lines(runs: dict):
    for label, run in runs.items():
        v = run.h["airspeed"].shape[1]
        for i in range(v):
            name = vehicle_label(i) + (f" ({label.replace('_', ' ')})" if len(runs) > 1 else "")
            yield run, i, name, _STYLES.get(label, "-")


def _strip(runs: dict, title: str, panels) -> plt.Figure:
    fig, axes = plt.subplots(len(panels), 1, figsize=(8.0, 1.9 * len(panels)), sharex=True, constrained_layout=True)
    axes = np.atleast_1d(axes)
    for ax, (ylabel, fn) in zip(axes, panels):
        for run, i, name, ls in _lines(runs):
            ax.plot(run.time, fn(run.h, i), ls, lw=1.0, label=name)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
    axes[0].set_title(title)
    axes[0].legend(fontsize=7, loc="best")
    axes[-1].set_xlabel("t (s)")
    return no_offset(fig)


def scenario_figures(runs: dict, out_dir, *, overwrite: bool = False) -> list[Path]:
    """Write the figures of ``runs`` ({label: ScenarioRun}) into ``out_dir``; returns the paths."""
    out = Path(out_dir)
    name = next(iter(runs.values())).scenario.name
    deg = np.rad2deg
    figs = {
        "positions": _strip(runs, f"{name}: position parameters", [
            ("dx (m)", lambda h, i: h["along_track"][:, i]),
            ("dy (m)", lambda h, i: h["off_track"][:, i]),
            ("h (m)", lambda h, i: -h["position_ned"][:, i, 2]),
            ("dh (m)", lambda h, i: h["altitude_error"][:, i]),
            ("chi (deg)", lambda h, i: deg(h["track_angle"][:, i]))]),
        "air_data": _strip(runs, f"{name}: air data", [
            ("V (m/s)", lambda h, i: h["airspeed"][:, i]),
            ("alpha (deg)", lambda h, i: deg(h["alpha"][:, i])),
            ("beta (deg)", lambda h, i: deg(h["beta"][:, i]))]),
        "euler": _strip(runs, f"{name}: Euler angles", [
            ("phi (deg)", lambda h, i: deg(h["euler"][:, i, 0])),
            ("theta (deg)", lambda h, i: deg(h["euler"][:, i, 1])),
            ("psi (deg)", lambda h, i: deg(h["euler"][:, i, 2]))]),
        "controls": _strip(runs, f"{name}: control settings", [
            ("elevator (deg)", lambda h, i: deg(h["controls"][:, i, 0])),
            ("aileron (deg)", lambda h, i: deg(h["controls"][:, i, 1])),
            ("rudder (deg)", lambda h, i: deg(h["controls"][:, i, 2])),
            ("throttle (-)", lambda h, i: h["controls"][:, i, 3])]),
        "induced_wind": _strip(runs, f"{name}: wind (ELL induced + ambient), NED", [
            ("Vi_x (m/s)", lambda h, i: h["induced_wind_ned"][:, i, 0]),
            ("Vi_y (m/s)", lambda h, i: h["induced_wind_ned"][:, i, 1]),
            ("Vi_z (m/s)", lambda h, i: h["induced_wind_ned"][:, i, 2]),
            ("ambient |w| (m/s)", lambda h, i: np.linalg.norm(h["ambient_wind_ned"][:, i], axis=1))]),
    }
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10.0, 4.0), constrained_layout=True)
    for run, i, lbl, ls in _lines(runs):
        p = run.h["position_ned"][:, i]
        a1.plot(p[:, 1], p[:, 0], ls, lw=1.0, label=lbl)
        a2.plot(p[:, 0], -p[:, 2], ls, lw=1.0, label=lbl)
        pd = run.h["position_demand_ned"][:, i]
        a1.plot(pd[:, 1], pd[:, 0], ":", lw=0.8, color="0.5")
    a1.set_xlabel("east (m)"); a1.set_ylabel("north (m)"); a1.set_title(f"{name}: ground track (dotted: demanded)")
    a2.set_xlabel("north (m)"); a2.set_ylabel("altitude (m)"); a2.set_title("side view")
    for a in (a1, a2):
        a.grid(True, alpha=0.3)
    a1.legend(fontsize=7)
    figs["trajectory"] = no_offset(fig)
    return [save_figure(f, out / f"{name}_{key}.png", overwrite=overwrite) for key, f in figs.items()]
