"""Import the optional parts of the project that are present (each section/benchmark provider
lives in its own module; a build without one simply skips it)."""

from __future__ import annotations

import importlib
from types import ModuleType


def import_available(names) -> dict[str, ModuleType]:
    """Import each module in ``names`` that exists; a missing module is skipped, any other import
    error propagates."""
    modules = {}
    for name in names:
        try:
            modules[name] = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:
                continue
            raise
    return modules
