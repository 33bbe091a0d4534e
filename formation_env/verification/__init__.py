"""Reproduction of the thesis's tables (used by ``formation-env verify`` and the tests).

Each section module exposes ``SECTIONS``: a mapping from the section key (as printed by
``formation-env verify --json``) to a function returning that section's data.
"""
