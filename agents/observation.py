"""Compatibility re-export: the FCS observation adapter now lives in
:mod:`formation_env.control.observation`; new code should import it from there."""

from formation_env.control.observation import *  # noqa: F401,F403
from formation_env.control.observation import __all__  # noqa: F401
