"""``formation-env train``: train an SB3 policy (PPO, recurrent PPO, SAC or TD3) on a formation scenario, or, with
``--backend rllib``, multi-agent PPO on Ray RLlib (locally or on an existing Ray cluster).

See ``train/sb3/train.py`` and ``train/rllib/backend.py`` for the run directory layouts and
``docs/training.md`` for the committed runs."""

from __future__ import annotations

import shlex
import sys

from ._args import MAX_TRAIN_STEPS, bounded_int


def _positive_int(text: str) -> int:
    import argparse

    try:
        value = int(text.replace("_", ""))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}")
    return value


def _nonneg_int(text: str) -> int:
    import argparse

    try:
        value = int(text.replace("_", ""))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be an integer >= 0, got {text!r}")
    return value


def register(sub) -> None:
    from train.config import ACTION_MODES
    from train.sb3.config import ALGOS

    from ..scenarios import scenario_names

    p = sub.add_parser("train", help="train an SB3 policy (PPO/recurrent PPO/SAC/TD3) or RLlib multi-agent PPO on a "
                                     "formation scenario")
    p.add_argument("--backend", default="sb3", choices=("sb3", "rllib"),
                   help="sb3 (default): Stable-Baselines3 on the native VecEnv; rllib: multi-agent PPO on Ray RLlib "
                        "through the PettingZoo env (needs the 'distributed' extra)")
    p.add_argument("--scenario", default=None, help=f"one of {scenario_names()} (required unless --resume)")
    p.add_argument("--algo", default=None, choices=ALGOS,
                   help="RL algorithm (sb3: required unless --resume; rllib: ppo, the default)")
    p.add_argument("--action-mode", default=None, choices=ACTION_MODES,
                   help="setpoints (PID tracker offsets), residual (added to the PID) or surfaces (direct); default: the task's "
                        "(set-points for every registered task)")
    p.add_argument("--steps", type=bounded_int(1, MAX_TRAIN_STEPS), default=None,
                   help=f"total environment steps, 1..{MAX_TRAIN_STEPS:,} (sb3: agent decisions; rllib: formation "
                        "decisions); default: n_timesteps of the hyperparameters")
    p.add_argument("--seed", type=_nonneg_int, default=None, help="seed of the env, the model and torch (default 0)")
    p.add_argument("--config", default=None,
                   help="YAML hyperparameter file merged over train/hyperparams/<algo>.yml (rllib: rllib_ppo.yml)")
    p.add_argument("--out", default=None, help="run directory (default runs/<scenario>-<algo>-<mode>-seed<k>-<timestamp>)")
    p.add_argument("--overwrite", action="store_true", help="allow an existing non-empty run directory")
    p.add_argument("--resume", action="store_true", help="continue the run in --out from its last checkpoint")
    r = p.add_argument_group("RLlib backend (--backend rllib)")
    r.add_argument("--iterations", type=_positive_int, default=None,
                   help="stop after this many PPO iterations (also stops at --steps)")
    r.add_argument("--num-env-runners", type=_nonneg_int, default=None,
                   help="sampling actors (default 2; 0 samples in the driver)")
    r.add_argument("--num-envs-per-env-runner", type=_positive_int, default=None, help="envs per actor (default 1)")
    r.add_argument("--policies", default=None, choices=("shared", "per-role"),
                   help="shared (default): one policy for every learning UAV; per-role: leader and follower policies")
    r.add_argument("--learning", default=None, choices=("followers", "all"),
                   help="which UAVs learn: followers (default; vehicle 0 flies the PID on its path) or all")
    r.add_argument("--address", default=None,
                   help="Ray cluster to join: auto (the cluster this machine is part of) or HEAD_HOST:PORT; "
                        "default: a local Ray instance on 127.0.0.1")
    r.add_argument("--num-cpus", type=_positive_int, default=None,
                   help="CPUs of the local Ray instance (default: all of this machine's)")
    bar = p.add_mutually_exclusive_group()
    bar.add_argument("--progress-bar", dest="progress_bar", action="store_true", default=None,
                     help="SB3's tqdm/rich progress bar (default: on when installed and stderr is a terminal)")
    bar.add_argument("--no-progress-bar", dest="progress_bar", action="store_false", help="plain progress lines")
    p.set_defaults(func=run)


def _check_config(path: str | None) -> None:
    """A --config file must be a readable YAML mapping (checked before any training work)."""
    import os

    if path is None or not os.path.isfile(path):
        return  # a missing file is reported by the trainer ("does not exist")
    import yaml

    try:
        with open(path, encoding="utf-8") as f:
            data = yaml.safe_load(f)
    except UnicodeDecodeError:
        raise ValueError(f"--config {path!r}: not a text (YAML) file") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or type(exc).__name__
        raise ValueError(f"--config {path!r}: invalid YAML{where}: {problem}") from None
    if data is not None and not isinstance(data, dict):
        raise ValueError(f"--config {path!r}: must be a YAML mapping of hyperparameters, got a {type(data).__name__}")


_RLLIB_ONLY = ("iterations", "num_env_runners", "num_envs_per_env_runner", "policies", "learning", "address",
               "num_cpus")


def run(args) -> int:
    if args.resume and args.overwrite:
        raise ValueError("--resume and --overwrite exclude each other")
    if args.num_cpus is not None and args.address is not None:
        raise ValueError("--num-cpus applies only to a local Ray instance (without --address)")
    _check_config(args.config)
    command = "formation-env " + " ".join(shlex.quote(a) for a in sys.argv[1:]) if sys.argv[1:2] == ["train"] else None
    if args.backend == "rllib":
        from train.rllib.backend import train_rllib

        if args.algo not in (None, "ppo"):
            raise ValueError(f"--backend rllib trains multi-agent PPO only, got --algo {args.algo}")
        if args.progress_bar is not None:
            raise ValueError("--progress-bar/--no-progress-bar: only with --backend sb3 (RLlib logs a line per iteration)")
        train_rllib(scenario=args.scenario, action_mode=args.action_mode, seed=args.seed, steps=args.steps,
                    iterations=args.iterations, policies=args.policies, learning=args.learning,
                    num_env_runners=args.num_env_runners, num_envs_per_env_runner=args.num_envs_per_env_runner,
                    address=args.address, num_cpus=args.num_cpus, config_file=args.config, out_dir=args.out,
                    overwrite=args.overwrite, resume=args.resume, command=command)
        return 0
    given = [f"--{k.replace('_', '-')}" for k in _RLLIB_ONLY if getattr(args, k) is not None]
    if given:
        raise ValueError(f"{', '.join(given)}: only with --backend rllib")
    from train.sb3.train import train

    train(scenario=args.scenario, algo=args.algo, action_mode=args.action_mode,
          seed=0 if args.seed is None else args.seed, steps=args.steps, config_file=args.config, out_dir=args.out,
          overwrite=args.overwrite, resume=args.resume, progress_bar=args.progress_bar, command=command)
    return 0


__all__ = ["register", "run"]
