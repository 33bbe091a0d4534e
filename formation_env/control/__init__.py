"""The thesis's PID flight control system (Appendix A): the baseline flight control law that the
environments run under the RL agents (and that flies the scenarios of :mod:`formation_env.scenarios`).
It lives inside the package so that ``formation_env`` never imports ``agents``.

* :mod:`.gains`: Tables A.8-A.10, A.13 and the open structural choices (:class:`FCSStructure`).
* :mod:`.law`: the compiled law, one aircraft per call (tracker A.5 -> autopilot A.4 -> attitude
  A.3 -> SAS A.2), gains in one named struct; the decision step and the policy both run it. Its
  readable numpy definition, layer by layer, is in tests/oracles/fcs_numpy.py.
* :mod:`.tracker`: the tracker's along/off-track errors (Eqs. A.16-A.21) for histories.
* :mod:`.policy`: :class:`PIDFlightControl` (``act(observation, controller_state)``).
* :mod:`.closed_loop`: closed-loop linearisation and modes (Tables A.11/A.12).
* :mod:`.observation`: the FCS observation adapter (aircraft state + demands -> observation) and
  virtual-leader slot demands.
"""

from .gains import AttitudeGains, AutopilotGains, FCSConfig, FCSStructure, SASGains, TrackerGains
from .policy import CSTATE_NAMES, N_CSTATE, PIDFlightControl

__all__ = ["AttitudeGains", "AutopilotGains", "FCSConfig", "FCSStructure", "SASGains", "TrackerGains",
           "CSTATE_NAMES", "N_CSTATE", "PIDFlightControl"]
