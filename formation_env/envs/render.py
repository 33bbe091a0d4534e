"""Drawing of a formation: top view (east-north) and side view (north-altitude), each UAV's wing and
its two tip trailing legs drawn a few spans downstream along its air velocity, and its slot."""

from __future__ import annotations

import numpy as np

from ..replay.view import LEG_LENGTH_M, SPAN_M, draw_formation  # shared with the replay GIF and 3D figures

__all__ = ["FormationRenderer", "draw_formation", "SPAN_M", "LEG_LENGTH_M"]


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
