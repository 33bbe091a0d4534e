"""Thesis scenarios as data (:mod:`.definitions`): ``tracking`` (A.5.3), ``gust`` (6.4),
``formation_keeping`` (6.5), ``reconfiguration`` (6.6) and this project's formations; the env reuses
these definitions. A task's own scenario (close_formation, wake_surfing) is defined in its
:mod:`formation_env.tasks` unit and registered here on import. :mod:`formation_env.runs` flies them with the thesis PID on every aircraft."""

from .definitions import (AEROSONDE_SPAN_M, SCENARIOS, Scenario, SlotSchedule, get_scenario, register_scenario,
                          scenario_names)

__all__ = ["AEROSONDE_SPAN_M", "SCENARIOS", "Scenario", "SlotSchedule", "get_scenario", "scenario_names",
           "register_scenario"]
