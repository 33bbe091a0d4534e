"""Drawing of a formation: top view (east-north) and side view (north-altitude), each UAV's wing and
its two tip trailing legs drawn a few spans downstream along its air velocity, and its slot."""

from __future__ import annotations

import numpy as np

from ..frames import dcm_body_to_ned_from_quaternion

__all__ = ["FormationRenderer", "draw_formation"]

SPAN_M = 2.9
LEG_LENGTH_M = 4 * SPAN_M


def draw_formation(ax_top, ax_side, state: np.ndarray, slots: np.ndarray | None = None, wind_ned=None) -> None:
    """Draw one formation (state (V, 16)) on two matplotlib axes."""
    v = state.shape[0]
    pos = state[:, 10:13]
    r = dcm_body_to_ned_from_quaternion(state[:, 6:10])
    vel = np.einsum("vij,vj->vi", r, state[:, 0:3])
    air = vel - (np.zeros(3) if wind_ned is None else np.asarray(wind_ned).reshape(-1, 3))
    colours = [f"C{i % 10}" for i in range(v)]
    for i in range(v):
        tips = pos[i] + np.stack([r[i] @ np.array([0.0, -SPAN_M / 2, 0.0]), r[i] @ np.array([0.0, SPAN_M / 2, 0.0])])
        back = -air[i] / max(np.linalg.norm(air[i]), 1e-9) * LEG_LENGTH_M
        for ax, (a, b) in ((ax_top, (1, 0)), (ax_side, (0, 2))):
            sgn = -1.0 if b == 2 else 1.0
            ax.plot(tips[:, a], sgn * tips[:, b], "-", color=colours[i], lw=2.5)
            for tip in tips:  # trailing legs (the wake)
                ax.plot([tip[a], tip[a] + back[a]], [sgn * tip[b], sgn * (tip[b] + back[b])], ":", color=colours[i], lw=1)
            if slots is not None:
                ax.plot(slots[i, a], sgn * slots[i, b], "x", color=colours[i], ms=6)
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


class FormationRenderer:
    """Renders the engine's first formation; ``draw()`` returns an RGB array (H, W, 3) uint8."""

    def __init__(self, engine, human: bool = False, size=(8.0, 4.0), dpi: int = 80) -> None:
        import matplotlib

        if not human:
            matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt

        self._plt = plt
        self.engine = engine
        self.human = human
        self.fig, (self.ax_top, self.ax_side) = plt.subplots(1, 2, figsize=size, dpi=dpi)

    def draw(self) -> np.ndarray:
        eng = self.engine
        self.ax_top.cla()
        self.ax_side.cla()
        draw_formation(self.ax_top, self.ax_side, eng.state[0], eng.position_demand[0], eng.ambient_wind()[0] + eng.induced[0])
        self.fig.suptitle(f"{eng.scenario.name}  t = {eng.time_s[0]:.1f} s", fontsize=9)
        self.fig.canvas.draw()
        rgba = np.asarray(self.fig.canvas.buffer_rgba())
        if self.human:
            self._plt.pause(0.001)
        return rgba[..., :3].copy()

    def close(self) -> None:
        self._plt.close(self.fig)
