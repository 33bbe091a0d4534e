"""Observation ablation (issue 24): what a learned policy flies on. An ablated copy of a policy sees some
observation groups (:data:`formation_env.envs.observations.GROUPS`) set to zero, the value each group takes
at the slot in calm, trimmed flight for the error and wind groups (the observation is a signed log of the
physical value, so zero is "no error, no wind"); it is evaluated on the same episodes as the policy itself.

Zeroing an input takes the policy out of its training distribution, so an ablation measures how much of the
policy's score depends on that input, not what the policy would do had it been trained without it."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from formation_env.envs.observations import GROUPS, ObservationLayout

from .policy import EvalPolicy

__all__ = ["ablated", "parse_ablation", "ablation_name"]


def parse_ablation(spec: str | Sequence[str]) -> tuple[str, ...]:
    """``"induced_wind,induced_rotation"`` (or a sequence of names) -> the group names, checked against
    :data:`GROUPS`; a ValueError naming a bad or repeated name and the allowed ones."""
    names = [s.strip() for s in (spec.split(",") if isinstance(spec, str) else spec)]
    if not names or any(not n for n in names):
        raise ValueError(f"ablation {spec!r}: give observation group names separated by commas, from {list(GROUPS)}")
    bad = [n for n in names if n not in GROUPS]
    if bad:
        raise ValueError(f"ablation {spec!r}: unknown observation group(s) {bad}; allowed: {list(GROUPS)}")
    if len(set(names)) != len(names):
        raise ValueError(f"ablation {spec!r}: a group is named twice")
    return tuple(names)


def ablation_name(policy_name: str, groups: Sequence[str]) -> str:
    return f"{policy_name}-without-{'+'.join(groups)}"


def ablated(policy: EvalPolicy, groups: Sequence[str], layout: ObservationLayout) -> EvalPolicy:
    """A copy of ``policy`` whose observation has ``groups`` zeroed (``layout``: the observations' groups, the env's
    :attr:`~formation_env.sim.simulation.Simulation.observation_layout`)."""
    groups = parse_ablation(groups)
    sizes = layout.groups
    absent = [name for name in groups if name not in sizes]
    if absent:
        raise ValueError(f"ablation: group(s) {absent} are not in the observation (its groups: {list(sizes)})")
    empty = [name for name in groups if sizes[name] == 0]
    if empty:
        raise ValueError(f"ablation: group {empty[0]!r} is empty in a formation of {layout.neighbours + 1} UAVs")
    cols = np.concatenate([np.arange(layout.size)[layout.slice(name)] for name in groups]).astype(np.int64)
    size, act = layout.size, policy.act

    def masked(obs: np.ndarray) -> np.ndarray:
        o = np.array(obs, copy=True)
        if o.shape[-1] != size:
            raise ValueError(f"ablated policy {policy.name!r}: observation length {o.shape[-1]}, expected {size} "
                             f"for {layout.neighbours} observed neighbours")
        o[..., cols] = 0.0
        return act(o)

    return EvalPolicy(name=ablation_name(policy.name, groups), action_mode=policy.action_mode, act=masked,
                      control_hz=policy.control_hz, path=policy.path, reset=policy.reset, observation=policy.observation)
