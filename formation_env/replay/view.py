"""Shared drawing primitives for a formation: each UAV as a wing, fuselage and tail, and its two
wing-tip trailing legs (the ELL wake) drawn a few spans downstream along its air velocity.

Used by the environments' ``render()`` (2D top/side views, :func:`draw_formation`), the episode
GIF (:mod:`formation_env.replay.animation`) and the 3D trajectory figure
(:mod:`formation_env.plotting.trajectory3d`) (3D view, :func:`draw_formation_3d`).

This module never selects a matplotlib backend (the caller does: Agg for files, an interactive
one for ``render_mode="human"``); it only draws on the axes it is given.

Frames: positions NED (m), the 3D view plots (east, north, altitude).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..frames import dcm_body_to_ned_from_quaternion, dcm_ned_to_body

__all__ = ["SPAN_M", "LEG_LENGTH_M", "FormationGeometry", "formation_geometry", "geometry_from_state",
           "geometry_from_euler", "draw_formation", "draw_formation_3d", "vehicle_colour", "figure_to_rgb"]

from ..constants import AEROSONDE_SPAN_M as SPAN_M  # noqa: E402  Aerosonde span (Table 6.1)
LEG_LENGTH_M = 4 * SPAN_M  # drawn length of the trailing legs
_FUSELAGE_M = (0.9, -1.2)  # nose and tail stations along body x, m (drawing only)


def vehicle_colour(i: int) -> str:
    return f"C{i % 10}"


@dataclass(frozen=True)
class FormationGeometry:
    """What is drawn for V vehicles, NED metres: ``position`` (V, 3), ``tips`` (V, 2, 3) port and
    starboard wing tips, ``nose``/``tail`` (V, 3) fuselage ends, ``legs`` (V, 2, 2, 3) the two
    trailing legs as (start, end) segments from the tips downstream along the air velocity."""

    position: np.ndarray
    tips: np.ndarray
    nose: np.ndarray
    tail: np.ndarray
    legs: np.ndarray


def formation_geometry(position_ned, dcm_body_to_ned, velocity_ned, wind_ned=None, *, span_m: float = SPAN_M,
                       leg_length_m: float = LEG_LENGTH_M) -> FormationGeometry:
    """Geometry of V vehicles from position (V, 3), body->NED DCMs (V, 3, 3), ground velocity
    (V, 3) and the wind (V, 3) or None (the legs trail along the air velocity, ground - wind)."""
    pos = np.asarray(position_ned, dtype=float).reshape(-1, 3)
    r = np.asarray(dcm_body_to_ned, dtype=float).reshape(-1, 3, 3)
    vel = np.asarray(velocity_ned, dtype=float).reshape(-1, 3)
    air = vel - (0.0 if wind_ned is None else np.asarray(wind_ned, dtype=float).reshape(-1, 3))
    half = np.array([[0.0, -span_m / 2, 0.0], [0.0, span_m / 2, 0.0]])
    tips = pos[:, None, :] + np.einsum("vij,kj->vki", r, half)
    nose = pos + r[:, :, 0] * _FUSELAGE_M[0]
    tail = pos + r[:, :, 0] * _FUSELAGE_M[1]
    speed = np.maximum(np.linalg.norm(air, axis=1, keepdims=True), 1e-9)
    back = -air / speed * leg_length_m
    legs = np.stack([tips, tips + back[:, None, :]], axis=2)
    return FormationGeometry(pos, tips, nose, tail, legs)


def geometry_from_state(state, wind_ned=None, **kw) -> FormationGeometry:
    """From aircraft states (V, 16) (cols 0-2 body velocity, 6-9 quaternion, 10-12 NED position)."""
    s = np.asarray(state, dtype=float).reshape(-1, 16)
    r = dcm_body_to_ned_from_quaternion(s[:, 6:10])
    vel = np.einsum("vij,vj->vi", r, s[:, 0:3])
    return formation_geometry(s[:, 10:13], r, vel, wind_ned, **kw)


def geometry_from_euler(position_ned, euler_rad, velocity_ned, wind_ned=None, **kw) -> FormationGeometry:
    """From positions (V, 3), Euler angles 3-2-1 (V, 3) rad and ground velocities (V, 3) NED."""
    r = np.swapaxes(dcm_ned_to_body(np.asarray(euler_rad, dtype=float).reshape(-1, 3)), -1, -2)
    return formation_geometry(position_ned, r, velocity_ned, wind_ned, **kw)


def draw_formation(ax_top, ax_side, state: np.ndarray, slots: np.ndarray | None = None, wind_ned=None) -> None:
    """Draw one formation (state (V, 16)) on two axes: top view (east-north) and side view
    (north-altitude); wings solid, trailing legs dotted, slots (V, 3) NED as crosses."""
    g = geometry_from_state(state, wind_ned)
    pos = g.position
    v = pos.shape[0]
    for i in range(v):
        c = vehicle_colour(i)
        for ax, (a, b) in ((ax_top, (1, 0)), (ax_side, (0, 2))):
            sgn = -1.0 if b == 2 else 1.0
            ax.plot(g.tips[i, :, a], sgn * g.tips[i, :, b], "-", color=c, lw=2.5)
            ax.plot([g.nose[i, a], g.tail[i, a]], [sgn * g.nose[i, b], sgn * g.tail[i, b]], "-", color=c, lw=1.2)
            for leg in g.legs[i]:
                ax.plot(leg[:, a], sgn * leg[:, b], ":", color=c, lw=1)
            if slots is not None:
                ax.plot(slots[i, a], sgn * slots[i, b], "x", color=c, ms=6)
        ax_top.annotate(f"uav_{i}", (pos[i, 1], pos[i, 0]), fontsize=7, xytext=(3, 3), textcoords="offset points")
    c = pos.mean(axis=0)
    half = max(3 * SPAN_M, 0.6 * np.ptp(pos, axis=0).max() + SPAN_M)
    ax_top.set_xlim(c[1] - half, c[1] + half)
    ax_top.set_ylim(c[0] - half, c[0] + half)
    ax_side.set_xlim(c[0] - half, c[0] + half)
    ax_side.set_ylim(-c[2] - half / 2, -c[2] + half / 2)
    ax_top.set_xlabel("east (m)")
    ax_top.set_ylabel("north (m)")
    ax_side.set_xlabel("north (m)")
    ax_side.set_ylabel("altitude (m)")
    ax_top.set_aspect("equal")
    ax_top.grid(alpha=0.3)
    ax_side.grid(alpha=0.3)


def _enu(p: np.ndarray) -> tuple:
    """NED (..., 3) -> plot coordinates (east, north, altitude)."""
    return p[..., 1], p[..., 0], -p[..., 2]


def draw_formation_3d(ax, geometry: FormationGeometry, *, trails=None, slots=None, labels: bool = True,
                      half_extent_m: float | None = None, centre_ned=None, scale: float = 1.0) -> None:
    """Draw a formation on a 3D axes in (east, north, altitude): wings and fuselages solid, trailing
    legs dotted, ``trails`` (V, T, 3) NED past positions thin, ``slots`` (V, 3) NED as crosses.
    ``scale`` enlarges the aircraft about their positions (for views far bigger than a span).
    The view is a cube of half-size ``half_extent_m`` about ``centre_ned`` (default: fit)."""
    g = geometry
    v = g.position.shape[0]
    if scale != 1.0:
        p = g.position
        g = FormationGeometry(p, p[:, None] + scale * (g.tips - p[:, None]), p + scale * (g.nose - p),
                              p + scale * (g.tail - p), p[:, None, None] + scale * (g.legs - p[:, None, None]))
    for i in range(v):
        c = vehicle_colour(i)
        ax.plot(*_enu(g.tips[i]), "-", color=c, lw=2.5)
        ax.plot(*_enu(np.stack([g.nose[i], g.tail[i]])), "-", color=c, lw=1.2)
        for leg in g.legs[i]:
            ax.plot(*_enu(leg), ":", color=c, lw=1.0)
        if trails is not None:
            ax.plot(*_enu(np.asarray(trails[i])), "-", color=c, lw=0.7, alpha=0.6)
        if slots is not None:
            ax.scatter(*_enu(np.asarray(slots[i])[None]), marker="x", color=c, s=20)
        if labels:
            e, n, h = _enu(g.position[i])
            ax.text(e, n, h, f" uav_{i}", fontsize=7, color=c)
    pts = g.position if trails is None else np.concatenate([g.position, np.asarray(trails).reshape(-1, 3)])
    centre = pts.mean(axis=0) if centre_ned is None else np.asarray(centre_ned, dtype=float)
    if half_extent_m is None:
        half_extent_m = max(3 * SPAN_M, 0.55 * float(np.ptp(pts, axis=0).max()) + SPAN_M)
    e, n, h = _enu(centre)
    ax.set_xlim(e - half_extent_m, e + half_extent_m)
    ax.set_ylim(n - half_extent_m, n + half_extent_m)
    ax.set_zlim(h - half_extent_m, h + half_extent_m)
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.set_zlabel("altitude (m)")


def figure_to_rgb(fig) -> np.ndarray:
    """Render a matplotlib figure to an RGB uint8 array (H, W, 3)."""
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()
