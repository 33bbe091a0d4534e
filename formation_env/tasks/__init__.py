"""Tasks as self-contained units (:class:`~formation_env.tasks.base.Task`): each holds its scenario, the
preset that poses it for learning, its action ranges and safe box (in the scenario), its reference optimum
and metrics where it has them, and the names of the baselines it is judged against.

* :mod:`.thesis`: the thesis's scenarios and the N-UAV formations (EnvConfig defaults);
* :mod:`.close_formation`: hold the ELL's induced-drag optimum (its saving map: ``.optimum``);
* :mod:`.wake_surfing`: find and hold the least-drag position in a safe box (``.optimum``, ``.metrics``, its own
  evaluation: ``.evaluation``, ``.controllers``);
* :mod:`.n_uav_formations`: N-UAV close formations (echelon3, vee5, vee9) at their joint ELL optimum, and
  ``vee_rotation`` (:mod:`.n_uav_formations.rotation`: the vee5 leader handing over the lead).

A task may add Python terms (reward, observation, termination, metric: :mod:`.terms`) composed after the compiled
step, and its own evaluation hooks (:mod:`.evaluation`); docs/custom-task.md writes one.

Importing this package registers every task (and its scenario) in order; ``formation_env`` imports it.
"""

from .base import (ALGORITHM_LABELS, HEADLINE_METRICS, TASKS, TEST_SEED_BASE, VALIDATION_SEED_BASE, EvaluationProtocol, RecordFile, Task, get_task, versus_records,
                   gym_ids, make_config, register_task, task_for_scenario, task_learning, task_names, task_options)
from . import thesis  # noqa: F401  (registers)
from . import close_formation  # noqa: F401
from . import wake_surfing  # noqa: F401
from . import n_uav_formations  # noqa: F401

__all__ = ["Task", "EvaluationProtocol", "RecordFile", "HEADLINE_METRICS", "ALGORITHM_LABELS", "versus_records", "TEST_SEED_BASE", "VALIDATION_SEED_BASE", "TASKS", "get_task", "task_names", "register_task", "task_options", "task_for_scenario", "make_config",
           "gym_ids", "task_learning"]
