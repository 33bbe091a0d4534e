"""The classical agents by name: the evaluation (``--policy station_keeper``) and the residual learners
(``residual_on: {agent: ...}``) build them here, so that neither imports the other."""

from __future__ import annotations

__all__ = ["CLASSICAL_AGENTS", "classical_agent"]


# spec -> (module, class), imported only when asked for
CLASSICAL_AGENTS = {"pid_formation": ("agents.pid_formation", "PIDFormation"),
                    "station_keeper": ("agents.station_keeper", "StationKeeper")}


def classical_agent(spec: str, *, neighbour_wind: bool = False, neighbour_attitude: bool = False):
    """A fresh instance of the classical agent ``spec`` of ``agents/`` (:data:`CLASSICAL_AGENTS`: ``pid_formation``,
    the formation-keeping controller; ``station_keeper``, the cross-track station keeper), imported only when asked
    for: a stateful, batched agent (``reset(n_rows)``, ``act(obs)``, ``action_mode``, ``control_hz``); ``neighbour_wind``:
    its observations carry the neighbours' winds (EnvConfig.neighbour_wind), which their length alone does not say;
    ``neighbour_attitude`` their attitudes."""
    import importlib

    module, cls = CLASSICAL_AGENTS[spec]
    try:
        agent_class = getattr(importlib.import_module(module), cls)
    except ModuleNotFoundError as exc:
        if exc.name not in (module, "agents"):
            raise
        raise ValueError(f"policy {spec!r} needs {module.replace('.', '/')}.py, which this checkout does not have") from None
    # the layout flag only where it is set: an agent class flown on plain observations takes no argument
    flags = {k: True for k, on in (("neighbour_wind", neighbour_wind), ("neighbour_attitude", neighbour_attitude)) if on}
    return agent_class(**flags)
