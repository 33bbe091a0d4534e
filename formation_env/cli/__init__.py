"""The ``formation-env`` console command.

Each subcommand lives in its own module of this package and exposes
``register(subparsers)``, which adds its parser and sets ``func`` (called with the parsed
arguments; returns the process exit code). Add a subcommand by adding its module name to
``COMMANDS``.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from ..errors import ClusterUnreachableError, MissingDependencyError

COMMANDS = ("verify", "bench", "demo", "trim", "modes", "run", "report", "replay", "train", "evaluate")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="formation-env",
        description="Close-formation UAV simulator (ELL wake model + Aerosonde 6-DOF).",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as exc:  # a subcommand whose module is not in this build
            if exc.name == f"{__name__}.{name}":
                continue
            raise
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (ValueError, FileExistsError, MissingDependencyError, ClusterUnreachableError) as exc:
        print(f"formation-env {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
