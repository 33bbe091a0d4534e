"""Multi-agent PPO on Ray RLlib, on this machine or on an existing Ray cluster.

``formation-env train --backend rllib`` trains the PettingZoo ParallelEnv through RLlib's PettingZoo
support (``train/rllib_env.py``): one policy shared by every learning UAV by default, or one policy
per role (``leader`` = vehicle 0, which flies the scenario's path; ``follower`` = the others) with
``policies="per-role"``. Sampling runs on ``num_env_runners`` Ray actors; the PPO update runs in the
driver.

Ray is an optional dependency (``pip install -e ".[distributed]"``). This module imports it only
inside functions, so importing the module (``formation-env evaluate`` does, to recognise RLlib
checkpoints) costs nothing; nothing else in the project imports ray.

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
    summary.json                        wall time, steps, throughput, last checkpoint

Steps are RLlib env steps: one decision of the whole formation (0.1 s). With the default
``learning="followers"`` in a two-UAV scenario that is one follower decision, the unit of SB3's steps.

Reproducibility: the seed fixes the policy initialisation and every env runner's episode stream
(runner ``i`` starts from seed ``seed + i``). PPO samples synchronously and RLlib gathers the runners'
episodes in a fixed order, so on CPU a rerun with the same seed reproduces the run (tested with 2 env
runners); RLlib itself does not promise this across releases.
"""

from __future__ import annotations

import copy
import csv
import io
import json
import math
import os
import re
import socket
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from formation_env.errors import ClusterUnreachableError, MissingDependencyError

from .config import _ENV_KEYS, HYPERPARAMS_DIR, _merge, _section, env_config_for, load_yaml

__all__ = ["RLlibTrainConfig", "train_rllib", "load_rllib_policy", "is_rllib_checkpoint", "require_rllib",
           "connect", "parse_address", "ClusterUnreachableError", "latest_rllib_checkpoint", "benchmark_sampling",
           "POLICY_MODES", "LEARNING_MODES", "DISTRIBUTED_INSTALL"]

DISTRIBUTED_INSTALL = 'pip install -e ".[distributed]"'
POLICY_MODES = ("shared", "per-role")
LEARNING_MODES = ("followers", "all")
CHECKPOINT_META = "formation_env.json"
_CKPT = re.compile(r"^iter_(\d+)$")
_PPO_KEYS = {"lr", "gamma", "lambda_", "clip_param", "vf_clip_param", "vf_loss_coeff", "entropy_coeff", "kl_coeff",
             "kl_target", "use_kl_loss", "use_gae", "grad_clip", "train_batch_size_per_learner", "minibatch_size",
             "num_epochs", "shuffle_batch_per_epoch"}
_MODEL_KEYS = {"fcnet_hiddens", "fcnet_activation", "vf_share_layers", "free_log_std", "log_std_clip_param",
               "fcnet_use_layernorm"}
_TOP_KEYS = {"n_timesteps", "iterations", "num_env_runners", "num_envs_per_env_runner", "num_cpus_per_env_runner",
             "checkpoint_every", "reward_scale", "training", "model", "env_kwargs", "learning", "policies"}


def require_rllib() -> None:
    """Raise MissingDependencyError (with the install command) unless Ray RLlib and torch import."""
    try:
        import ray  # noqa: F401
        import ray.rllib  # noqa: F401
        import torch  # noqa: F401
    except ImportError as exc:
        raise MissingDependencyError(
            f"the RLlib backend needs Ray RLlib, which is not installed here ({exc}); install the optional "
            f"extra with: {DISTRIBUTED_INSTALL}") from exc


