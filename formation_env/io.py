"""Safe file output: every file the tools write goes through here, written atomically (temporary
file + rename) and never silently overwriting an existing file."""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

__all__ = ["atomic_write", "atomic_write_text", "atomic_write_json", "prepare_output_dir", "save_figure"]


def atomic_write(path: str | os.PathLike, writer: Callable[[Path], None], *, overwrite: bool = False) -> Path:
    """Create ``path`` by calling ``writer(tmp_path)`` and renaming the result into place.

    Raises FileExistsError if ``path`` exists and ``overwrite`` is False. The temporary file lives
    in the same directory, so the rename is atomic; on failure it is removed.
    """
    path = Path(path)
    if path.exists() and not overwrite:
        raise FileExistsError(f"refusing to overwrite existing file {str(path)!r} (pass overwrite=True / --overwrite)")
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix or ".tmp", dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        writer(tmp_path)
        if not overwrite and path.exists():  # appeared while we were writing
            raise FileExistsError(f"refusing to overwrite existing file {str(path)!r}")
        # mkstemp creates the file private (0600); give it the permissions a plain open() would.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp_path, 0o666 & ~umask)
        os.replace(tmp_path, path)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()
    return path


def atomic_write_text(path: str | os.PathLike, text: str, *, overwrite: bool = False) -> Path:
    return atomic_write(path, lambda p: p.write_text(text), overwrite=overwrite)


def atomic_write_json(path: str | os.PathLike, data, *, overwrite: bool = False) -> Path:
    return atomic_write_text(path, json.dumps(data, indent=2, sort_keys=False) + "\n", overwrite=overwrite)


def prepare_output_dir(path: str | os.PathLike, *, overwrite: bool = False) -> Path:
    """Create an output directory; an existing non-empty one is an error unless ``overwrite``."""
    path = Path(path)
    if path.exists():
        if not path.is_dir():
            raise FileExistsError(f"output path {str(path)!r} exists and is not a directory")
        if any(path.iterdir()) and not overwrite:
            raise FileExistsError(f"output directory {str(path)!r} exists and is not empty (pass --overwrite)")
    path.mkdir(parents=True, exist_ok=True)
    return path


def save_figure(fig, path: str | Path, *, overwrite: bool = False, dpi: int = 120) -> Path:
    """Save a matplotlib figure atomically (PNG/PDF by suffix) and close it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    try:
        return atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=dpi, bbox_inches="tight", format=path.suffix.lstrip(".") or "png"),
                            overwrite=overwrite)
    finally:
        plt.close(fig)
