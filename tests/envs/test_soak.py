"""Soak: a vector env of formations stepped for many decisions with random and extreme actions (uniform in the
Box, out-of-range values the env clips, the bounds, sudden reversals, bang-bang) on every task: no observation,
reward or info is ever non-finite (a lone UAV's distance to its nearest neighbour is +inf, as documented: there is
none), and the process's memory stays flat after a warm-up.

The suite runs a short form (a few formations, a few hundred decisions per task). The long form is this file run
as a script: ``python tests/envs/test_soak.py --formations 256 --minutes 15`` (every task in turn, 15 minutes of
this process's CPU time shared among them; ``--decisions N`` caps the vector steps per task), printing one JSON line per task and a summary."""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np
import pytest

from formation_env.envs import FormationVecEnv
from formation_env.tasks import task_names


def rss_bytes() -> int:
    """Resident memory of this process (Linux /proc; 0 elsewhere)."""
    try:
        with open("/proc/self/statm") as fh:
            import os

            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


def extreme_actions(rng: np.random.Generator, k: int, n: int, previous: np.ndarray) -> np.ndarray:
    """The k-th decision's (n, 4) actions: a cycle of uniform, out-of-range (clipped), the bounds, a sudden
    reversal of the last actions, bang-bang on one axis, huge finite values, zeros."""
    kind = k % 7
    if kind == 0:
        return rng.uniform(-1.0, 1.0, (n, 4)).astype(np.float32)
    if kind == 1:
        return rng.uniform(-5.0, 5.0, (n, 4)).astype(np.float32)  # clipped to [-1, 1]
    if kind == 2:
        return rng.choice(np.array([-1.0, 1.0], np.float32), (n, 4))
    if kind == 3:
        return -previous  # a sudden reversal
    if kind == 4:
        a = np.zeros((n, 4), np.float32)
        a[:, k % 4] = 1.0 if (k // 7) % 2 else -1.0
        return a
    if kind == 5:
        return rng.choice(np.array([-3e38, 3e38], np.float32), (n, 4))  # float32's extremes, clipped
    return np.zeros((n, 4), np.float32)


def _finite(key: str, value, alone: bool) -> bool:
    """Finite, but for a lone UAV's distance to its nearest neighbour, documented as +inf (there is none)."""
    if alone and key == "min_separation_m":
        return not np.any(np.isnan(value)) and np.all(np.isfinite(value) | (value == np.inf))
    return bool(np.all(np.isfinite(value)))


def _non_finite_infos(sim) -> list[str]:
    bad = []
    for name in dir(type(sim.info)):
        if name.startswith("_") or not isinstance(getattr(type(sim.info), name), property):
            continue
        value = getattr(sim.info, name)
        if isinstance(value, np.ndarray) and value.dtype.kind in "fc" and not _finite(name, value, sim.n_vehicles == 1):
            bad.append(name)
    return bad


def soak(task: str, n_formations: int, decisions: int, *, seed: int = 0, seconds: float | None = None,
         detailed_every: int = 50) -> dict:
    """Step ``task``'s vector env ``decisions`` times (or until ``seconds`` of this process's CPU time pass); returns
    the figures and raises
    AssertionError at the first non-finite value. Memory: resident size after the first fifth of the decisions (or
    of the CPU time) as the warm-up, and at the end."""
    venv = FormationVecEnv(n_formations, scenario=task, seed=seed, detailed_infos=False)
    rng = np.random.default_rng(seed)
    obs = venv.reset()
    assert np.all(np.isfinite(obs)), f"{task}: non-finite observation at reset"
    act = np.zeros((venv.num_envs, 4), np.float32)
    warm = max(decisions // 5, 1)
    rss_warm = rss_end = 0
    episodes = 0
    t0, c0 = time.perf_counter(), time.process_time()
    k = 0
    for k in range(decisions):
        act = extreme_actions(rng, k, venv.num_envs, act)
        venv.detailed_infos = (k % detailed_every == detailed_every - 1)
        obs, rew, done, infos = venv.step(act)
        assert np.all(np.isfinite(obs)), f"{task}: non-finite observation at decision {k}"
        assert np.all(np.isfinite(rew)), f"{task}: non-finite reward at decision {k}"
        bad = _non_finite_infos(venv.batch.sim)
        assert not bad, f"{task}: non-finite info {bad} at decision {k}"
        for i in np.nonzero(done)[0]:
            episodes += 1
            assert np.all(np.isfinite(infos[i]["terminal_observation"])), f"{task}: terminal observation at {k}"
            assert np.isfinite(infos[i]["episode"]["r"]), f"{task}: episode return at {k}"
        if venv.detailed_infos:
            for info in infos:
                for key, v in info.items():
                    if isinstance(v, (float, np.ndarray)) and not _finite(key, v, venv.batch.sim.n_vehicles == 1):
                        raise AssertionError(f"{task}: non-finite info {key!r} at decision {k}")
        used = time.process_time() - c0
        if not rss_warm and (k + 1 == warm if seconds is None else used > seconds / 5):  # the warm-up's end
            rss_warm = rss_bytes()
        if seconds is not None and used > seconds and rss_warm:
            break
    rss_end = rss_bytes()
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    venv.close()
    steps = k + 1
    return {"task": task, "formations": n_formations, "vector_steps": steps,
            "formation_decisions": steps * n_formations, "agent_steps": steps * venv.num_envs,
            "episodes_ended": episodes, "wall_s": round(wall, 1), "cpu_s": round(cpu, 1), "rss_warm_mb": round(rss_warm / 2**20, 1),
            "rss_end_mb": round(rss_end / 2**20, 1),
            "rss_growth": round((rss_end - rss_warm) / rss_warm, 4) if rss_warm else 0.0}


@pytest.mark.parametrize("task", task_names())
def test_soak_short_form(task):
    """4 formations, 160 decisions with every kind of extreme action: finite throughout; memory within 5 %."""
    r = soak(task, 4, 160, seed=1, detailed_every=20)
    assert r["vector_steps"] == 160
    assert r["rss_growth"] < 0.05, r


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description="the soak's long form (module docstring)")
    p.add_argument("--formations", type=int, default=256)
    p.add_argument("--minutes", type=float, default=15.0, help="CPU time (one core) shared among the tasks")
    p.add_argument("--decisions", type=int, default=10**6, help="most vector steps per task")
    p.add_argument("--tasks", nargs="*", default=None)
    args = p.parse_args(argv)
    tasks = args.tasks or task_names()
    per_task = args.minutes * 60.0 / len(tasks)
    rows = []
    for task in tasks:
        r = soak(task, args.formations, args.decisions, seconds=per_task)
        rows.append(r)
        print(json.dumps(r), flush=True)
    total = {"tasks": len(rows), "formation_decisions": sum(r["formation_decisions"] for r in rows),
             "agent_steps": sum(r["agent_steps"] for r in rows), "wall_s": round(sum(r["wall_s"] for r in rows), 1),
             "cpu_s": round(sum(r["cpu_s"] for r in rows), 1),
             "max_rss_growth": max(r["rss_growth"] for r in rows), "non_finite": 0}
    print(json.dumps(total), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
