"""How fast RLlib samples the formation env with 1, 2, ... env runners (``formation-env bench --rllib``)."""

from __future__ import annotations

import os
import time
from collections.abc import Callable

import numpy as np

from .cluster import connect
from .config import RLlibTrainConfig, build_algo_config, load_rllib_hyperparams

__all__ = ["benchmark_sampling"]


def _sample_env_steps(runner, num_timesteps: int) -> int:
    """Runs on an env runner: sample ``num_timesteps`` env steps with the current policy and count them."""
    return int(sum(ep.env_steps() for ep in runner.sample(num_timesteps=num_timesteps)))


def benchmark_sampling(runner_counts=(1, 2), *, scenario: str = "formation_keeping", action_mode: str = "setpoints",
                       rounds: int = 5, batch: int = 2000, num_envs_per_env_runner: int = 1,
                       num_cpus: int | None = None, address: str | None = None,
                       log: Callable[[str], None] = print) -> dict:
    """Env steps/s RLlib samples with each number of env runners, the training's env options
    (Dryden turbulence, initial offsets, wake).

    For each count a fresh Algorithm is built; every runner then samples ``batch / n`` env steps at
    once and the wall time of that parallel call is taken (``rounds`` times after one warm-up round,
    which absorbs actor start-up and numba cache loading); the median is reported. The same is done for
    whole PPO iterations (sampling + the driver's update of one epoch), timed by RLlib's
    ``time_this_iter_s``."""
    started = connect(address, num_cpus=num_cpus, log=log)
    out = {"scenario": scenario, "action_mode": action_mode, "batch_env_steps": batch, "rounds": rounds,
           "num_envs_per_env_runner": num_envs_per_env_runner, "cpus": os.cpu_count(), "results": {}}
    try:
        for n in runner_counts:
            cfg = RLlibTrainConfig(scenario=scenario, action_mode=action_mode, num_env_runners=n, checkpoint_every=0,
                                   num_envs_per_env_runner=num_envs_per_env_runner,
                                   env_kwargs=load_rllib_hyperparams(scenario).get("env_kwargs", {}),
                                   training={"train_batch_size_per_learner": batch, "minibatch_size": min(500, batch),
                                             "num_epochs": 1},
                                   model={"fcnet_hiddens": [64, 64]})
            algo = build_algo_config(cfg).build_algo()
            try:
                per_runner = batch // max(n, 1)
                group = algo.env_runner_group
                rates = []
                for k in range(rounds + 1):
                    t0 = time.perf_counter()
                    counts = group.foreach_env_runner(lambda r, m=per_runner: _sample_env_steps(r, m),
                                                      local_env_runner=n == 0)
                    dt = time.perf_counter() - t0
                    if k:
                        rates.append(sum(counts) / dt)
                iters = []
                for k in range(rounds + 1):
                    res = algo.train()
                    if k:
                        iters.append(res["env_runners"]["num_env_steps_sampled"] / res["time_this_iter_s"])
            finally:
                algo.stop()
            out["results"][n] = {"env_steps_per_s_sampling": round(float(np.median(rates)), 1),
                                 "env_steps_per_s_sampling_all": [round(r, 1) for r in rates],
                                 "env_steps_per_s_training": round(float(np.median(iters)), 1)}
            log(f"{n} env runner(s): {np.median(rates):.0f} env steps/s sampled, {np.median(iters):.0f} env steps/s "
                "in PPO iterations (sampling + update)")
    finally:
        if started:
            import ray

            ray.shutdown()
    return out
