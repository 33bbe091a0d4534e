"""Fly a committed PPO policy against the baselines on held-out episodes, with paired statistics.

The policy is train/policies/close_formation_ppo_setpoints_seed0.zip; its sidecar JSON tells the project's loader
its action interface and the separation guard it flies through. The baselines are the thesis PID (``pid``) and the
station keeper (``station_keeper``, agents/station_keeper.py). Every policy flies the same episodes (seeds the
training never draws) as the task's evaluation protocol poses them: 100 episodes in a frozen von Karman field of
sigma 1 m/s, the induced-drag saving computed. The evaluation pairs the policies episode by episode and reports
95 % bootstrap intervals; the headline is the harvest ratio (the saving flown over the task's optimum).

    python examples/evaluate_committed.py            # the task's protocol: 100 episodes per policy
    python examples/evaluate_committed.py --smoke    # 4 episodes of 10 s

The command-line equivalent: ``formation-env evaluate --scenario close_formation --benefit --policy
train/policies/close_formation_ppo_setpoints_seed0.zip --policy pid --policy station_keeper``.
"""

import argparse
from pathlib import Path

from formation_env.tasks import get_task
import formation_env.own_packages  # noqa: F401  `train` below is the project's, even beside a user's train.py
from train.evaluation.evaluate import evaluate

REPO = Path(__file__).resolve().parents[1]
POLICY = REPO / "train" / "policies" / "close_formation_ppo_setpoints_seed0.zip"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--smoke", action="store_true", help="4 short episodes instead of the task's 100")
    parser.add_argument("--policy", default=str(POLICY), help="an SB3 zip with its sidecar, or an RLlib checkpoint")
    parser.add_argument("--out", default=None, help="also write results.json, results.md and plots here")
    args = parser.parse_args()

    task = get_task("close_formation")
    protocol = task.evaluation  # held-out seeds, episodes, turbulence level and headline metric of the task
    report = evaluate([args.policy, *task.baselines], scenario=task.scenario_name,
                      episodes=4 if args.smoke else protocol.episodes, seeds=[protocol.seed_base],
                      turbulence_sigma_mps=protocol.headline_level, compute_benefit=True,
                      duration_s=10.0 if args.smoke else None, n_boot=1000 if args.smoke else 10_000,
                      out_dir=args.out, log=print)

    print(f"\n{task.gym_id}: {len(report['seeds'])} held-out episodes, sigma {report['turbulence_sigma_mps']:g} m/s\n")
    print(report["table_markdown"])
    print("paired comparisons (reduction = baseline - policy, per episode):\n" + report["comparison_markdown"])

    name = Path(args.policy).stem
    metric = protocol.metric
    for baseline in ("pid", "station_keeper"):
        c = report["comparisons"][name][baseline][metric]
        lo, hi = c["mean_reduction_ci"]
        print(f"{metric}, {name} minus {baseline}: {-c['mean_reduction']:+.3f} [{-hi:+.3f}, {-lo:+.3f}] "
              f"(better in {c['n_better']} of {c['n']} episodes, sign test p = {c['sign_test_p']:.2g})")


if __name__ == "__main__":
    main()
