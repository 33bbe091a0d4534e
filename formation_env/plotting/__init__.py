"""Figures (matplotlib, Agg backend). Every file is written atomically and never overwritten silently."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

from pathlib import Path  # noqa: E402

from ..io import atomic_write  # noqa: E402


def save_figure(fig, path: str | Path, *, overwrite: bool = False, dpi: int = 120) -> Path:
    """Save a matplotlib figure atomically (PNG/PDF by suffix) and close it."""
    import matplotlib.pyplot as plt

    path = Path(path)
    try:
        return atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=dpi, bbox_inches="tight", format=path.suffix.lstrip(".") or "png"),
                            overwrite=overwrite)
    finally:
        plt.close(fig)
