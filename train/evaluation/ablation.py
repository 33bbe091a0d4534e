"""Observation ablation (issue 24): what a learned policy flies on. An ablated copy of a policy sees some
observation groups (:data:`formation_env.envs.observations.GROUPS`) set to zero, the value each group takes
at the slot in calm, trimmed flight for the error and wind groups (the observation is a signed log of the
physical value, so zero is "no error, no wind"); it is evaluated on the same episodes as the policy itself.

Zeroing an input takes the policy out of its training distribution, so an ablation measures how much of the
policy's score depends on that input, not what the policy would do had it been trained without it."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from formation_env.envs.observations import GROUPS, group_sizes

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


def ablated(policy: EvalPolicy, groups: Sequence[str], n_vehicles: int, neighbour_count: int | None = None,
            neighbour_wind: bool = False, neighbour_attitude: bool = False) -> EvalPolicy:
    """A copy of ``policy`` whose observation has ``groups`` zeroed (formation of ``n_vehicles`` UAVs observing
    ``neighbour_count`` neighbours, and their winds with ``neighbour_wind`` and attitudes with ``neighbour_attitude``,
    as the env's options)."""
    groups = parse_ablation(groups)
    sizes = group_sizes(n_vehicles, neighbour_count, neighbour_wind, neighbour_attitude)
    mask, k = [], 0
    for name, size in sizes.items():
        if name in groups:
            if size == 0:
                raise ValueError(f"ablation: group {name!r} is empty in a formation of {n_vehicles} UAVs")
            mask.extend(range(k, k + size))
        k += size
    cols = np.asarray(mask, dtype=np.int64)
    act = policy.act

    def masked(obs: np.ndarray) -> np.ndarray:
        o = np.array(obs, copy=True)
        if o.shape[-1] != k:
            raise ValueError(f"ablated policy {policy.name!r}: observation length {o.shape[-1]}, expected {k} "
                             f"for {n_vehicles} UAVs")
        o[..., cols] = 0.0
        return act(o)

    return EvalPolicy(name=ablation_name(policy.name, groups), action_mode=policy.action_mode, act=masked,
                      control_hz=policy.control_hz, path=policy.path, reset=policy.reset,
                      neighbour_wind=policy.neighbour_wind, neighbour_attitude=policy.neighbour_attitude)
