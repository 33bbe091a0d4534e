"""The classical agents by name: the evaluation (``--policy station_keeper``) and the residual learners
(``residual_on: {agent: ...}``) build them here, so that neither imports the other."""

from __future__ import annotations

__all__ = ["CLASSICAL_AGENTS", "classical_agent"]


# spec -> (module, class), imported only when asked for
CLASSICAL_AGENTS = {"pid_formation": ("agents.pid_formation", "PIDFormation"),
                    "station_keeper": ("agents.station_keeper", "StationKeeper")}


def classical_agent(spec: str, *, layout=None):
    """A fresh instance of the classical agent ``spec`` of ``agents/`` (:data:`CLASSICAL_AGENTS`: ``pid_formation``,
    the formation-keeping controller; ``station_keeper``, the cross-track station keeper), imported only when asked
    for: a stateful, batched agent (``reset(n_rows)``, ``act(obs)``, ``action_mode``, ``control_hz``); ``layout``: the
    :class:`~formation_env.sim.layout.ObservationLayout` its observations have (their optional groups, which their
    length alone does not say)."""
    import importlib

    module, cls = CLASSICAL_AGENTS[spec]
    try:
        agent_class = getattr(importlib.import_module(module), cls)
    except ModuleNotFoundError as exc:
        if exc.name not in (module, "agents"):
            raise
        raise ValueError(f"policy {spec!r} needs {module.replace('.', '/')}.py, which this checkout does not have") from None
    # the layout only where it has optional groups: an agent class flown on plain observations takes no argument
    return agent_class(layout=layout) if layout is not None and layout.optional else agent_class()
