"""Multi-agent PPO on Ray RLlib: the four followers of a vee of five share one policy.

RLlib samples the PettingZoo parallel env (the task's benchmark configuration) on its env runners, one Ray actor
each, and updates one RLModule that every follower flies (``policies="per-role"`` would give the leader and the
followers one each). The project's backend (train/rllib/) starts a private Ray instance on this machine, writes
checkpoints that ``formation-env evaluate`` and the project's evaluation read, and shuts Ray down at the end. The
last checkpoint is then flown against the station keeper on held-out episodes.

    python examples/rllib_vee5.py            # train/hyperparams/rllib_ppo.yml's 1M env steps, 2 env runners
    python examples/rllib_vee5.py --smoke    # one tiny iteration, sampled in the driver

Needs the ``distributed`` extra (``pip install -e ".[distributed]"``: ray[rllib]). ``formation-env train --backend
rllib --scenario vee5`` is the command-line equivalent; ``--address`` runs it on an existing Ray cluster.
"""

import argparse

from formation_env.tasks import get_task
import formation_env.own_packages  # noqa: F401  `train` below is the project's, even beside a user's train.py
from train.evaluation.evaluate import evaluate
from train.rllib.backend import train_rllib

# a tiny run: small batches, one small layer, 3 s episodes, sampled in the driver (no env runner actors)
SMOKE = {"training": {"train_batch_size_per_learner": 200, "minibatch_size": 100, "num_epochs": 1},
         "model": {"fcnet_hiddens": [16]}, "env_kwargs": {"duration_s": 3.0}, "checkpoint_every": 1}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--smoke", action="store_true", help="one tiny iteration and 2 short test episodes")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default="runs/example-rllib-vee5", help="the run directory (checkpoints)")
    parser.add_argument("--num-cpus", type=int, default=2, help="CPUs of the local Ray instance")
    parser.add_argument("--env-runners", type=int, default=None,
                        help="Ray actors sampling the env (default: 2; with --smoke 0, the driver samples)")
    args = parser.parse_args()

    task = get_task("vee5")
    if args.smoke:
        run = dict(iterations=1, num_env_runners=0 if args.env_runners is None else args.env_runners, overrides=SMOKE)
    else:  # the n_timesteps of train/hyperparams/rllib_ppo.yml
        run = dict(num_env_runners=2 if args.env_runners is None else args.env_runners)
    summary = train_rllib(scenario=task.scenario_name, seed=args.seed, policies="shared", out_dir=args.out,
                          overwrite=True, num_cpus=args.num_cpus, **run)
    print(f"RLlib: {summary['iterations']} iterations, {summary['env_steps']:,} env steps in {summary['wall_s']} s "
          f"-> {summary['checkpoint']}")

    protocol = task.evaluation
    report = evaluate([summary["checkpoint"], "station_keeper"], scenario=task.scenario_name,
                      episodes=2 if args.smoke else protocol.episodes, seeds=[protocol.seed_base],
                      turbulence_sigma_mps=protocol.headline_level, compute_benefit=True,
                      duration_s=3.0 if args.smoke else None, n_boot=1000 if args.smoke else 10_000)
    print(report["table_markdown"])
    for name, result in report["policies"].items():
        s = result["summary"]
        print(f"{name}: formation saving {s['formation_saving']:.3f}, "
              f"collisions {s['collisions']}/{len(report['seeds'])}")


if __name__ == "__main__":
    main()
