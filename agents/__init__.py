"""Agents that fly the formation simulator through its public API.

* :mod:`agents.pid_formation`: the formation-keeping controller around the thesis PID (the env's
  ``setpoints`` action mode).
* :mod:`agents.station_keeper`: a classical station keeper tuned for cross-track precision in
  ``close_formation`` (attitude laws through the set-points, vertical-gust feed-forward, separation guard).
* :mod:`agents.registry`: the classical agents by name (:func:`~agents.registry.classical_agent`), for the
  evaluation's ``--policy NAME`` and a residual learner's ``residual_on`` agent.

The thesis PID flight control system (Appendix A) they build on is :mod:`formation_env.control` (its observation
adapter :mod:`formation_env.control.observation`), and the scenario runner :mod:`formation_env.runs.runner`: the
environments run them, and ``formation_env`` never imports ``agents``.
"""
