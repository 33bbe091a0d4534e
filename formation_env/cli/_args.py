"""Shared argument types and checks of the ``formation-env`` subcommands: every bad value is
rejected with one line naming it (exit status 2) before any heavy work starts."""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

__all__ = ["MAX_DURATION_S", "MAX_GIF_FRAMES", "MAX_EPISODES", "OneLineArgumentParser", "duration",
           "positive_int", "nonneg_int", "bounded_int", "finite_float", "check_out_path"]

MAX_DURATION_S = 3600.0  # longest episode replay/run/evaluate fly (one hour of flight)
MAX_GIF_FRAMES = 2000    # most frames of a replay GIF (formation_env.replay.animation.MAX_FRAMES)
MAX_EPISODES = 10_000    # most evaluation episodes per policy (they run as one batch)


class OneLineArgumentParser(argparse.ArgumentParser):
    """argparse's parser, but a usage error is one line on stderr (``prog: error: message``) and exit 2."""

    def error(self, message: str):  # noqa: D401 - argparse API
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())} (see {self.prog} --help)\n")


def _number(text: str, kind: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be {kind}, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be {kind}, got {text!r}")
    return value


def duration(text: str) -> float:
    """An episode duration, s: finite, > 0 and at most :data:`MAX_DURATION_S`."""
    kind = f"a number of seconds in (0, {MAX_DURATION_S:g}]"
    value = _number(text, kind)
    if not 0.0 < value <= MAX_DURATION_S:
        raise argparse.ArgumentTypeError(f"must be {kind}, got {text!r}")
    return value


def finite_float(text: str) -> float:
    return _number(text, "a finite number")


def _int(text: str, kind: str) -> int:
    try:
        return int(text.replace("_", ""))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be {kind}, got {text!r}") from None


def bounded_int(lo: int, hi: int | None = None):
    """An integer type for argparse within [lo, hi]."""
    kind = f"an integer >= {lo}" if hi is None else f"an integer in [{lo}, {hi}]"

    def parse(text: str) -> int:
        value = _int(text, kind)
        if value < lo or (hi is not None and value > hi):
            raise argparse.ArgumentTypeError(f"must be {kind}, got {text!r}")
        return value

    parse.__name__ = "integer"
    return parse


positive_int = bounded_int(1)
nonneg_int = bounded_int(0)


def check_out_path(path, option: str = "--out") -> None:
    """Raise ValueError (one line) when ``path`` cannot become an output directory: it is a file, one
    of its parents is a file, or the nearest existing parent is not writable."""
    if path is None:
        return
    text = str(path)
    if not text.strip():
        raise ValueError(f"{option} {text!r}: empty path")
    p = Path(text).expanduser()
    if p.exists():
        if not p.is_dir():
            raise ValueError(f"{option} {text!r}: exists and is not a directory")
        if not os.access(p, os.W_OK | os.X_OK):
            raise ValueError(f"{option} {text!r}: directory is not writable")
        return
    parent = p.absolute().parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise ValueError(f"{option} {text!r}: {str(parent)!r} is a file, not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ValueError(f"{option} {text!r}: cannot create it, {str(parent)!r} is not writable")
