"""The thesis's tables as numbers (a copy of ``shared/reference/thesis_values.json``)."""

from __future__ import annotations

import json
from functools import lru_cache
from importlib import resources


@lru_cache(maxsize=1)
def thesis_values() -> dict:
    """Return the thesis tables (angles in degrees unless a key says rad)."""
    text = resources.files("formation_env.data").joinpath("thesis_values.json").read_text()
    return json.loads(text)
