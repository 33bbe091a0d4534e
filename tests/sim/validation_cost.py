"""What the engine's boundary checks cost: decisions per second of ``Simulation.step`` with them (the package's
step: the action check and the after-the-end bookkeeping) and without (the same compiled step called directly,
as the step did before the checks), interleaved in one process on the same simulation, at B formations.

    python tests/sim/validation_cost.py [--batch 1024] [--scenario close_formation] [--rounds 5] [--steps 20]

Prints one JSON line: the medians of both, and their ratio (what the docs quote; no test asserts a timing)."""

from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np


def main(argv=None) -> dict:
    from formation_env.sim import Simulation
    from formation_env.sim.step import step as compiled_step
    from formation_env.tasks import make_config

    p = argparse.ArgumentParser()
    p.add_argument("--batch", type=int, default=1024)
    p.add_argument("--scenario", default="close_formation")
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--steps", type=int, default=20)
    args = p.parse_args(argv)
    sim = Simulation(make_config(scenario=args.scenario, duration_s=3600.0), batch_size=args.batch)
    sim.reset(seeds=list(range(args.batch)))
    rng = np.random.default_rng(0)
    acts = [rng.uniform(-1.0, 1.0, (args.batch, sim.n_agents, 4)).astype(np.float32) for _ in range(8)]

    def checked(a):
        sim.step(a)

    def unchecked(a):  # the step without the boundary: copy the actions in, run the compiled step
        if sim._all_agents:
            np.copyto(sim._actions, a, casting="unsafe")
        else:
            sim._actions[:, sim.agent_mask] = a
        compiled_step(sim.params, sim.state, sim._actions, sim.output)

    for f in (checked, unchecked):  # warm both
        f(acts[0])
    rates = {"checked": [], "unchecked": []}
    for r in range(args.rounds):
        for name, f in (("checked", checked), ("unchecked", unchecked))[:: 1 if r % 2 else -1]:
            t0 = time.perf_counter()
            for k in range(args.steps):
                f(acts[k % len(acts)])
            rates[name].append(args.steps * args.batch / (time.perf_counter() - t0))
    med = {k: statistics.median(v) for k, v in rates.items()}
    out = {"scenario": args.scenario, "batch": args.batch, "rounds": args.rounds, "steps_per_round": args.steps,
           "formation_decisions_per_s_checked": round(med["checked"], 1),
           "formation_decisions_per_s_unchecked": round(med["unchecked"], 1),
           "cost_percent": round(100.0 * (med["unchecked"] / med["checked"] - 1.0), 2),
           "check_us_per_step": None}
    # the checks alone, timed apart from the physics: what they add to each step
    from formation_env.sim.validation import check_actions

    shape = (args.batch, sim.n_agents, 4)
    t0 = time.perf_counter()
    n = 2000
    for k in range(n):
        check_actions(acts[k % len(acts)], shape)
        np.logical_or(sim.output.terminated, sim.output.truncated, out=sim._ended)
        bool(sim._ended.any())
    out["check_us_per_step"] = round(1e6 * (time.perf_counter() - t0) / n, 1)
    print(json.dumps(out), flush=True)
    return out


if __name__ == "__main__":
    main()
