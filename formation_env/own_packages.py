"""Bind the top-level names ``agents`` and ``train`` to formation-env's own packages, whatever lies on ``sys.path``.

The project installs ``agents`` and ``train`` as top-level packages beside ``formation_env``. Python puts a script's
directory (``python examples/x.py``) or the working directory (``python -m``, ``python -c``, a notebook) first on
``sys.path``, and Ray puts the driver's on its workers' path: a user's own ``train.py`` or ``agents/`` there would be
imported instead of the project's. :func:`bind` loads each package from the directory beside this ``formation_env``
(where every install puts them: a wheel, an editable install, a checkout on ``PYTHONPATH``) and registers it in
``sys.modules``, so every later ``import train.sb3...`` resolves inside the project's package. Importing this
module binds them (one line at the top of an example); ``formation-env`` binds them before any command runs, and
the RLlib backend makes it each Ray worker's setup hook.

``import formation_env`` alone binds nothing: a user's own modules of those names stay theirs in their own code.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

from .errors import ShadowedPackageError

__all__ = ["NAMES", "bind", "package_dir"]

NAMES = ("agents", "train")
_ROOT = Path(__file__).resolve().parent.parent


def package_dir(name: str) -> Path | None:
    """The directory of formation-env's own package ``name`` (beside ``formation_env``), None where this install
    has none."""
    directory = _ROOT / name
    return directory if (directory / "__init__.py").is_file() else None


def _origin(module) -> str:
    where = getattr(module, "__file__", None)
    if where is None:  # a namespace package: its search path
        where = ", ".join(getattr(module, "__path__", [])) or repr(module)
    return where


def _is_own(module, directory: Path) -> bool:
    where = getattr(module, "__file__", None)
    return where is not None and Path(where).resolve().parent == directory


def bind() -> None:
    """Make ``agents`` and ``train`` in ``sys.modules`` formation-env's own packages (idempotent). Raises
    :class:`~formation_env.errors.ShadowedPackageError` when another module of that name is already imported in
    this process: it cannot be replaced without breaking what imported it."""
    for name in NAMES:
        directory = package_dir(name)
        if directory is None:  # an install without the package: the import system decides
            continue
        loaded = sys.modules.get(name)
        if loaded is not None:
            if _is_own(loaded, directory):
                continue
            raise ShadowedPackageError(
                f"`{name}` is already imported from {_origin(loaded)}, not formation-env's package {directory}: "
                f"rename that module so that formation-env's `{name}` can be imported")
        spec = importlib.util.spec_from_file_location(name, directory / "__init__.py",
                                                      submodule_search_locations=[str(directory)])
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            sys.modules.pop(name, None)
            raise


bind()
