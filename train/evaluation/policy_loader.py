"""Loading the policies to evaluate: ``"pid"`` (the thesis FCS, zero residual), ``"pid_formation"``
(the classical formation-keeping baseline), ``"station_keeper"`` (the cross-track station keeper), an SB3 zip or an RLlib checkpoint / run directory."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from agents.registry import CLASSICAL_AGENTS, classical_agent
from formation_env.sim.layout import ObservationLayout

from ..config import ACTION_MODES
from .policy import EvalPolicy
from ..sb3.config import ALGOS

__all__ = ["CLASSICAL_AGENTS", "classical_agent", "load_policy", "policy_layout"]


def _pid_policy() -> EvalPolicy:
    return EvalPolicy("pid", "residual", lambda obs: np.zeros((obs.shape[0], 4), dtype=np.float32))


def _agent_policy(spec: str) -> EvalPolicy:
    """:func:`classical_agent` as an evaluation policy, whose ``reset(n_rows)`` runs before every batch of episodes."""
    agent = classical_agent(spec)
    return EvalPolicy(spec, str(agent.action_mode), agent.act, float(agent.control_hz), reset=agent.reset)


def _stamp(config: dict) -> dict:
    """The task, version and departures of a run's config.yaml (:func:`train.config.task_stamp`), {} if unreadable."""
    from ..config import task_stamp

    try:
        return task_stamp(config["scenario"], config.get("env_kwargs") or {}, config["action_mode"])
    except (KeyError, TypeError, ValueError):
        return {}


def policy_metadata(path: Path) -> dict:
    """Metadata of a policy zip: its sidecar ``<stem>.json``, else its run's ``config.yaml``."""
    side = path.with_suffix(".json")
    if side.is_file():
        data = json.loads(side.read_text())
        return data.get("env", data)
    for parent in (path.parent, path.parent.parent):
        cfg = parent / "config.yaml"
        if cfg.is_file():
            import yaml

            data = yaml.safe_load(cfg.read_text()) or {}
            data = data.get("config", data)  # a run's config.yaml: {"command", "config": TrainConfig fields}
            return {"algo": data.get("algo"), "action_mode": data.get("action_mode"), "scenario": data.get("scenario"),
                    "control_hz": (data.get("env_kwargs") or {}).get("control_hz", 10.0),
                    "action_guard": (data.get("action_guard") if isinstance(data.get("action_guard"), dict)
                                     else bool(data.get("action_guard", False))),
                    "residual_on": data.get("residual_on"),
                    **{k: True for k in ObservationLayout.from_dict(None, data.get("env_kwargs") or {}).options},
                    **_stamp(data)}
    return {}


def policy_layout(meta: dict) -> ObservationLayout:
    """The observation layout a policy's metadata records (its ``observation``); metadata written before layouts
    were recorded: the one its observation switches give (``neighbour_wind: true``, ...), any formation."""
    return ObservationLayout.from_dict(meta.get("observation"), meta)


def warn_task_version(spec: str, meta: dict) -> str | None:
    """Warn (``UserWarning``) when a policy was trained on another version of its task than the registered one,
    or on a scenario whose task version it does not record; returns the warning's text (None: no warning)."""
    import warnings

    from formation_env.tasks import task_for_scenario

    task = task_for_scenario(meta.get("scenario"))
    if task is None:
        return None
    trained = meta.get("task_version")
    if trained == task.version:
        return None
    what = "an unrecorded version" if trained is None else f"version {trained}"
    text = (f"policy {spec!r} was trained on {what} of task {task.name!r}, not on {task.gym_id or task.name} "
            f"(version {task.version}): its results are not comparable with this version's")
    warnings.warn(text, UserWarning, stacklevel=3)
    return text