# ------------------------------------------------------------------------------------------ config
@dataclass
class RLlibTrainConfig:
    """Everything that defines an RLlib run (saved as ``config.yaml`` in the run directory)."""

    scenario: str
    action_mode: str = "residual"
    seed: int = 0
    learning: str = "followers"
    policies: str = "shared"
    n_timesteps: int | None = 1_000_000
    iterations: int | None = None
    num_env_runners: int = 2
    num_envs_per_env_runner: int = 1
    num_cpus_per_env_runner: int = 1
    checkpoint_every: int = 10
    reward_scale: float = 1.0
    training: dict = field(default_factory=dict)
    model: dict = field(default_factory=dict)
    env_kwargs: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        from formation_env.scenarios import scenario_names

        from .config import ACTION_MODES

        if self.scenario not in scenario_names():
            raise ValueError(f"unknown scenario {self.scenario!r}; available: {scenario_names()}")
        if self.action_mode not in ACTION_MODES:
            raise ValueError(f"unknown action mode {self.action_mode!r}; choose one of {ACTION_MODES}")
        if self.learning not in LEARNING_MODES:
            raise ValueError(f"learning must be one of {LEARNING_MODES}, got {self.learning!r}")
        if self.policies not in POLICY_MODES:
            raise ValueError(f"policies must be one of {POLICY_MODES}, got {self.policies!r}")
        for name, low in (("seed", 0), ("n_timesteps", 1), ("num_env_runners", 0), ("num_envs_per_env_runner", 1),
                          ("num_cpus_per_env_runner", 0), ("checkpoint_every", 0), ("iterations", 1)):
            v = getattr(self, name)
            if v is None and name in ("iterations", "n_timesteps"):
                continue
            if isinstance(v, float) and math.isfinite(v) and v.is_integer():
                v = int(v)
                setattr(self, name, v)
            if isinstance(v, bool) or not isinstance(v, int) or v < low:
                raise ValueError(f"{name} must be an integer >= {low}, got {v!r}")
        if self.n_timesteps is None and self.iterations is None:
            raise ValueError("give the run an end: steps (n_timesteps) or iterations")
        if isinstance(self.reward_scale, bool) or not isinstance(self.reward_scale, (int, float)) \
                or not math.isfinite(self.reward_scale) or self.reward_scale <= 0:
            raise ValueError(f"reward_scale must be a finite number > 0, got {self.reward_scale!r}")
        for name, valid in (("training", _PPO_KEYS), ("model", _MODEL_KEYS), ("env_kwargs", _ENV_KEYS - {"learning"})):
            value = getattr(self, name)
            if not isinstance(value, dict):
                raise ValueError(f"{name} must be a mapping, got {type(value).__name__}")
            bad = sorted(set(value) - valid)
            if bad:
                raise ValueError(f"unknown {name} key(s) {bad}; valid: {sorted(valid)}")
        # Validates the environment options here, without ray (the env itself is built on the runners).
        from formation_env.scenarios import get_scenario

        env_config_for(self.scenario, self.action_mode, self.env_kwargs, learning=self.learning)
        if self.learning == "followers" and not get_scenario(self.scenario).slots:
            raise ValueError(f"scenario {self.scenario!r} flies one UAV: there are no followers to learn "
                             "(use learning='all')")

    @property
    def modules(self) -> list[str]:
        """The RLModule ids this run trains."""
        if self.policies == "shared":
            return ["shared"]
        return (["leader"] if self.learning == "all" else []) + ["follower"]

    @classmethod
    def from_hyperparams(cls, params: dict, **given) -> RLlibTrainConfig:
        p = copy.deepcopy(params)
        bad = sorted(set(p) - _TOP_KEYS)
        if bad:
            raise ValueError(f"unknown RLlib hyperparameter key(s) {bad}; valid: {sorted(_TOP_KEYS)}")
        p.update({k: v for k, v in given.items() if v is not None})
        return cls(**p)

    def to_dict(self) -> dict:
        return asdict(self)


def load_rllib_hyperparams(scenario: str, config_file: str | Path | None = None) -> dict:
    """``train/hyperparams/rllib_ppo.yml`` for ``scenario``, with ``config_file`` merged over it."""
    params = _section(load_yaml(HYPERPARAMS_DIR / "rllib_ppo.yml"), scenario)
    if config_file is not None:
        params = _merge(params, _section(load_yaml(config_file), scenario))
    return params


def env_config_dict(cfg: RLlibTrainConfig, episode_stream: int = 0) -> dict:
    """The ``env_config`` RLlib hands to ``FormationMultiAgentEnv`` on every env runner
    (``episode_stream``: 0, or the iteration a resumed run restarts from, so it sees new episodes)."""
    return {"scenario": cfg.scenario, "action_mode": cfg.action_mode, "learning": cfg.learning,
            "env_kwargs": copy.deepcopy(cfg.env_kwargs), "reward_scale": cfg.reward_scale,
            "episode_stream": int(episode_stream)}


def checkpoint_metadata(cfg: RLlibTrainConfig, *, iteration: int, env_steps: int) -> dict:
    """What ``formation-env evaluate`` needs to fly a checkpoint (stored beside RLlib's own files)."""
    import ray

    env = env_config_for(cfg.scenario, cfg.action_mode, cfg.env_kwargs, learning=cfg.learning)
    return {"backend": "rllib", "algo": "ppo", "scenario": cfg.scenario, "action_mode": cfg.action_mode,
            "learning": cfg.learning, "policies": cfg.policies, "modules": cfg.modules, "control_hz": env.control_hz,
            "seed": cfg.seed, "iteration": int(iteration), "env_steps": int(env_steps), "ray_version": ray.__version__}


