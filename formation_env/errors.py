"""Exceptions shared by the command line and the optional parts of the project."""

from __future__ import annotations

__all__ = ["MissingDependencyError"]


class MissingDependencyError(ImportError):
    """An optional dependency a feature needs is not installed; the message says how to install it."""
