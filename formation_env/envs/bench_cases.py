"""Benchmark cases on the public env API only, so the same file measures this checkout and an older
one (:mod:`formation_env.envs.bench` runs a copy of this file as a script, ``bench_cases_script.py CASES_JSON``, with
either checkout first on ``PYTHONPATH``, both in the same session; an older checkout has no ``formation-env``
subcommand for it).

A case is a dict: ``{"kind": "single", "mode": ..., "learning": ...}`` (PettingZoo parallel env,
B = 1) or ``{"kind": "vector", "formations": B, "mode": ..., "learning": ..., "wake_update_every": k,
"benefit": bool, "turbulence": field name, "sigma": m/s, "scenario": name, "task_file": path}`` (SB3 VecEnv;
turbulence of that field at sigma, default 1 m/s; scenario default formation_keeping, e.g. ``vee5`` for a formation
of 5; ``task_file``: a Python file of the checkout that registers the scenario's task, e.g. examples/custom_task.py) or ``{"kind": "machine"}`` (a fixed numpy workload: the machine's own timing spread). A
vector case also reports the spread of 40 consecutive decisions timed one by one. A case the code under test cannot build (an older checkout without a newer option) gives
``{"unsupported": reason}`` instead of figures. All cases: formation_keeping, 2 Aerosondes, wake on, 10 Hz
decisions (5 physics steps each), unless a vector case names another scenario. Result: the best of ``repeats`` timed runs after a warm-up run
(best, not median: on a shared 2-core machine the slower runs measure the neighbours).
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

__all__ = ["run_case", "run_cases"]


def _calibrated(step, budget_s: float, repeats: int) -> tuple[int, float]:
    """``(n, best time of n calls of step())``: after a warm-up (compilation), n is chosen so that one
    timed run lasts about ``budget_s`` whatever the code's speed (older code may be 10x slower)."""
    step()
    t0 = time.perf_counter()
    k = 0
    while k < 3 or time.perf_counter() - t0 < 0.05 * budget_s:
        step()
        k += 1
    n = max(2, int(budget_s * k / max(time.perf_counter() - t0, 1e-9)))
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n):
            step()
        times.append(time.perf_counter() - t0)
    return n, float(min(times))


def _single(case: dict, budget_s: float, repeats: int) -> dict:
    import formation_env

    env = formation_env.parallel_env("formation_keeping", action_mode=case["mode"], learning=case["learning"])
    zero = {a: np.zeros(4, np.float32) for a in env.possible_agents}
    env.reset(seed=0)
    substeps = env.substeps

    def one():
        if not env.agents:
            env.reset(seed=0)
        env.step(zero)

    decisions, t = _calibrated(one, budget_s, repeats)
    physics = decisions * substeps / t
    return {**case, "decisions_per_s": decisions / t, "physics_steps_per_s": physics,
            "uav_physics_steps_per_s": 2 * physics}


def _vector(case: dict, budget_s: float, repeats: int) -> dict:
    from formation_env.envs.vector import FormationVecEnv

    n = int(case["formations"])
    opts = {"wake_update_every": case.get("wake_update_every", 1)}
    if case.get("benefit"):
        opts["compute_benefit"] = True
    if case.get("turbulence"):
        from formation_env.sim.config import Randomisation

        opts["turbulence_field"] = case["turbulence"]
        opts["randomisation"] = Randomisation(turbulence_sigma_mps=case.get("sigma", 1.0))
    if case.get("task_file"):  # a task defined in a Python file of the checkout (registered on import)
        import importlib.util
        import os

        path = os.path.join(os.environ.get("FORMATION_ENV_BENCH_ROOT", "."), case["task_file"])
        if not os.path.isfile(path):
            return {**case, "unsupported": f"no {case['task_file']} in this checkout"}
        spec = importlib.util.spec_from_file_location("bench_task_file", path)
        spec.loader.exec_module(importlib.util.module_from_spec(spec))
    try:
        venv = FormationVecEnv(n, scenario=case.get("scenario", "formation_keeping"), learning=case["learning"],
                               action_mode=case["mode"], seed=0, **opts)
    except (TypeError, ValueError, KeyError) as exc:  # an older checkout without this option or scenario
        return {**case, "unsupported": f"{type(exc).__name__}: {exc}"}
    venv.reset()
    act = np.zeros((venv.num_envs, 4), np.float32)
    decisions, t = _calibrated(lambda: venv.step(act), budget_s, repeats)
    physics = n * decisions * 5 / t
    from formation_env.scenarios import get_scenario

    uavs = get_scenario(case.get("scenario", "formation_keeping")).n_vehicles
    return {**case, "uavs": uavs, "formation_physics_steps_per_s": physics, "uav_physics_steps_per_s": uavs * physics,
            "agent_decisions_per_s": venv.num_envs * decisions / t, **_spread(lambda: venv.step(act))}


SPREAD_DECISIONS = 40  # issue 26: the slowest over the fastest of 40 consecutive decisions


def _spread(call, k: int = SPREAD_DECISIONS) -> dict:
    """Each of ``k`` consecutive calls timed alone (after the calibration's warm calls): the spread a user
    sees from one decision to the next (min, median, max in ms and max / min)."""
    times = []
    for _ in range(k):
        t0 = time.perf_counter()
        call()
        times.append(time.perf_counter() - t0)
    w = np.asarray(times) * 1e3
    return {"decision_ms_min": float(w.min()), "decision_ms_median": float(np.median(w)),
            "decision_ms_max": float(w.max()), "decision_max_over_min": float(w.max() / w.min())}


def _machine(case: dict, budget_s: float, repeats: int) -> dict:
    """The machine's own spread, for scale: a fixed numpy workload (the same matrix products every call, about
    the time of a B = 1,024 decision) timed as :func:`_spread` times decisions; nothing of formation_env runs."""
    rng = np.random.default_rng(0)
    a, b = rng.standard_normal((700, 700)), rng.standard_normal((700, 700))

    def call():
        c = a
        for _ in range(int(case.get("products", 10))):
            c = np.tanh(c @ b * 1e-2)
        return c

    call()
    return {**case, **_spread(call)}


def run_case(case: dict, budget_s: float = 0.5, repeats: int = 3) -> dict:
    if case["kind"] == "single":
        return _single(case, budget_s, repeats)
    if case["kind"] == "vector":
        return _vector(case, budget_s, repeats)
    if case["kind"] == "machine":
        return _machine(case, budget_s, repeats)
    raise ValueError(f"unknown bench case kind {case['kind']!r}")


PROGRESS = "bench-case"  # stderr line "bench-case K N" before case K (0-based) of N: formation_env.envs.bench


def run_cases(cases: list[dict], budget_s: float = 0.5, repeats: int = 3, progress=None) -> list[dict]:
    """Every case in order; ``progress(k, n)`` is called before case k (outside any timing)."""
    out = []
    for k, c in enumerate(cases):
        if progress is not None:
            progress(k, len(cases))
        out.append(run_case(c, budget_s, repeats))
    return out


def _progress_line(k: int, n: int) -> None:
    print(f"{PROGRESS} {k} {n}", file=sys.stderr, flush=True)


if __name__ == "__main__":  # pragma: no cover - driven by formation_env.envs.bench in a subprocess
    spec = json.loads(sys.argv[1])
    print(json.dumps(run_cases(spec["cases"], spec.get("budget_s", 0.5), spec.get("repeats", 3), _progress_line)))
