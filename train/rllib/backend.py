"""Multi-agent PPO on Ray RLlib, on this machine or on an existing Ray cluster.

``formation-env train --backend rllib`` trains the PettingZoo ParallelEnv through RLlib's PettingZoo
support (``train/rllib/env.py``): one policy shared by every learning UAV by default, or one policy
per role (``leader`` = vehicle 0, which flies the scenario's path; ``follower`` = the others) with
``policies="per-role"``. Sampling runs on ``num_env_runners`` Ray actors; the PPO update runs in the
driver.

Ray is an optional dependency (``pip install -e ".[distributed]"``). This module and its parts
import it only inside functions, so importing them (``formation-env evaluate`` imports
``train.rllib.checkpoints`` to recognise RLlib checkpoints) costs nothing; nothing else in the
project imports ray. The parts: :mod:`train.rllib.config` (the run's configuration and PPOConfig),
:mod:`train.rllib.cluster` (where Ray runs), :mod:`train.rllib.checkpoints`,
:mod:`train.rllib.policy` (inference) and :mod:`train.rllib.bench` (sampling throughput); this
module holds the training loop and the run directory, and re-exports the parts' names.

Where Ray runs (``address``):

* ``None`` / ``"local"``: a private Ray instance on this machine (no dashboard; token authentication
  on, as Ray does by default), stopped at the end;
* ``"auto"``: the Ray cluster this machine belongs to (``ray start`` was run here, or RAY_ADDRESS);
* ``"HOST:PORT"``: the head node of an existing cluster (its GCS port, 6379 by default).

Run directory (a new directory; ``resume`` continues one)::

    config.yaml                         the RLlibTrainConfig and the command
    checkpoints/iter_000010/            RLlib checkpoints (Algorithm.save_to_path), each written to a
                                        temporary directory and renamed into place, with
                                        formation_env.json (what `formation-env evaluate` needs)
    progress.csv                        one row per iteration (steps, return, sampling throughput)
    summary.json                        wall time, steps, throughput, last checkpoint, and where the env
                                        runners ran (``env_runner_nodes``, below)

Where the env runners ran: after every iteration the driver asks each env runner for the Ray node it
lives on (``ray.get_runtime_context().get_node_id()`` and the node's IP, one small remote call per
runner); ``summary.json`` lists every distinct (runner, node) pair seen as ``env_runner_nodes``
(``[{"runner": 1, "node_id": "...", "node_ip": "..."}, ...]``; a runner Ray restarted on another node
appears twice; with 0 env runners the driver samples and is listed as runner 0) and ``nodes_used``,
the number of distinct nodes among them. ``custom_resources_per_env_runner`` (hyperparameters) places
the runners on the nodes that offer those Ray resources.

Steps are RLlib env steps: one decision of the whole formation (0.1 s). With the default
``learning="followers"`` in a two-UAV scenario that is one follower decision, the unit of SB3's steps.

Reproducibility: the seed fixes the policy initialisation and every env runner's episode stream
(runner ``i`` starts from seed ``seed + i``). PPO samples synchronously and RLlib gathers the runners'
episodes in a fixed order, so on CPU a rerun with the same seed reproduces the run (tested with 2 env
runners); RLlib itself does not promise this across releases.
"""

from __future__ import annotations

import csv
import io
import json
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from formation_env.errors import ClusterUnreachableError, MissingDependencyError  # noqa: F401 - re-exported

from ..config import merge_config
from .bench import benchmark_sampling
from .checkpoints import (_CKPT, CHECKPOINT_META, _save_checkpoint, checkpoint_metadata, is_rllib_checkpoint,
                          latest_rllib_checkpoint)
from .cluster import DISTRIBUTED_INSTALL, check_reachable, connect, parse_address, require_rllib, runner_node
from .config import (LEARNING_MODES, POLICY_MODES, RLlibTrainConfig, build_algo_config, env_config_dict,
                     load_rllib_hyperparams)
from .policy import load_rllib_policy

__all__ = ["RLlibTrainConfig", "train_rllib", "load_rllib_policy", "is_rllib_checkpoint", "require_rllib",
           "connect", "parse_address", "ClusterUnreachableError", "latest_rllib_checkpoint", "benchmark_sampling",
           "POLICY_MODES", "LEARNING_MODES", "DISTRIBUTED_INSTALL", "CHECKPOINT_META", "build_algo_config",
           "check_reachable", "checkpoint_metadata", "env_config_dict", "load_rllib_hyperparams"]


_PROGRESS_COLUMNS = ("iteration", "env_steps_lifetime", "env_steps", "agent_steps", "episodes", "episode_return_mean",
                     "episode_len_mean", "iteration_s", "sample_s", "env_steps_per_s")


