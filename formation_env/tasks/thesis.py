"""The thesis's scenarios (chapter 6, Appendix A.5.3) and this project's N-UAV formations as tasks: posed
by the EnvConfig defaults, judged against the thesis PID and ``pid_formation`` on the generic evaluation
table (:mod:`train.evaluation.evaluate`). Their scenarios are data in :mod:`formation_env.scenarios.definitions`."""

from __future__ import annotations

from .base import Task, register_task

__all__ = ["THESIS_TASKS"]

THESIS_TASKS = tuple(register_task(t) for t in (
    Task("formation_keeping", "formation_keeping", "formation_env/FormationKeeping-v0", 1,
         description="6.5: hold the slot 2 spans behind, 1 starboard, 0.3 below"),
    Task("reconfiguration", "reconfiguration", "formation_env/Reconfiguration-v0", 1,
         description="6.6: follow the slot schedule from behind to ahead of the leader"),
    Task("gust", "gust", "formation_env/Gust-v0", 0, baselines=("pid",), description="6.4: fly through the gusts"),
    Task("tracking", "tracking", "formation_env/Tracking-v0", 0, baselines=("pid",),
         description="A.5.3: track a displaced reference"),
    Task("echelon", "echelon", "formation_env/Echelon-v0", 1, description="right echelon of 3"),
    Task("vee", "vee", "formation_env/Vee-v0", 1, description="vee of 5"),
))
