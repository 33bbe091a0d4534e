"""Agents that fly the formation simulator.

* :mod:`agents.fcs`: the thesis's PID flight control system (Appendix A), the baseline policy
  :class:`agents.fcs.PIDFlightControl` (``act(observation, controller_state)``).
* :mod:`agents.observation`: the observation adapter (aircraft state + demands -> observation)
  shared by the FCS and the RL environments; virtual-leader slot demands.
"""
