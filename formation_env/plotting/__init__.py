"""Figures (matplotlib, Agg backend). Every file is written atomically and never overwritten silently."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

from ..io import save_figure  # noqa: E402

__all__ = ["save_figure"]
