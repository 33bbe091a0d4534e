"""Exceptions shared by the command line and the optional parts of the project."""

from __future__ import annotations

__all__ = ["MissingDependencyError", "ClusterUnreachableError"]


class MissingDependencyError(ImportError):
    """An optional dependency a feature needs is not installed; the message says how to install it."""


class ClusterUnreachableError(ConnectionError):
    """The Ray cluster named by ``--address`` cannot be reached or joined; the message says why."""
