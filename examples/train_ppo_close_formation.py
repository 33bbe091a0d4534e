"""Train Stable-Baselines3 PPO on close_formation, then judge it against the baselines on held-out episodes.

The env is the project's batched vector env (``FormationVecEnv``: 32 formations stepped in one compiled call, each
learning UAV one SB3 env index) on the task's benchmark configuration; the hyperparameters are the committed
recipe's (train/hyperparams/ppo.yml, section close_formation), the separation guard filters the set-points in the
loop as in the committed runs, and the rewards the learner sees are scaled by 0.05. The trained policy is saved
with a sidecar JSON naming its action mode and guard (what the project's policy loader reads), and flown with the
thesis PID and the station keeper on the same held-out episodes (the project's evaluation: paired statistics).

    python examples/train_ppo_close_formation.py            # the recipe's 2.2M steps, then 100 test episodes
    python examples/train_ppo_close_formation.py --smoke    # 2,048 steps, then 4 short test episodes

The full run is the committed recipe's budget (how long the committed runs took: ``wall_s`` in their records,
train/policies/close_formation_ppo_setpoints_seed*.json). ``formation-env train --scenario close_formation --algo
ppo`` runs the same recipe (its final model is this script's, bit for bit) with validation-based model selection,
checkpoints and learning curves: the committed policies were made with it.
"""

import argparse
import json
import time
from pathlib import Path

import torch
from stable_baselines3 import PPO

from formation_env.envs import FormationVecEnv
from formation_env.tasks import get_task
import formation_env.own_packages  # noqa: F401  `train` below is the project's, even beside a user's train.py
from train.evaluation.evaluate import evaluate
from train.sb3.guard import GuardedVecEnv
from train.sb3.reward_scale import ScaleReward

TASK = get_task("close_formation")

# the committed recipe (train/hyperparams/ppo.yml: close_formation)
TOTAL_STEPS = 2_200_000
N_FORMATIONS = 32          # 32 formations x 1 learning follower = 32 env indices
REWARD_SCALE = 0.05        # per-episode returns ~ -900 -> ~ -45 for the value loss
PPO_KWARGS = dict(learning_rate=3e-4, n_steps=128, batch_size=512, n_epochs=10, gamma=0.995, gae_lambda=0.95,
                  clip_range=0.2, ent_coef=0.0, vf_coef=0.5, max_grad_norm=0.5,
                  policy_kwargs=dict(net_arch=[64, 64], activation_fn=torch.nn.Tanh, log_std_init=-1.0))


def make_env(n_formations: int, seed: int):
    venv = FormationVecEnv(n_formations, TASK.default_config(), seed=seed)  # the benchmark task
    venv = GuardedVecEnv(venv)  # the separation guard (agents/separation_guard.py) between policy and env
    return ScaleReward(venv, REWARD_SCALE)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--smoke", action="store_true", help="a few thousand steps and 4 short test episodes")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default="runs/example-ppo-close-formation", help="where the model goes")
    args = parser.parse_args()
    steps, n_formations = (2_048, 4) if args.smoke else (TOTAL_STEPS, N_FORMATIONS)
    kwargs = dict(PPO_KWARGS, batch_size=128) if args.smoke else PPO_KWARGS

    torch.set_num_threads(1)  # as the committed runs: the env's batch is the parallel part
    env = make_env(n_formations, args.seed)
    model = PPO("MlpPolicy", env, seed=args.seed, device="cpu", verbose=0, **kwargs)
    print(f"training PPO on {TASK.gym_id} ({n_formations} formations, {env.num_envs} env indices) for {steps:,} steps")
    t0 = time.perf_counter()
    model.learn(total_timesteps=steps)
    print(f"trained {model.num_timesteps:,} steps in {time.perf_counter() - t0:.0f} s")
    env.close()

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "model.zip"
    model.save(path)
    # the sidecar the policy loader reads: SB3 algorithm, action interface, and the guard the policy flies with
    # (the task's: the guard in the training loop plus its lateral clip, as the published policies)
    sidecar = {"algo": "ppo", "task": TASK.name, "task_version": TASK.version, "scenario": TASK.scenario_name,
               "action_mode": TASK.action_mode, "control_hz": 10.0,
               "action_guard": dict(TASK.guard_options) or True, "num_timesteps": int(model.num_timesteps)}
    path.with_suffix(".json").write_text(json.dumps(sidecar, indent=2) + "\n")
    print(f"saved {path} and {path.with_suffix('.json').name}")

    # held-out test episodes (seeds the training never draws), every policy on the same ones
    protocol = TASK.evaluation
    report = evaluate([str(path), "pid", "station_keeper"], scenario=TASK.scenario_name,
                      episodes=4 if args.smoke else protocol.episodes, seeds=[protocol.seed_base],
                      turbulence_sigma_mps=protocol.headline_level, compute_benefit=True,
                      duration_s=10.0 if args.smoke else None, n_boot=1000 if args.smoke else 10_000)
    print(report["table_markdown"])
    metric = protocol.metric  # the task's headline: the harvest ratio
    for baseline in ("pid", "station_keeper"):
        c = report["comparisons"]["model"][baseline][metric]  # paired by episode; reduction = baseline - model
        lo, hi = c["mean_reduction_ci"]
        print(f"{metric}, model minus {baseline}: {-c['mean_reduction']:+.3f} [{-hi:+.3f}, {-lo:+.3f}] "
              f"(better in {c['n_better']} of {c['n']} episodes)")


if __name__ == "__main__":
    main()