def _progress_row(result: dict, reward_scale: float) -> dict:
    er = result.get("env_runners", {})
    agent_steps = er.get("num_agent_steps_sampled", {}) or {}
    ret = er.get("episode_return_mean")
    sample_s = float(result.get("timers", {}).get("env_runner_sampling_timer", float("nan")))
    env_steps = int(er.get("num_env_steps_sampled", 0) or 0)
    iteration_s = float(result.get("time_this_iter_s", float("nan")))
    return {
        "iteration": int(result["training_iteration"]),
        "env_steps_lifetime": int(er.get("num_env_steps_sampled_lifetime", 0) or 0),
        "env_steps": env_steps,
        "agent_steps": int(sum(int(v) for v in agent_steps.values())),
        "episodes": int(er.get("num_episodes", 0) or 0),
        # Returns are per agent and per episode, unscaled (the learner saw them x reward_scale).
        "episode_return_mean": (round(float(ret) / reward_scale / max(len(agent_steps), 1), 6)
                                if ret is not None and np.isfinite(ret) else ""),
        "episode_len_mean": round(float(er["episode_len_mean"]), 1) if er.get("episode_len_mean") is not None else "",
        "iteration_s": round(iteration_s, 3),
        "sample_s": round(sample_s, 3),  # RLlib's env_runner_sampling_timer (a smoothed mean over iterations)
        "env_steps_per_s": round(env_steps / iteration_s, 1) if iteration_s > 0 else "",  # sampling + update
    }


def _write_progress(run_dir: Path, rows: list[dict]) -> None:
    from formation_env.io import atomic_write_text

    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=_PROGRESS_COLUMNS, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    atomic_write_text(run_dir / "progress.csv", buf.getvalue(), overwrite=True)


def _read_progress(run_dir: Path, upto_iteration: int) -> list[dict]:
    path = run_dir / "progress.csv"
    if not path.is_file():
        return []
    with path.open() as fh:
        return [r for r in csv.DictReader(fh) if int(r["iteration"]) <= upto_iteration]


def train_rllib(*, scenario: str | None = None, action_mode: str | None = None, seed: int | None = None,
                steps: int | None = None, iterations: int | None = None, policies: str | None = None,
                learning: str | None = None, num_env_runners: int | None = None,
                num_envs_per_env_runner: int | None = None, address: str | None = None, num_cpus: int | None = None,
                config_file: str | Path | None = None, out_dir: str | Path | None = None, overwrite: bool = False,
                resume: bool = False, overrides: dict | None = None, log: Callable[[str], None] | None = None,
                command: str | None = None) -> dict:
    """Train (or resume) one RLlib run; returns its summary. ``overrides``: hyperparameters merged
    last (the YAML format; the tests use it for tiny runs).

    On ``resume`` the run's own configuration is used. A new ``steps`` and/or ``iterations`` replaces
    the run's end (whichever of the two is given; both when both are), ``num_env_runners`` and
    ``num_envs_per_env_runner`` may change, and the env runners draw new episodes (their seeds are
    mixed with the restored iteration). Everything that can be checked is checked before Ray starts,
    and the run directory is created only once the Algorithm is built."""
    import yaml

    log = log or (lambda msg: print(msg, flush=True))
    parse_address(address)  # a malformed address fails before anything starts
    require_rllib()
    if resume:
        cfg, run_dir, ck = _resume_config(out_dir, config_file, overwrite, dict(
            scenario=scenario, action_mode=action_mode, policies=policies, learning=learning, seed=seed),
            dict(n_timesteps=steps, iterations=iterations, num_env_runners=num_env_runners,
                 num_envs_per_env_runner=num_envs_per_env_runner))
    else:
        if scenario is None:
            raise ValueError("give --scenario")
        params = load_rllib_hyperparams(scenario, config_file)
        if action_mode is None:  # the task's
            from ..config import default_action_mode

            action_mode = default_action_mode(scenario)
        if overrides:
            params = merge_config(params, overrides)
        cfg = RLlibTrainConfig.from_hyperparams(
            params, scenario=scenario, action_mode=action_mode, seed=seed, n_timesteps=steps, iterations=iterations,
            policies=policies, learning=learning, num_env_runners=num_env_runners,
            num_envs_per_env_runner=num_envs_per_env_runner)
        run_dir = Path(out_dir) if out_dir is not None else Path("runs") / (
            f"{cfg.scenario}-rllib-ppo-{cfg.policies}-seed{cfg.seed}-{time.strftime('%Y%m%d-%H%M%S')}")
        _check_new_run_dir(run_dir, overwrite)
        ck = None

    import ray

    if parse_address(address) is None and not ray.is_initialized():
        _check_custom_resources(cfg, local=True, log=log)  # before a local instance starts
    started = connect(address, num_cpus=num_cpus, log=log)
    try:
        if not started:
            _check_custom_resources(cfg, local=False, log=log)
        algo = build_algo_config(cfg, episode_stream=ck[1] if ck else 0).build_algo()
        try:
            if ck is None:
                _prepare_new_run_dir(run_dir, overwrite)
                from formation_env.io import atomic_write_text

                atomic_write_text(run_dir / "config.yaml", yaml.safe_dump(
                    {"backend": "rllib", "command": command, "config": cfg.to_dict()}, sort_keys=False))
            return _train_loop(algo, cfg, run_dir, ck, log)
        finally:
            algo.stop()
    finally:
        if started:
            ray.shutdown()