# ------------------------------------------------------------------------------------------ Ray
def parse_address(address: str | None):
    """``None`` (a local instance), ``"auto"`` or ``(host, port)``; ValueError naming a malformed one."""
    if address is None or address == "local":
        return None
    if not isinstance(address, str) or not address.strip():
        raise ValueError(f"--address must be 'auto', 'local' or HOST:PORT, got {address!r}")
    address = address.strip()
    if address == "auto":
        return "auto"
    if "://" in address:
        raise ValueError(f"--address {address!r}: give the head's GCS address HOST:PORT (e.g. 10.0.0.5:6379) or "
                         "'auto' on a cluster node; Ray Client (ray://) and dashboard (http://) addresses are not "
                         "supported")
    host, sep, port = address.rpartition(":")
    host = host.strip("[]")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"--address must be 'auto', 'local' or HOST:PORT (e.g. 10.0.0.5:6379), got {address!r}")
    return host, int(port)


# The HTTP/2 client preface and an empty SETTINGS frame: a gRPC server (Ray's GCS is one) answers with
# a SETTINGS frame (9-byte header, type 4); an HTTP/1 server, a dashboard or a database answers otherwise.
_H2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + b"\x00\x00\x00\x04\x00\x00\x00\x00\x00"


def check_reachable(host: str, port: int, timeout_s: float = 5.0) -> None:
    """Check that ``host:port`` accepts TCP connections and speaks gRPC, as a Ray head's GCS port
    does, so that a wrong address fails in seconds with a clear message (``ray.init`` itself retries
    for about a minute on a closed port, and for longer on a port where something else listens)."""
    try:
        with socket.create_connection((host, port), timeout=timeout_s) as sock:
            sock.settimeout(timeout_s)
            sock.sendall(_H2_PREFACE)
            head = b""
            try:
                while len(head) < 9 and (chunk := sock.recv(9 - len(head))):
                    head += chunk
            except (socket.timeout, ConnectionResetError):
                pass
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise ClusterUnreachableError(
            f"cannot reach a Ray cluster at {host}:{port} ({reason}). Start its head node with "
            f"`ray start --head --port={port}`, check that this machine can reach that port, or leave out "
            f"--address to train on a local Ray instance") from exc
    if os.environ.get("RAY_USE_TLS", "0").lower() in ("1", "true"):
        return  # a TLS cluster answers the plaintext preface with a TLS alert; the TCP check is what we can do
    if len(head) < 9 or head[3] != 0x04:
        raise ClusterUnreachableError(
            f"{host}:{port} accepts connections but is not a Ray head's GCS port (it does not speak gRPC; "
            f"answered {head[:16]!r}). Give the port the head was started with (`ray start --head --port=P`, "
            "6379 by default); the dashboard (8265) and Ray Client (10001) ports are not it")


def _use_cluster_token() -> None:
    """Ray >= 2.5x protects clusters with a token, but a process joining one only sends it when
    RAY_AUTH_MODE=token; when a token is at hand (RAY_AUTH_TOKEN, RAY_AUTH_TOKEN_PATH or
    ~/.ray/auth_token, the head's copy) and the mode is unset, send it."""
    if os.environ.get("RAY_AUTH_MODE") is not None:
        return  # the user chose
    try:  # Ray's own switch also refreshes its cached config, which an env variable alone does not
        from ray._private.authentication.authentication_token_setup import (
            maybe_enable_token_auth_if_token_available,
        )
    except ImportError:  # a Ray without token auth: nothing to send
        return
    maybe_enable_token_auth_if_token_available(warn_if_disabled=False)


def _join(address: str, label: str) -> None:
    import ray

    _use_cluster_token()
    try:
        ray.init(address=address, logging_level="ERROR")
    except (ConnectionError, TimeoutError, RuntimeError) as exc:
        chain, e = [], exc
        while e is not None:
            chain.append(f"{type(e).__name__}: {e}")
            e = e.__cause__ or e.__context__
        text = " <- ".join(chain)
        if "auth" in text.lower() and "token" in text.lower():
            raise ClusterUnreachableError(
                f"the Ray cluster at {label} refused this machine's authentication token: copy the head's "
                "~/.ray/auth_token here (or set RAY_AUTH_TOKEN) and set RAY_AUTH_MODE=token") from exc
        if label == "auto":
            raise ClusterUnreachableError(
                "--address auto: no running Ray cluster found on this machine (start one with `ray start --head`, "
                "join this machine with `ray start --address=HEAD:6379`, set RAY_ADDRESS, or leave out --address "
                f"for a local instance): {exc}") from exc
        raise ClusterUnreachableError(f"could not join the Ray cluster at {label}: {text[:600]}") from exc


