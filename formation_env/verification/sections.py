"""The verification sections present in this build: ``SECTION_MODULES`` each expose
``SECTIONS = {key: callable returning a JSON-serialisable dict}``. Used by ``formation-env verify``
and the report (kept here, below both, so that the report does not import the CLI)."""

from __future__ import annotations

import importlib
from types import ModuleType

__all__ = ["SECTION_MODULES", "available_sections", "import_available"]

SECTION_MODULES = ("formation_env.verification.ell_tables", "formation_env.verification.aircraft")


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


def available_sections() -> dict:
    """Section key -> function returning its data, over the section modules of this build."""
    sections = {}
    for module in import_available(SECTION_MODULES).values():
        sections.update(module.SECTIONS)
    return sections
