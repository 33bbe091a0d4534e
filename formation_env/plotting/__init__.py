"""Figures (matplotlib, Agg backend). Every file is written atomically and never overwritten silently."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

from matplotlib.ticker import ScalarFormatter  # noqa: E402

from ..io import save_figure  # noqa: E402

__all__ = ["save_figure", "no_offset", "vehicle_label"]


def vehicle_label(i: int) -> str:
    """The one name of vehicle ``i`` in every figure: ``uav_<i>`` (the agent names of the envs)."""
    return f"uav_{int(i)}"


def no_offset(fig):
    """Full tick values on every axis of ``fig`` (x, y and, in 3D, z): no "+1e3"-style offset text
    (an altitude near 1000 m otherwise reads as 0..5 "+1e3"). Call it once the axes are final."""
    for ax in fig.axes:
        for axis in (getattr(ax, name, None) for name in ("xaxis", "yaxis", "zaxis")):
            if axis is None:
                continue
            fmt = axis.get_major_formatter()
            if isinstance(fmt, ScalarFormatter):
                fmt.set_useOffset(False)
    return fig