def connect(address: str | None = None, *, num_cpus: int | None = None, log: Callable[[str], None] = print) -> bool:
    """Connect to (or start) Ray. Returns True when this call started a local instance (the caller
    shuts it down). A Ray already initialised in this process is reused as it is."""
    require_rllib()
    import ray

    target = parse_address(address)
    if ray.is_initialized():
        return False
    if num_cpus is not None and target is not None:
        raise ValueError("--num-cpus applies only to a local Ray instance (without --address); a cluster has "
                         "the CPUs its nodes were started with")
    if target is None:
        # A private instance: address="local" so that a RAY_ADDRESS in the environment is not joined
        # instead, and no dashboard. Ray addresses the node by this machine's IP (it turns a requested
        # 127.0.0.1 into that) and its servers listen on every interface; its token authentication, on
        # by default, guards them.
        ray.init(address="local", num_cpus=num_cpus, include_dashboard=False, logging_level="ERROR",
                 configure_logging=True)
        node = ray.nodes()[0].get("NodeManagerAddress", "?")
        log(f"started a local Ray instance ({int(ray.cluster_resources().get('CPU', 0))} CPUs, node address {node})")
        return True
    if target == "auto":
        _join("auto", "auto")
    else:
        host, port = target
        check_reachable(host, port)
        _join(f"{host}:{port}", f"{host}:{port}")
    res = ray.cluster_resources()
    log(f"joined the Ray cluster at {address} ({len(ray.nodes())} node(s), {int(res.get('CPU', 0))} CPUs)")
    return False


# ------------------------------------------------------------------------------------------ algorithm
def build_algo_config(cfg: RLlibTrainConfig, episode_stream: int = 0):
    """The PPOConfig of a run: the PettingZoo env through RLlib, shared or per-role policies."""
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig
    from ray.rllib.core.rl_module.multi_rl_module import MultiRLModuleSpec
    from ray.rllib.core.rl_module.rl_module import RLModuleSpec

    from .rllib_env import FormationMultiAgentEnv, role_policy, shared_policy

    mapping = shared_policy if cfg.policies == "shared" else role_policy
    return (
        PPOConfig()
        .environment(FormationMultiAgentEnv, env_config=env_config_dict(cfg, episode_stream))
        .env_runners(num_env_runners=cfg.num_env_runners, num_envs_per_env_runner=cfg.num_envs_per_env_runner,
                     num_cpus_per_env_runner=cfg.num_cpus_per_env_runner, rollout_fragment_length="auto")
        .multi_agent(policies=set(cfg.modules), policy_mapping_fn=mapping)
        .rl_module(rl_module_spec=MultiRLModuleSpec(rl_module_specs={m: RLModuleSpec() for m in cfg.modules}),
                   model_config=DefaultModelConfig(**cfg.model))
        .training(**cfg.training)
        .debugging(seed=cfg.seed, log_level="ERROR")
    )


def latest_rllib_checkpoint(run_dir: str | Path) -> tuple[Path, int] | None:
    ckdir = Path(run_dir) / "checkpoints"
    if not ckdir.is_dir():
        return None
    found = [(int(m.group(1)), p) for p in ckdir.iterdir() if (m := _CKPT.match(p.name)) and p.is_dir()]
    if not found:
        return None
    it, path = max(found)
    return path, it


def is_rllib_checkpoint(path: str | Path) -> bool:
    """An RLlib checkpoint directory written by this backend, or a run directory holding one."""
    p = Path(path)
    return (p / CHECKPOINT_META).is_file() or (p.is_dir() and latest_rllib_checkpoint(p) is not None)