def _check_custom_resources(cfg: RLlibTrainConfig, *, local: bool, log) -> None:
    """Env runners that ask for custom resources no node offers would wait for them forever: refused
    on a local instance (it offers none); on a cluster, where an autoscaler may still add such nodes,
    a warning names what is missing."""
    wanted = cfg.custom_resources_per_env_runner
    if not wanted or cfg.num_env_runners == 0:
        return
    if local:
        raise ValueError(f"custom_resources_per_env_runner {wanted} asks for Ray resources that a local Ray instance "
                         "does not offer (its nodes have only CPUs); give --address of a cluster whose nodes were "
                         "started with `ray start --resources '{...}'`, or leave the key out")
    import ray

    total = ray.cluster_resources()
    short = {k: (total.get(k, 0.0), v * cfg.num_env_runners) for k, v in wanted.items()
             if total.get(k, 0.0) < v * cfg.num_env_runners}
    if short:
        log("warning: the cluster offers " + ", ".join(f"{k}: {have:g} (the {cfg.num_env_runners} env runners need "
                                                        f"{need:g})" for k, (have, need) in short.items())
            + "; the runners that do not fit wait for nodes that offer it")


def _record_runner_nodes(algo, cfg: RLlibTrainConfig, seen: list[dict], log) -> None:
    """Add the env runners' current (runner, node) pairs to ``seen``; log them when they change."""
    try:
        now = algo.env_runner_group.foreach_env_runner(runner_node, local_env_runner=cfg.num_env_runners == 0,
                                                       timeout_seconds=30.0)
    except Exception as exc:  # noqa: BLE001 - a bookkeeping query never stops training
        log(f"warning: could not ask the env runners where they run: {type(exc).__name__}: {exc}")
        return
    new = [p for p in sorted(now, key=lambda p: p["runner"]) if p not in seen]
    if new:
        seen.extend(new)
        seen.sort(key=lambda p: p["runner"])
        log("env runners on " + ", ".join(f"runner {p['runner']}: node {p['node_id'][:12]} ({p['node_ip']})"
                                          for p in new))


_OWN_FILES = ("progress.csv", "summary.json", "config.yaml")


def _check_new_run_dir(run_dir: Path, overwrite: bool) -> None:
    from formation_env.io import prepare_output_dir

    if run_dir.exists() and not overwrite and (not run_dir.is_dir() or any(run_dir.iterdir())):
        prepare_output_dir(run_dir, overwrite=False)  # raises its clear error, before Ray starts
    if run_dir.exists() and not run_dir.is_dir():
        raise FileExistsError(f"output path {str(run_dir)!r} exists and is not a directory")


def _prepare_new_run_dir(run_dir: Path, overwrite: bool) -> None:
    """Create the run directory; with ``overwrite``, first remove what an earlier run of this backend
    left there (its checkpoints would otherwise be taken for this run's by resume and evaluate)."""
    import shutil

    from formation_env.io import prepare_output_dir

    if overwrite and run_dir.is_dir():
        ckdir = run_dir / "checkpoints"
        if ckdir.is_dir():
            for p in ckdir.iterdir():
                if p.is_dir() and (_CKPT.match(p.name) or p.name.startswith(".iter_")):
                    shutil.rmtree(p)
        for p in list(run_dir.glob("summary-resume-*.json")) + [run_dir / f for f in _OWN_FILES]:
            if p.is_file():
                p.unlink()
    prepare_output_dir(run_dir, overwrite=overwrite)


