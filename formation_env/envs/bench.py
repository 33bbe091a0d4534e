"""Environment benchmarks: the single PettingZoo env and the batched vector env, 2 UAVs in
formation_keeping with the wake on. Medians of repeated runs; no assertions."""

from __future__ import annotations

import time

import numpy as np

__all__ = ["run_benchmarks"]

PEERS = {
    "PyFlyt 2-aircraft dogfight (joint steps/s)": 408,
    "gym-pybullet-drones, 4 drones with downwash (steps/s)": 688,
    "VMAS CPU flocking, 1,024 envs (env-steps/s)": 44_500,
    "JaxMARL MPE CPU (env-steps/s)": 443_000,
}


def _median(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def _single_env(mode: str, decisions: int, repeats: int) -> dict:
    import formation_env

    env = formation_env.parallel_env("formation_keeping", action_mode=mode)
    zero = {a: np.zeros(4, np.float32) for a in env.possible_agents}
    env.reset(seed=0)

    def run():
        for _ in range(decisions):
            if not env.agents:
                env.reset(seed=0)
            env.step(zero)

    run()  # compile/warm up
    t = _median(run, repeats)
    physics = decisions * env.substeps / t
    return {"action_mode": mode, "decisions_per_s": decisions / t, "physics_steps_per_s": physics,
            "uav_physics_steps_per_s": 2 * physics, "real_time_factor": physics * env.engine.dt}


def _vector(n_formations: int, mode: str, decisions: int, repeats: int, wake_update_every: int = 1) -> dict:
    from .vector import FormationVecEnv

    venv = FormationVecEnv(n_formations, scenario="formation_keeping", learning="all", action_mode=mode, seed=0,
                           wake_update_every=wake_update_every)
    venv.reset()
    act = np.zeros((venv.num_envs, 4), np.float32)

    def run():
        for _ in range(decisions):
            venv.step(act)

    run()
    t = _median(run, repeats)
    sub = venv.batch.core.substeps
    physics = n_formations * decisions * sub / t
    return {"formations": n_formations, "action_mode": mode, "wake_hz": 50.0 / wake_update_every,
            "formation_physics_steps_per_s": physics,
            "uav_physics_steps_per_s": 2 * physics, "real_time_factor_per_formation": decisions * sub * 0.02 / t,
            "agent_decisions_per_s": venv.num_envs * decisions / t}


def run_benchmarks(quick: bool = False) -> dict:
    reps = 3 if quick else 5
    out = {"case": "formation_keeping, 2 Aerosondes, ELL wake on every 50 Hz physics step, 10 Hz decisions",
           "single_env": [_single_env("surfaces", 50 if quick else 300, reps),
                          _single_env("residual", 20 if quick else 100, reps)],
           "vector_env": [], "peers_reported": PEERS}
    sizes = (1, 64) if quick else (1, 64, 1024)
    for n in sizes:
        out["vector_env"].append(_vector(n, "surfaces", 5 if n >= 1024 else 20, reps))
    if not quick:
        out["vector_env"].append(_vector(1024, "surfaces", 5, reps, wake_update_every=2))
        out["vector_env"].append(_vector(64, "residual", 10, reps))
        out["vector_env"].append(_vector(1024, "residual", 3, 3))
    return out
