"""Agents that fly the formation simulator through its public API.

* :mod:`agents.pid_formation`: the formation-keeping controller around the thesis PID (the env's
  ``setpoints`` action mode).
* :mod:`agents.station_keeper`: a classical station keeper tuned for cross-track precision in
  ``close_formation`` (attitude laws through the set-points, vertical-gust feed-forward, separation guard).
* :mod:`agents.fcs`, :mod:`agents.observation`, :mod:`agents.run`: compatibility re-exports of
  :mod:`formation_env.control` (the thesis PID flight control system, Appendix A),
  :mod:`formation_env.control.observation` (the FCS observation adapter) and
  :mod:`formation_env.runs.runner` (the scenario runner), which moved into the package so
  that ``formation_env`` never imports ``agents``.
"""
