"""The peers' own environments timed on this machine (``formation-env bench --peers``): VMAS's flocking scenario,
1,024 formations of 4 agents on the CPU (2-D point masses, vectorised over the batch with torch), and PyFlyt's
fixed-wing dogfight with one aircraft a team (two aircraft, pybullet rigid bodies), each stepped with actions drawn
once at random, the step loop timed as formation-env's own cases are (median of repeated timed windows).

Run as a script by :func:`formation_env.envs.bench.run_peers` with the interpreter the peers are installed in (a
virtual environment of their own where their pins clash with formation-env's: PyFlyt needs numpy < 2): it imports
neither formation_env nor anything the peer does not need, and prints one JSON line, a row per peer, each either
its figures or ``{"unsupported": why}`` (not installed, or its API differs from the one timed here).
"""

from __future__ import annotations

import json
import statistics
import sys
import time

AGENT_HZ = 30  # PyFlyt's default decision rate
#: (peer, what one step is) in the order measured
PEERS = (("VMAS flocking", "1,024 envs x 4 agents, CPU"), ("PyFlyt fixed-wing dogfight", "2 aircraft (team_size=1)"))


def _version(distribution: str) -> str:
    from importlib import metadata

    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:  # imported from a source tree, not installed
        return "?"


def _timed(step, budget_s: float, repeats: int) -> float:
    """Median steps/s of ``repeats`` windows of about ``budget_s`` seconds each (after a few untimed steps)."""
    for _ in range(3):
        step()
    rates = []
    for _ in range(repeats):
        n, t0 = 0, time.perf_counter()
        while True:
            step()
            n += 1
            dt = time.perf_counter() - t0
            if dt >= budget_s:
                break
        rates.append(n / dt)
    return statistics.median(rates)


def vmas_flocking(budget_s: float, repeats: int, threads: int, envs: int = 1024, agents: int = 4) -> dict:
    import torch
    import vmas

    torch.set_num_threads(threads)
    env = vmas.make_env("flocking", num_envs=envs, device="cpu", continuous_actions=True, seed=0, n_agents=agents)
    env.reset()
    gen = torch.Generator().manual_seed(0)
    actions = [(torch.rand((envs, 2), generator=gen) * 2 - 1) * env.agents[0].u_range for _ in env.agents]
    rate = _timed(lambda: env.step(actions), budget_s, repeats)
    return {"env_steps_per_s": rate * envs, "agent_steps_per_s": rate * envs * agents, "batch_steps_per_s": rate,
            "envs": envs, "agents": agents, "torch": torch.__version__, "version": _version("vmas")}


def pyflyt_dogfight(budget_s: float, repeats: int, threads: int) -> dict:
    import numpy as np
    from PyFlyt.pz_envs import MAFixedwingDogfightEnvV2

    env = MAFixedwingDogfightEnvV2(team_size=1, agent_hz=AGENT_HZ)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = {a: rng.uniform(env.action_space(a).low, env.action_space(a).high).astype(np.float32)
               for a in env.possible_agents}

    def step() -> None:
        _, _, terms, truncs, _ = env.step({a: actions[a] for a in env.agents})
        if not env.agents or any(terms.values()) or any(truncs.values()):
            env.reset(seed=0)

    rate = _timed(step, budget_s, repeats)
    env.close()
    return {"joint_steps_per_s": rate, "aircraft": len(env.possible_agents), "agent_hz": AGENT_HZ,
            "version": _version("PyFlyt")}


def measure(budget_s: float, repeats: int, threads: int) -> list[dict]:
    rows = []
    for (name, what), fn in zip(PEERS, (vmas_flocking, pyflyt_dogfight)):
        row = {"peer": name, "case": what}
        try:
            row.update(fn(budget_s, repeats, threads))
        except ImportError as e:
            row["unsupported"] = f"not installed in {sys.executable} ({e})"
        except Exception as e:  # noqa: BLE001  (another release's API: reported, not fatal to the benchmark)
            row["unsupported"] = f"{type(e).__name__}: {e}"
        rows.append(row)
    return rows


if __name__ == "__main__":
    args = json.loads(sys.argv[1])
    print(json.dumps(measure(args["budget_s"], args["repeats"], args["threads"])))
