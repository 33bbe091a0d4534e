"""Compatibility re-export: the thesis PID flight control system now lives in
:mod:`formation_env.control` (``formation_env/control/``), so the environments do not import
``agents``. ``from agents.fcs import PIDFlightControl`` and ``import agents.fcs.<module>`` (gains,
law, tracker, policy, closed_loop; the numpy layers sas/attitude/autopilot/common became the test
oracle tests/oracles/fcs_numpy.py) keep working; new code should import
from :mod:`formation_env.control`.
"""

import importlib as _importlib
import sys as _sys

from formation_env.control import *  # noqa: F401,F403
from formation_env.control import __all__  # noqa: F401

for _name in ("gains", "law", "tracker", "policy", "closed_loop"):
    _module = _importlib.import_module(f"formation_env.control.{_name}")
    _sys.modules.setdefault(f"{__name__}.{_name}", _module)
    globals()[_name] = _module
del _importlib, _sys, _name, _module
