"""Task ``close_formation``: hold the ELL's induced-drag optimum 2 spans behind the leader.

Its slot is the optimum of the cached saving map (:mod:`.optimum`, ``formation_env/data/close_formation_map.json``,
docs/close_formation.md), found outside the band |z| < 0.1 b where the follower's wing meets the leader's
discrete trailing legs (the saving ripples with the leg spacing there)."""

from __future__ import annotations

from ...scenarios import Scenario, SlotSchedule
from ..base import Task, register_task

__all__ = ["SCENARIO", "TASK"]

SCENARIO = Scenario(
    "close_formation", "close formation at the ELL's induced-drag optimum: follower 2 spans behind, "
    "0.96 span starboard of and 0.1 span below the leader, just off its wake plane (37 % "
    "induced-drag saving against 15 % at the thesis slot 1 span starboard, 0.3 span below)",
    duration_s=60.0,
    slots=(SlotSchedule(((0.0, (-2.0, 0.96, 0.1)),)),),
    notes={"induced_drag_saving": 0.3665, "thesis_slot_saving": 0.1484, "z_exclusion_b": 0.1},
    # an energy task: the ELL's loads reach the 6-DOF consistently (formation_env.wake.coupling, docs/ell.md)
    wake_coupling="load_weighted")

TASK = register_task(Task("close_formation", SCENARIO, "formation_env/CloseFormation-v0", 1,
                          baselines=("pid", "pid_formation", "station_keeper"),
                          reference="formation_env.tasks.close_formation.optimum",
                          description="hold the ELL induced-drag optimum slot",
                          # the follower starts a tenth of a span (std, per axis) off its slot: the scale on
                          # which the saving changes, and without it the calm-air test episodes are all one
                          test_randomisation={"initial_offset_m": 0.3}))
