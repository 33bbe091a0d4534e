"""Formation trajectories in 3D (east, north, altitude): every UAV's track, with the aircraft and
their trailing wake legs drawn at a few instants (the drawing of :mod:`formation_env.replay.view`,
shared with the GIF replay and ``env.render()``). Input: an :class:`~formation_env.replay.EpisodeLog`."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from ..replay.log import EpisodeLog
from ..replay.view import draw_formation_3d, geometry_from_euler, vehicle_colour
from . import no_offset, vehicle_label

__all__ = ["trajectory_3d_figure"]


def trajectory_3d_figure(log: EpisodeLog, n_snapshots: int = 5, relative: bool = True):
    """Left: tracks in NED (east, north, altitude) with aircraft at ``n_snapshots`` instants
    (enlarged x3 to be visible at the episode's scale). Right (``relative``): the followers'
    positions relative to vehicle 0 (leader-fixed NED axes), which shows slot changes and swaps."""
    ncol = 2 if relative and log.n_vehicles > 1 else 1
    fig = plt.figure(figsize=(6.0 * ncol, 5.5), constrained_layout=True)
    ax = fig.add_subplot(1, ncol, 1, projection="3d")
    wind = log.ambient_wind_ned + log.induced_wind_ned
    p = log.position_ned
    snaps = np.unique(np.linspace(0, log.n_samples - 1, max(1, n_snapshots)).round().astype(int))
    for i in range(log.n_vehicles):
        ax.plot(p[:, i, 1], p[:, i, 0], -p[:, i, 2], "-", color=vehicle_colour(i), lw=0.8)
    for k in snaps:
        g = geometry_from_euler(p[k], log.euler_rad[k], log.velocity_ned[k], wind[k])
        draw_formation_3d(ax, g, labels=k == snaps[-1], scale=3.0)
    # draw_formation_3d fits a cube about the last snapshot; refit the whole episode
    lo, hi = np.nanmin(p.reshape(-1, 3), axis=0), np.nanmax(p.reshape(-1, 3), axis=0)
    ax.set_xlim(lo[1] - 10, hi[1] + 10)
    ax.set_ylim(lo[0] - 10, hi[0] + 10)
    ax.set_zlim(-hi[2] - 10, -lo[2] + 10)
    ax.set_title(f"{log.scenario}: tracks (aircraft x3 at {len(snaps)} instants)", fontsize=9)
    if ncol == 2:
        ax2 = fig.add_subplot(1, 2, 2, projection="3d")
        rel = p - p[:, :1]
        for i in range(log.n_vehicles):
            ax2.plot(rel[:, i, 1], rel[:, i, 0], -rel[:, i, 2], "-", color=vehicle_colour(i), lw=1.0, label=vehicle_label(i))
        for k in snaps:  # the aircraft and their wake legs at the same instants, true scale, equal axes
            g = geometry_from_euler(rel[k], log.euler_rad[k], log.velocity_ned[k], wind[k])
            draw_formation_3d(ax2, g, labels=False, trails=rel.swapaxes(0, 1))
        ax2.set_xlabel("east rel. (m)")
        ax2.set_ylabel("north rel. (m)")
        ax2.set_zlabel("altitude rel. (m)")
        ax2.set_title(f"relative to uav_0 (leader-fixed NED axes, true scale), {len(snaps)} instants", fontsize=9)
        ax2.legend(fontsize=7)
    return no_offset(fig)
