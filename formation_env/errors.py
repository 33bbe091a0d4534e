"""Exceptions shared by the command line and the optional parts of the project."""

from __future__ import annotations

__all__ = ["MissingDependencyError", "ClusterUnreachableError", "ShadowedPackageError"]


class MissingDependencyError(ImportError):
    """An optional dependency a feature needs is not installed; the message says how to install it."""


class ClusterUnreachableError(ConnectionError):
    """The Ray cluster named by ``--address`` cannot be reached or joined; the message says why."""


class ShadowedPackageError(ImportError):
    """The name ``agents`` or ``train`` is already bound in this process to a module that is not formation-env's
    own package of that name (a user's ``train.py`` imported first); the message names both places."""
