"""The ``formation-env`` console command.

Each subcommand lives in its own module of this package and exposes
``register(subparsers)``, which adds its parser and sets ``func`` (called with the parsed
arguments; returns the process exit code). Add a subcommand by adding its module name to
``COMMANDS``.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from ..errors import ClusterUnreachableError, MissingDependencyError, ShadowedPackageError
from ._args import OneLineArgumentParser, check_out_path

COMMANDS = ("verify", "bench", "demo", "trim", "modes", "run", "report", "replay", "train", "evaluate", "warmup", "docs", "results",
            "publish", "data")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineArgumentParser(
        prog="formation-env",
        description="Close-formation UAV simulator (ELL wake model + Aerosonde 6-DOF).",
    )
    parser.add_argument("--version", action="version", version=f"formation-env {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=OneLineArgumentParser)
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as exc:  # a subcommand whose module is not in this build
            if exc.name == f"{__name__}.{name}":
                continue
            raise
        module.register(sub)
    return parser


def _version() -> str:
    """formation_env.__version__, else the installed package's metadata."""
    try:
        from .. import __version__

        return str(__version__)
    except ImportError:  # pragma: no cover - a build without the attribute
        from importlib.metadata import PackageNotFoundError, version

        try:
            return version("formation-env")
        except PackageNotFoundError:
            return "unknown"


def _quiet_broken_pipe() -> int:
    """The reader of stdout went away (``formation-env verify --json | head``): point stdout at devnull
    so that the interpreter's final flush does not fail again, and end quietly with status 1 (the
    handling the Python docs recommend, "Note on SIGPIPE" in the signal module's documentation)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # stdout is not a real file (tests' StringIO)
        pass
    return 1


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.filename is not None and exc.strerror:
        text = f"{exc.strerror}: {str(exc.filename)!r}"  # e.g. a directory that cannot be created
    else:
        text = str(exc) or type(exc).__name__
    return " ".join(text.split())


def main(argv: list[str] | None = None) -> int:
    """Run one subcommand. Bad arguments (argparse's, or a ValueError / FileExistsError / OSError raised by
    the subcommand before or while writing) are one line on stderr and exit status 2, never a traceback.
    A closed stdout pipe (``| head``) ends the command quietly (status 1, see :func:`_quiet_broken_pipe`)."""
    try:
        return _main(argv)
    except BrokenPipeError:
        return _quiet_broken_pipe()


def _main(argv: list[str] | None) -> int:
    # `python -m formation_env.cli` puts the working directory first on sys.path: a user's train.py there must not
    # stand in for the project's train package that the commands import
    try:
        from .. import own_packages  # binds them on import

        own_packages.bind()
    except ShadowedPackageError as exc:
        print(f"formation-env: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    parser = build_parser()
    try:
        args = parser.parse_args(argv)  # usage errors: one line, SystemExit(2)
    except SystemExit:
        sys.stdout.flush()  # --help / --version into a closed pipe: BrokenPipeError here, not at exit
        raise
    try:
        check_out_path(getattr(args, "out", None))
        code = int(args.func(args) or 0)
        sys.stdout.flush()
        return code
    except BrokenPipeError:
        raise
    except (ValueError, OSError, MissingDependencyError, ClusterUnreachableError) as exc:
        name = " ".join(n for n in (args.command, getattr(args, "action", None)) if n)  # e.g. "publish levels"
        print(f"formation-env {name}: error: {_one_line(exc)}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