def _resume_config(out_dir, config_file, overwrite: bool, fixed: dict, changeable: dict):
    """The configuration, directory and checkpoint of a run to resume, checked before Ray starts."""
    import yaml

    if out_dir is None:
        raise ValueError("--resume needs --out RUN_DIR (the run to continue)")
    if config_file is not None:
        raise ValueError("--resume continues the run's own configuration; --config applies to new runs only")
    if overwrite:
        raise ValueError("--resume and --overwrite exclude each other")
    run_dir = Path(out_dir)
    if not (run_dir / "config.yaml").is_file():
        raise ValueError(f"cannot resume: {str(run_dir)!r} holds no config.yaml (not a training run directory)")
    saved = yaml.safe_load((run_dir / "config.yaml").read_text()) or {}
    if saved.get("backend") != "rllib":
        raise ValueError(f"cannot resume {str(run_dir)!r} with --backend rllib: it is an SB3 run (leave out --backend)")
    data = dict(saved["config"])
    for name, given in fixed.items():
        if given is not None and given != data.get(name):
            raise ValueError(f"--resume: {name} {given!r} differs from the run's {data.get(name)!r}")
    if changeable["n_timesteps"] is not None or changeable["iterations"] is not None:
        data["n_timesteps"], data["iterations"] = changeable["n_timesteps"], changeable["iterations"]
    for name in ("num_env_runners", "num_envs_per_env_runner"):
        if changeable[name] is not None:
            data[name] = changeable[name]
    cfg = RLlibTrainConfig(**data)
    ck = latest_rllib_checkpoint(run_dir)
    if ck is None:
        raise ValueError(f"cannot resume: no checkpoint in {str(run_dir / 'checkpoints')!r}")
    meta = json.loads((ck[0] / CHECKPOINT_META).read_text())
    if _done(cfg, ck[1], int(meta["env_steps"])):
        raise ValueError(f"the run is already at iteration {ck[1]} / {meta['env_steps']} env steps; give a larger "
                         "--iterations or --steps to continue it")
    return cfg, run_dir, ck


def _done(cfg: RLlibTrainConfig, iteration: int, env_steps: int) -> bool:
    return ((cfg.n_timesteps is not None and env_steps >= cfg.n_timesteps)
            or (cfg.iterations is not None and iteration >= cfg.iterations))


def _train_loop(algo, cfg: RLlibTrainConfig, run_dir: Path, ck, log) -> dict:
    from formation_env.io import atomic_write_json

    rows: list[dict] = []
    start_iter, env_steps = 0, 0
    if ck is not None:
        path, it = ck
        algo.restore_from_path(str(path.resolve()))
        meta = json.loads((path / CHECKPOINT_META).read_text())
        start_iter, env_steps = algo.iteration, int(meta["env_steps"])
        if start_iter != it:
            raise RuntimeError(f"restored iteration {start_iter} differs from the checkpoint's name {path.name}")
        rows = _read_progress(run_dir, start_iter)  # rows after the checkpoint (a crash between two) are dropped
        log(f"resuming {run_dir} from {path.name} ({env_steps} env steps)")
    log(f"training RLlib PPO ({cfg.policies} policies: {', '.join(cfg.modules)}) on {cfg.scenario} "
        f"({cfg.action_mode} actions, {cfg.learning} learn), seed {cfg.seed}, {cfg.num_env_runners} env runner(s) "
        f"-> {run_dir}")
    t0 = time.perf_counter()
    last_ck = ck[0] if ck else None
    runner_nodes: list[dict] = []
    while not _done(cfg, algo.iteration, env_steps):
        result = algo.train()
        _record_runner_nodes(algo, cfg, runner_nodes, log)
        row = _progress_row(result, cfg.reward_scale)
        env_steps = row["env_steps_lifetime"]
        rows.append(row)
        _write_progress(run_dir, rows)
        log(f"iter {row['iteration']:4d}  env steps {env_steps:9d}  return/agent {row['episode_return_mean'] or '-':>10}"
            f"  {row['env_steps_per_s'] or '-'} env steps/s")
        if cfg.checkpoint_every and algo.iteration % cfg.checkpoint_every == 0:
            last_ck = _save_checkpoint(algo, cfg, run_dir, env_steps)
    if last_ck is None or last_ck.name != f"iter_{algo.iteration:06d}":
        last_ck = _save_checkpoint(algo, cfg, run_dir, env_steps)
    wall = time.perf_counter() - t0
    new = rows[len(rows) - (algo.iteration - start_iter):] if algo.iteration > start_iter else []
    sampled = sum(int(r["env_steps"]) for r in new)
    summary = {"run_dir": str(run_dir), "backend": "rllib", "scenario": cfg.scenario, "policies": cfg.policies,
               "modules": cfg.modules, "seed": cfg.seed, "iterations": algo.iteration, "env_steps": env_steps,
               "resumed_from_iteration": start_iter or None, "num_env_runners": cfg.num_env_runners,
               "num_envs_per_env_runner": cfg.num_envs_per_env_runner,
               "wall_s": round(wall, 1), "env_steps_per_s": round(sampled / wall, 1) if wall > 0 else None,
               "checkpoint": str(last_ck), "env_runner_nodes": runner_nodes,
               "nodes_used": len({p["node_id"] for p in runner_nodes})}
    name = "summary.json" if not start_iter else f"summary-resume-{start_iter}.json"
    atomic_write_json(run_dir / name, summary, overwrite=True)
    log(f"done in {wall:.0f} s: iteration {algo.iteration}, {env_steps} env steps -> {last_ck}")
    return summary
