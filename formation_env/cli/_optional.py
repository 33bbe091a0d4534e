"""Import the optional parts of the project that are present (each section/benchmark provider
lives in its own module; a build without one simply skips it). The helper lives in
:mod:`formation_env.verification.sections` (shared with the report, which must not import the CLI)."""

from __future__ import annotations

from ..verification.sections import import_available

__all__ = ["import_available"]