def load_policy(spec: str, *, action_mode: str | None = None, name: str | None = None, device: str = "cpu") -> EvalPolicy:
    """``"pid"`` (the thesis FCS: zero residual), ``"pid_formation"`` (the classical formation-keeping
    baseline of ``agents.pid_formation``), ``"station_keeper"`` (``agents.station_keeper``), the path of an SB3 zip (its algo and action mode come from
    the sidecar JSON or the run's config.yaml; ``action_mode`` overrides; a recurrent PPO's ``reset(n_rows)`` starts
    its LSTM state, which ``act`` carries from one decision to the next), or an RLlib checkpoint / run
    directory of ``formation-env train --backend rllib`` (its metadata fixes the action mode).

    Security: an SB3 zip is read without unpickling anything (:mod:`train.evaluation.safe_zip`; a file that is not
    one of this project's is a ``ValueError`` saying it is not a readable policy). An RLlib checkpoint is restored
    by Ray, which unpickles it: it runs code, so load only checkpoints you trust (docs/reliability.md)."""
    if spec == "pid":
        return _pid_policy()
    if spec in CLASSICAL_AGENTS:
        return _agent_policy(spec)
    path = Path(spec)
    if path.is_dir():
        # An RLlib checkpoint (or run directory); ray is imported only here, and only then.
        from ..rllib.checkpoints import is_rllib_checkpoint
        from ..rllib.policy import load_rllib_policy

        if not is_rllib_checkpoint(path):
            raise ValueError(f"policy directory {spec!r} is not an RLlib checkpoint or run directory of this project")
        pol = load_rllib_policy(path, name=name)
        if action_mode is not None and action_mode != pol.action_mode:
            raise ValueError(f"policy {spec!r} was trained with {pol.action_mode!r} actions, not {action_mode!r} "
                             "(an RLlib checkpoint's metadata fixes its action mode; leave out --action-mode)")
        return pol
    if not path.is_file():
        raise ValueError(f"policy file {spec!r} does not exist (give an SB3 .zip, an RLlib checkpoint directory, "
                         "'pid', 'pid_formation' or 'station_keeper')")
    from .safe_zip import load_sb3_model, read_policy_zip

    read_policy_zip(path, repr(spec))  # not a zip, truncated or corrupt: one line saying so, before anything else
    meta = policy_metadata(path)
    warn_task_version(spec, meta)
    mode = action_mode or meta.get("action_mode")
    if mode is None:
        raise ValueError(f"policy {spec!r}: its action mode is unknown (no {path.with_suffix('.json').name} or "
                         "config.yaml beside it); pass --action-mode")
    if mode not in ACTION_MODES:
        raise ValueError(f"unknown action mode {mode!r}; choose one of {ACTION_MODES}")
    algo = meta.get("algo")
    # no pickle in the zip is unpickled (train/evaluation/safe_zip.py): a policy file cannot run code on load
    model = load_sb3_model(path, algo if algo in ALGOS else None, device=device, label=repr(spec))
    from ..recurrent import chain_resets, model_policy

    # a recurrent policy's reset(n_rows) starts its LSTM state, carried across the decisions of an episode batch
    act, reset = model_policy(model)
    try:
        layout = policy_layout(meta)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"policy {spec!r}: its metadata's observation: {exc}") from None
    if meta.get("residual_on") is not None:  # a residual on a classical agent: the agent is part of the policy
        if mode != "setpoints":
            raise ValueError(f"policy {spec!r}: its metadata's residual_on adds to set-points, but it is flown with "
                             f"{mode!r} actions")
        from ..sb3.residual import residual_policy

        try:
            act, agent_reset = residual_policy(act, meta["residual_on"], layout=layout)
            reset = chain_resets(reset, agent_reset)
        except ValueError as exc:
            raise ValueError(f"policy {spec!r}: its metadata's {exc}") from None
    if meta.get("action_guard"):  # trained with the separation guard in the loop: it is part of the policy
        if mode != "setpoints":
            raise ValueError(f"policy {spec!r}: its metadata asks for the separation guard, which filters set-point "
                             f"actions, but it is flown with {mode!r} actions")
        from ..sb3.guard import guarded

        try:
            # True: the default gains; a mapping: the sidecar's (told the observation's layout: the policy's)
            act = guarded(act, meta["action_guard"], layout=layout)
        except ValueError as exc:
            raise ValueError(f"policy {spec!r}: its metadata's action_guard: {exc}") from None
    return EvalPolicy(name or path.stem, mode, act, float(meta.get("control_hz", 10.0) or 10.0), str(path), reset=reset,
                      observation=layout)
