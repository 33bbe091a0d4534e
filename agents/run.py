"""Compatibility re-export: the scenario runner (:func:`run_scenario`, :func:`scenario_metrics`,
:func:`run_scenario_to_dir`, :class:`ScenarioRun`) now lives in
:mod:`formation_env.runs.runner`; new code should import it from there."""

from formation_env.runs.runner import *  # noqa: F401,F403
from formation_env.runs.runner import __all__  # noqa: F401
