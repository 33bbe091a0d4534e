"""Shared argument types and checks of the ``formation-env`` subcommands: every bad value is
rejected with one line naming it (exit status 2) before any heavy work starts."""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

__all__ = ["MAX_DURATION_S", "MAX_GIF_FRAMES", "MAX_EPISODES", "MAX_TRAIN_STEPS", "OneLineArgumentParser", "duration",
           "positive_int", "nonneg_int", "bounded_int", "finite_float", "check_out_path", "check_min_duration",
           "trained_scenario", "check_policy_scenario"]

from ..constants import MAX_DURATION_S  # noqa: E402  longest episode replay/run/evaluate fly
MAX_GIF_FRAMES = 2000    # most frames of a replay GIF (formation_env.replay.animation.MAX_FRAMES)
MAX_EPISODES = 10_000    # most evaluation episodes per policy (they run as one batch)
MAX_TRAIN_STEPS = 10 ** 9  # most environment steps of one training run (--steps)


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


def check_min_duration(duration_s: float | None, scenario) -> None:
    """A --duration shorter than one physics step of ``scenario`` (a Scenario) is a ValueError."""
    if duration_s is not None and duration_s < scenario.dt:
        raise ValueError(f"--duration {duration_s:g}: shorter than one step of {scenario.name!r} ({scenario.dt:g} s); "
                         f"give a number of seconds in [{scenario.dt:g}, {MAX_DURATION_S:g}]")


def trained_scenario(path) -> str | None:
    """The scenario a policy was trained on: a zip's sidecar JSON / config.yaml, or an RLlib checkpoint's
    metadata (the checkpoint directory's, or the latest checkpoint's of a run directory); None if unknown."""
    import json

    path = Path(path)
    if path.is_file():
        from train.evaluation.policy_loader import policy_metadata

        try:
            return policy_metadata(path).get("scenario")
        except (OSError, ValueError, AttributeError):
            return None
    if not path.is_dir():
        return None
    from train.rllib.checkpoints import CHECKPOINT_META, latest_rllib_checkpoint

    meta = path / CHECKPOINT_META
    if not meta.is_file():
        latest = latest_rllib_checkpoint(path)
        if latest is None:
            return None
        meta = latest[0] / CHECKPOINT_META
    try:
        return json.loads(meta.read_text()).get("scenario")
    except (OSError, ValueError, AttributeError):
        return None


def check_policy_scenario(spec: str, scenario: str, *, allow: bool) -> None:
    """A learned policy flies only the scenario it was trained for: another one is a ValueError naming
    both, unless ``allow`` (--allow-scenario-mismatch) and the two observation sizes agree. Policies whose
    metadata names no scenario, and the baselines, pass."""
    if spec in ("pid", "pid_formation", "station_keeper"):
        return
    trained = trained_scenario(spec)
    if trained is None or trained == scenario:
        return
    from ..scenarios import get_scenario, scenario_names
    from ..sim.layout import ObservationLayout

    if not allow:
        raise ValueError(f"--policy {spec!r} was trained for {trained!r}, not --scenario {scenario!r} (use "
                         f"--scenario {trained}, or pass --allow-scenario-mismatch)")
    sc = get_scenario(scenario)
    size = ObservationLayout.of(sc.n_vehicles, sc.neighbour_count).size
    if trained in scenario_names():
        tr = get_scenario(trained)
        own = ObservationLayout.of(tr.n_vehicles, tr.neighbour_count).size
        if own != size:
            raise ValueError(f"--policy {spec!r} was trained for {trained!r} (observations of {own}), --scenario "
                             f"{scenario!r} observes {size}: --allow-scenario-mismatch needs equal sizes")
