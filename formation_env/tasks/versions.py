"""Task versions held mechanically: each Gymnasium id's behaviour has a fingerprint, recorded once per version.

:func:`fingerprint` flies a short seeded episode of ``gym.make(id)`` (the task's benchmark configuration) with a
fixed sequence of actions drawn uniformly over the action space, and summarises what a learner sees: the sums of
the observations, their squares and absolute values, the rewards, the decision at which the episode ended and how.
``formation_env/data/task_versions.json`` holds the fingerprint of every id (each version its own entry, kept as
history). ``tests/tasks/test_task_versions.py`` flies every registered id and compares: a change of behaviour
without a version bump (``Task.version``, hence a new id) fails. :func:`record_new_versions` adds the entries of
ids not yet in the table and never rewrites an existing one.
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import numpy as np

__all__ = ["VERSIONS_FILE", "FINGERPRINT_DECISIONS", "FINGERPRINT_RTOL", "fingerprint", "load_versions",
           "record_new_versions", "compare"]

VERSIONS_FILE = Path(__file__).resolve().parents[1] / "data" / "task_versions.json"
#: decisions flown per fingerprint (4 s at 10 Hz): long enough for every term of the reward to act
FINGERPRINT_DECISIONS = 40
#: relative tolerance of the comparison: far above the last bits a compiler or CPU may change, far below any change
#: of reward weight, randomisation, observation or dynamics (those move the sums by 1e-3 or more)
FINGERPRINT_RTOL = 1e-6
_SEED = 20_260_000
_ACTION_SEED = 7


def fingerprint(gym_id: str, decisions: int = FINGERPRINT_DECISIONS) -> dict:
    """The fingerprint of ``gym_id`` (registered in Gymnasium): a dict of summary numbers and a short ``digest``
    of them rounded to 6 significant digits (for display; the comparison uses the numbers)."""
    import gymnasium as gym

    if isinstance(decisions, bool) or not isinstance(decisions, int) or not 1 <= decisions <= 100_000:
        raise ValueError(f"fingerprint: decisions must be an integer in [1, 100000], got {decisions!r}")
    env = gym.make(gym_id)
    try:
        space = env.action_space
        rng = np.random.default_rng(_ACTION_SEED)
        obs, _ = env.reset(seed=_SEED)
        obs_list, rewards, end, how = [np.asarray(obs, dtype=float).ravel()], [], decisions, "running"
        for k in range(decisions):
            action = rng.uniform(space.low, space.high).astype(space.dtype)
            obs, reward, terminated, truncated, _ = env.step(action)
            obs_list.append(np.asarray(obs, dtype=float).ravel())
            rewards.append(float(reward))
            if terminated or truncated:
                end, how = k + 1, "terminated" if terminated else "truncated"
                break
        o = np.concatenate(obs_list)
        r = np.asarray(rewards)
        out = {"obs_dim": int(obs_list[0].size), "action_dim": int(np.prod(space.shape)),
               "max_episode_steps": env.spec.max_episode_steps if env.spec is not None else None,
               "decisions": end, "end": how,
               "obs_sum": float(o.sum()), "obs_abs_sum": float(np.abs(o).sum()), "obs_sq_sum": float((o * o).sum()),
               "reward_sum": float(r.sum()), "reward_sq_sum": float((r * r).sum()),
               "reward_last": float(r[-1]) if r.size else 0.0}
    finally:
        env.close()
    rounded = {k: (float(f"{v:.6g}") if isinstance(v, float) else v) for k, v in out.items()}
    out["digest"] = hashlib.sha256(json.dumps(rounded, sort_keys=True).encode()).hexdigest()[:16]
    return out


def load_versions(path: Path = VERSIONS_FILE) -> dict:
    """The table: id -> {"task", "version", "fingerprint"}."""
    return json.loads(Path(path).read_text(encoding="utf-8")) if Path(path).is_file() else {}


def compare(recorded: dict, measured: dict, rtol: float = FINGERPRINT_RTOL) -> list[str]:
    """The fields on which ``measured`` differs from ``recorded`` (beyond ``rtol`` for the numbers)."""
    bad = []
    for k, v in recorded.items():
        if k == "digest":
            continue
        m = measured.get(k)
        if isinstance(v, float) and isinstance(m, float):
            if not math.isclose(v, m, rel_tol=rtol, abs_tol=rtol):
                bad.append(f"{k}: recorded {v!r}, now {m!r}")
        elif v != m:
            bad.append(f"{k}: recorded {v!r}, now {m!r}")
    return bad


def record_new_versions(path: Path = VERSIONS_FILE) -> list[str]:
    """Add the fingerprint of every registered id not yet in the table (written atomically); an existing entry is
    never rewritten: a task whose behaviour changed needs a new version. Returns the ids added."""
    from . import TASKS

    table = load_versions(path)
    added = []
    for task in TASKS.values():
        if task.gym_id is None or task.gym_id in table:
            continue
        table[task.gym_id] = {"task": task.name, "version": task.version, "fingerprint": fingerprint(task.gym_id)}
        added.append(task.gym_id)
    if added:
        tmp = Path(path).with_suffix(".tmp")
        tmp.write_text(json.dumps(dict(sorted(table.items())), indent=1) + "\n", encoding="utf-8")
        tmp.replace(path)
    return added

