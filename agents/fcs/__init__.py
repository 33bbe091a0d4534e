"""The thesis's PID flight control system (Appendix A) as the baseline agent.

* :mod:`.gains`: Tables A.8-A.10, A.13 and the open structural choices (:class:`FCSStructure`).
* :mod:`.sas`, :mod:`.attitude`, :mod:`.autopilot`, :mod:`.tracker`: the layers (pure functions).
* :mod:`.policy`: :class:`PIDFlightControl` (``act(observation, controller_state)``).
* :mod:`.closed_loop`: closed-loop linearisation and modes (Tables A.11/A.12).
"""

from .gains import AttitudeGains, AutopilotGains, FCSConfig, FCSStructure, SASGains, TrackerGains
from .policy import CSTATE_NAMES, N_CSTATE, PIDFlightControl

__all__ = ["AttitudeGains", "AutopilotGains", "FCSConfig", "FCSStructure", "SASGains", "TrackerGains",
           "CSTATE_NAMES", "N_CSTATE", "PIDFlightControl"]