def _save_checkpoint(algo, cfg: RLlibTrainConfig, run_dir: Path, env_steps: int) -> Path:
    """``algo.save_to_path`` into a temporary directory beside the final one, then rename: a reader
    never sees half a checkpoint, and an existing checkpoint is never replaced."""
    ckdir = run_dir / "checkpoints"
    ckdir.mkdir(parents=True, exist_ok=True)
    final = ckdir / f"iter_{algo.iteration:06d}"
    if final.exists():
        raise FileExistsError(f"checkpoint {str(final)!r} exists already; not overwriting it")
    tmp = Path(tempfile.mkdtemp(prefix=f".{final.name}.", dir=ckdir))
    try:
        algo.save_to_path(str(tmp.resolve()))  # RLlib takes a path without a scheme for a URI unless absolute
        meta = checkpoint_metadata(cfg, iteration=algo.iteration, env_steps=env_steps)
        (tmp / CHECKPOINT_META).write_text(json.dumps(meta, indent=2) + "\n")
        os.chmod(tmp, 0o755)
        os.replace(tmp, final)
    finally:
        if tmp.exists():
            import shutil

            shutil.rmtree(tmp, ignore_errors=True)
    return final


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
        if overrides:
            params = _merge(params, overrides)
        cfg = RLlibTrainConfig.from_hyperparams(
            params, scenario=scenario, action_mode=action_mode, seed=seed, n_timesteps=steps, iterations=iterations,
            policies=policies, learning=learning, num_env_runners=num_env_runners,
            num_envs_per_env_runner=num_envs_per_env_runner)
        run_dir = Path(out_dir) if out_dir is not None else Path("runs") / (
            f"{cfg.scenario}-rllib-ppo-{cfg.policies}-seed{cfg.seed}-{time.strftime('%Y%m%d-%H%M%S')}")
        _check_new_run_dir(run_dir, overwrite)
        ck = None

    started = connect(address, num_cpus=num_cpus, log=log)
    try:
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
            import ray

            ray.shutdown()


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
    while not _done(cfg, algo.iteration, env_steps):
        result = algo.train()
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
               "checkpoint": str(last_ck)}
    name = "summary.json" if not start_iter else f"summary-resume-{start_iter}.json"
    atomic_write_json(run_dir / name, summary, overwrite=True)
    log(f"done in {wall:.0f} s: iteration {algo.iteration}, {env_steps} env steps -> {last_ck}")
    return summary


# ------------------------------------------------------------------------------------------ inference
def load_rllib_policy(spec: str | Path, *, name: str | None = None, module_id: str | None = None):
    """An ``EvalPolicy`` flying the follower (or shared) RLModule of an RLlib checkpoint written by
    this backend; ``spec`` may also be a run directory (its latest checkpoint). Deterministic: the mean
    of the Gaussian, clipped to the [-1, 1] action box (RLlib's unsquashing is the identity on it)."""
    require_rllib()
    import torch
    from ray.rllib.core.rl_module.rl_module import RLModule

    from .evaluate import EvalPolicy

    path = Path(spec)
    if not (path / CHECKPOINT_META).is_file():
        ck = latest_rllib_checkpoint(path) if path.is_dir() else None
        if ck is None:
            raise ValueError(f"{str(spec)!r} is not an RLlib checkpoint of this project (no {CHECKPOINT_META}) nor a "
                             "run directory holding one")
        path = ck[0]
    meta = json.loads((path / CHECKPOINT_META).read_text())
    modules = meta["modules"]
    module_id = module_id or ("follower" if "follower" in modules else "shared")
    if module_id not in modules:
        raise ValueError(f"checkpoint {str(path)!r} has no module {module_id!r}; it has {modules}")
    module = RLModule.from_checkpoint(str((path / "learner_group" / "learner" / "rl_module" / module_id).resolve()))
    dist_cls = module.get_inference_action_dist_cls()
    obs_size = int(np.prod(module.observation_space.shape))

    def act(obs: np.ndarray) -> np.ndarray:
        obs = np.asarray(obs)
        if obs.ndim != 2 or obs.shape[1] != obs_size:
            raise ValueError(f"RLlib policy {str(path)!r} (trained on {meta['scenario']!r}) takes observations of "
                             f"size {obs_size}; got shape {obs.shape} (a scenario with another number of UAVs?)")
        x = torch.from_numpy(np.ascontiguousarray(obs, dtype=np.float32))
        with torch.no_grad():
            out = module.forward_inference({"obs": x})
            a = dist_cls.from_logits(out["action_dist_inputs"]).to_deterministic().sample()
        return np.clip(a.numpy(), -1.0, 1.0)

    run_name = path.resolve().parent.parent.name
    label = name or f"{'' if 'rllib' in run_name else 'rllib-'}{run_name}-{path.name}"
    return EvalPolicy(label, meta["action_mode"], act, float(meta.get("control_hz", 10.0)), str(path))


# ------------------------------------------------------------------------------------------ benchmark
def _sample_env_steps(runner, num_timesteps: int) -> int:
    """Runs on an env runner: sample ``num_timesteps`` env steps with the current policy and count them."""
    return int(sum(ep.env_steps() for ep in runner.sample(num_timesteps=num_timesteps)))


def benchmark_sampling(runner_counts=(1, 2), *, scenario: str = "formation_keeping", action_mode: str = "residual",
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
