"""``formation-env train``: train an SB3 policy (PPO, SAC or TD3) on a formation scenario.

See ``train/train.py`` for the run directory layout and ``docs/training.md`` for the committed runs."""

from __future__ import annotations

import shlex
import sys


def _positive_int(text: str) -> int:
    import argparse

    try:
        value = int(text.replace("_", ""))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}")
    return value


def _seed(text: str) -> int:
    import argparse

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be an integer >= 0, got {text!r}")
    return value


def register(sub) -> None:
    from train.config import ACTION_MODES, ALGOS

    from ..scenarios import scenario_names

    p = sub.add_parser("train", help="train an SB3 policy (PPO/SAC/TD3) on a formation scenario")
    p.add_argument("--scenario", default=None, help=f"one of {scenario_names()} (required unless --resume)")
    p.add_argument("--algo", default=None, choices=ALGOS, help="RL algorithm (required unless --resume)")
    p.add_argument("--action-mode", default="residual", choices=ACTION_MODES,
                   help="surfaces (direct), residual (added to the PID, default) or setpoints (PID tracker offsets)")
    p.add_argument("--steps", type=_positive_int, default=None,
                   help="total environment steps (agent decisions); default: n_timesteps of the hyperparameters")
    p.add_argument("--seed", type=_seed, default=0, help="seed of the env, the model and torch (default 0)")
    p.add_argument("--config", default=None, help="YAML hyperparameter file merged over train/hyperparams/<algo>.yml")
    p.add_argument("--out", default=None, help="run directory (default runs/<scenario>-<algo>-<mode>-seed<k>-<timestamp>)")
    p.add_argument("--overwrite", action="store_true", help="allow an existing non-empty run directory")
    p.add_argument("--resume", action="store_true", help="continue the run in --out from its last checkpoint")
    bar = p.add_mutually_exclusive_group()
    bar.add_argument("--progress-bar", dest="progress_bar", action="store_true", default=None,
                     help="SB3's tqdm/rich progress bar (default: on when installed and stderr is a terminal)")
    bar.add_argument("--no-progress-bar", dest="progress_bar", action="store_false", help="plain progress lines")
    p.set_defaults(func=run)


def run(args) -> int:
    from train.train import train

    if args.resume and args.overwrite:
        raise ValueError("--resume and --overwrite exclude each other")
    command = "formation-env " + " ".join(shlex.quote(a) for a in sys.argv[1:]) if sys.argv[1:2] == ["train"] else None
    train(scenario=args.scenario, algo=args.algo, action_mode=args.action_mode, seed=args.seed, steps=args.steps,
          config_file=args.config, out_dir=args.out, overwrite=args.overwrite, resume=args.resume,
          progress_bar=args.progress_bar, command=command)
    return 0


__all__ = ["register", "run"]
