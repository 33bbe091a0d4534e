"""Animated replay of an episode: a 3D view (east, north, altitude) following the formation, each
UAV with its trailing wake legs and a fading trail, beside strip charts of the induced wind; written
as a GIF with matplotlib's PillowWriter (or MP4 with ffmpeg when installed).

The drawing is :func:`formation_env.replay.view.draw_formation_3d`, the same code as the
environments' frames and the 3D trajectory figure.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..io import atomic_write
from .log import EpisodeLog
from .view import draw_formation_3d, geometry_from_euler, vehicle_colour

__all__ = ["write_animation", "frame_indices", "MAX_FRAMES"]


MAX_FRAMES = 2000  # the most frames an animation may have (formation-env replay --max-frames)


def frame_indices(log: EpisodeLog, fps: float, speedup: float, max_frames: int | None) -> np.ndarray:
    """Sample indices giving ``fps`` frames per second of playback at ``speedup`` x real time, at most
    ``max_frames`` (an integer in [1, MAX_FRAMES]; None: MAX_FRAMES)."""
    if max_frames is None:
        max_frames = MAX_FRAMES
    if isinstance(max_frames, bool) or not isinstance(max_frames, (int, np.integer)) or not 1 <= max_frames <= MAX_FRAMES:
        raise ValueError(f"max_frames must be an integer in [1, {MAX_FRAMES}], got {max_frames!r}")
    if not (np.isfinite(fps) and fps > 0 and np.isfinite(speedup) and speedup > 0):
        raise ValueError(f"fps and speedup must be finite and > 0, got fps={fps!r}, speedup={speedup!r}")
    dt = float(np.median(np.diff(log.time_s))) if log.n_samples > 1 else 1.0
    step = max(1, int(round(speedup / (fps * dt))))
    idx = np.arange(0, log.n_samples, step)
    if idx.size > max_frames:
        idx = np.unique(np.linspace(0, log.n_samples - 1, int(max_frames)).round().astype(int))
    return idx


def write_animation(log: EpisodeLog, path, *, fps: float = 10.0, speedup: float = 4.0, max_frames: int | None = 200,
                    trail_s: float = 8.0, dpi: int = 72, overwrite: bool = False, fixed_extent_m: float | None = None,
                    progress=None) -> Path:
    """Write ``log`` as an animation to ``path`` (``.gif``: Pillow; ``.mp4``: ffmpeg), atomically.

    ``speedup``: simulated seconds per playback second; ``trail_s``: seconds of past track drawn;
    ``fixed_extent_m``: half-size of the view cube following the formation (default: fits the
    formation's largest separation over the episode plus the wake legs); ``progress``: called with each
    frame's number (0-based) as it is rendered (a progress display)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ValueError(f"animation path must end in .gif or .mp4, got {str(path)!r}")
    if suffix == ".mp4" and not animation.writers.is_available("ffmpeg"):
        raise ValueError("MP4 needs ffmpeg, which is not installed; write a .gif instead")
    idx = frame_indices(log, fps, speedup, max_frames)
    dt = float(np.median(np.diff(log.time_s))) if log.n_samples > 1 else 1.0
    n_trail = max(1, int(round(trail_s / dt)))
    wind = log.ambient_wind_ned + log.induced_wind_ned
    rel = log.position_ned - log.position_ned.mean(axis=1, keepdims=True)
    half = fixed_extent_m or max(6.0, float(np.nanmax(np.abs(rel))) + 5.0)

    fig = plt.figure(figsize=(10.0, 5.0), dpi=dpi)
    gs = fig.add_gridspec(3, 2, width_ratios=(1.5, 1.0), left=0.02, right=0.98, wspace=0.25, hspace=0.35)
    ax3 = fig.add_subplot(gs[:, 0], projection="3d")
    axw = [fig.add_subplot(gs[k, 1]) for k in range(3)]
    for k, (ax, lab) in enumerate(zip(axw, ("Vi north", "Vi east", "Vi down"))):
        for i in range(log.n_vehicles):
            ax.plot(log.time_s, log.induced_wind_ned[:, i, k], color=vehicle_colour(i), lw=0.8, label=f"uav_{i}")
        ax.set_ylabel(f"{lab}\n(m/s)", fontsize=7)
        ax.tick_params(labelsize=6)
        ax.grid(alpha=0.3)
    axw[0].set_title("ELL induced wind, NED", fontsize=8)
    axw[0].legend(fontsize=6, loc="upper right")
    axw[-1].set_xlabel("t (s)", fontsize=7)
    cursors = [ax.axvline(log.time_s[0], color="k", lw=0.8) for ax in axw]

    def draw(k: int):
        ax3.cla()
        g = geometry_from_euler(log.position_ned[k], log.euler_rad[k], log.velocity_ned[k], wind[k])
        trails = log.position_ned[max(0, k - n_trail):k + 1].swapaxes(0, 1)
        pd = log.position_demand_ned[k]
        draw_formation_3d(ax3, g, trails=trails, slots=pd if np.all(np.isfinite(pd)) else None,
                          half_extent_m=half, centre_ned=log.position_ned[k].mean(axis=0))
        ax3.set_title(f"{log.scenario}  t = {log.time_s[k]:.1f} s", fontsize=9)
        ax3.view_init(elev=25, azim=-130)
        ax3.tick_params(labelsize=6)
        for c in cursors:
            c.set_xdata([log.time_s[k], log.time_s[k]])
        return []

    anim = animation.FuncAnimation(fig, draw, frames=[int(k) for k in idx], blit=False)

    def writer(tmp: Path) -> None:
        w = animation.PillowWriter(fps=fps) if suffix == ".gif" else animation.FFMpegWriter(fps=fps)
        cb = None if progress is None else (lambda i, n: progress(i))
        anim.save(str(tmp), writer=w, dpi=dpi, progress_callback=cb)

    try:
        return atomic_write(path, writer, overwrite=overwrite)
    finally:
        plt.close(fig)
