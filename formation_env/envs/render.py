"""Drawing of a formation: top view (east-north) and side view (north-altitude), each UAV's wing and
its two tip trailing legs drawn a few spans downstream along its air velocity, and its slot.

Vehicles are labelled ``uav_<index>`` (the agent names). ``draw(formation=f)`` draws formation ``f``
of a batched :class:`~formation_env.sim.Simulation` (the vector envs render each of their formations with one renderer)."""

from __future__ import annotations

import numpy as np

from ..replay.view import LEG_LENGTH_M, SPAN_M, draw_formation  # shared with the replay GIF and 3D figures

__all__ = ["FormationRenderer", "draw_formation", "SPAN_M", "LEG_LENGTH_M"]


class FormationRenderer:
    """Renders one formation of a simulation. ``draw()`` returns an RGB array (H, W, 3) uint8, or None
    for a human renderer (``human=True``: the frame is shown in a window, as Gymnasium's
    ``render_mode="human"`` expects)."""

    def __init__(self, sim, human: bool = False, size=(8.0, 4.0), dpi: int = 80) -> None:
        import matplotlib

        if not human:
            matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt

        self._plt = plt
        self.sim = sim
        self.human = human
        # a fixed layout (the same pixels for the same state, frame after frame) with room for the
        # tick labels of absolute positions (altitude ~1000 m): axis labels, views and title never overlap
        self.fig, (self.ax_top, self.ax_side) = plt.subplots(1, 2, figsize=size, dpi=dpi)
        self.fig.subplots_adjust(left=0.09, right=0.98, bottom=0.13, top=0.87, wspace=0.28)

    def draw(self, formation: int = 0) -> np.ndarray | None:
        eng = self.sim
        f = int(formation)
        self.ax_top.cla()
        self.ax_side.cla()
        draw_formation(self.ax_top, self.ax_side, eng.aircraft[f], eng.position_demand[f], eng.ambient_wind()[f] + eng.induced[f])
        for ax in (self.ax_top, self.ax_side):
            # absolute positions (altitude ~1e3 m): full tick values, no "+1e3" offset text
            ax.ticklabel_format(useOffset=False, style="plain")
            ax.tick_params(labelsize=7)
            ax.xaxis.label.set_fontsize(8)
            ax.yaxis.label.set_fontsize(8)
            ax.locator_params(axis="x", nbins=5)
        self.ax_top.set_title("top view", fontsize=8)
        self.ax_side.set_title("side view", fontsize=8)
        self.fig.suptitle(f"{eng.scenario.name}  t = {eng.time_s[f]:.1f} s", fontsize=9)
        self.fig.canvas.draw()
        if self.human:
            self._plt.pause(0.001)
            return None
        return np.asarray(self.fig.canvas.buffer_rgba())[..., :3].copy()

    def close(self) -> None:
        self._plt.close(self.fig)
