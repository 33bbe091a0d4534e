"""MAPPO on vee5: one actor shared by the four followers of a vee of five, a centralised critic.

The actor reads each follower's own observation; the critic reads the agent-specific global state (its own
observation, then the other followers' of its formation: ``GlobalStateVecEnv``). The project's
``CentralCriticPolicy`` (train/sb3/central_critic.py) splits the two inside SB3's PPO, so execution stays
decentralised: the saved policy flies on plain per-agent observations, like a shared-PPO one. The env is the
project's batched vector env on the task's benchmark configuration; the hyperparameters are the committed recipe's
(train/hyperparams/ppo.yml, section vee5, with train/hyperparams/mappo.yml's policy). The trained policy is then
flown against the station keeper on held-out episodes (the task's headline: the formation's induced-drag saving).

    python examples/mappo_vee5.py            # the recipe's 4M steps, then 100 test episodes
    python examples/mappo_vee5.py --smoke    # 2,048 steps, then 2 short test episodes

The full run is the committed recipe's budget (how long the committed runs took: ``wall_s`` in their records,
train/policies/vee5_mappo_setpoints_seed*.json). ``formation-env train --scenario vee5 --algo ppo --config
train/hyperparams/mappo.yml`` runs the same recipe (its final model is this script's, bit for bit) with
validation-based model selection: the committed policies were made with it.
"""

import argparse
import json
import time
from pathlib import Path

import torch
from stable_baselines3 import PPO
from stable_baselines3.common.utils import LinearSchedule

from formation_env.envs import FormationVecEnv
from formation_env.tasks import get_task
import formation_env.own_packages  # noqa: F401  `train` below is the project's, even beside a user's train.py
from train.evaluation.evaluate import evaluate
from train.sb3.central_critic import CentralCriticPolicy, GlobalStateVecEnv
from train.sb3.reward_scale import ScaleReward

TASK = get_task("vee5")

# the committed recipe (train/hyperparams/ppo.yml: vee5; mappo.yml: policy CentralCriticPolicy)
TOTAL_STEPS = 4_000_000
N_FORMATIONS = 8           # 8 vees x 4 learning followers = 32 env indices
REWARD_SCALE = 0.05
PPO_KWARGS = dict(learning_rate=LinearSchedule(3e-4, 0.0, 1.0),  # decayed linearly to 0 over the run
                  n_steps=128, batch_size=512, n_epochs=10, gamma=0.995, gae_lambda=0.95, clip_range=0.2,
                  ent_coef=0.0, vf_coef=0.5, max_grad_norm=0.5)
NET = dict(net_arch=[64, 64], activation_fn=torch.nn.Tanh, log_std_init=-1.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--smoke", action="store_true", help="a few thousand steps and 2 short test episodes")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default="runs/example-mappo-vee5", help="where the model goes")
    args = parser.parse_args()
    steps, n_formations = (2_048, 2) if args.smoke else (TOTAL_STEPS, N_FORMATIONS)
    kwargs = dict(PPO_KWARGS, batch_size=128) if args.smoke else PPO_KWARGS

    torch.set_num_threads(1)
    venv = FormationVecEnv(n_formations, TASK.default_config(), seed=args.seed)  # rows formation-major
    agents = venv.num_envs // n_formations  # the learning followers of each vee
    env = ScaleReward(GlobalStateVecEnv(venv, agents), REWARD_SCALE)
    local_dim = venv.observation_space.shape[0]  # what the actor reads: the follower's own observation
    model = PPO(CentralCriticPolicy, env, policy_kwargs=dict(NET, local_dim=local_dim), seed=args.seed,
                device="cpu", verbose=0, **kwargs)
    print(f"training MAPPO on {TASK.gym_id}: {n_formations} vees x {agents} followers, actor input {local_dim}, "
          f"critic input {env.observation_space.shape[0]}, {steps:,} steps")
    t0 = time.perf_counter()
    model.learn(total_timesteps=steps)
    print(f"trained {model.num_timesteps:,} steps in {time.perf_counter() - t0:.0f} s")
    env.close()

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "model.zip"
    model.save(path)
    # the sidecar the policy loader reads (vee5's published policies fly without a guard)
    sidecar = {"algo": "ppo", "task": TASK.name, "task_version": TASK.version, "scenario": TASK.scenario_name,
               "action_mode": TASK.action_mode, "control_hz": 10.0,
               "num_timesteps": int(model.num_timesteps)}
    path.with_suffix(".json").write_text(json.dumps(sidecar, indent=2) + "\n")
    print(f"saved {path} and {path.with_suffix('.json').name}")

    protocol = TASK.evaluation
    report = evaluate([str(path), "station_keeper"], scenario=TASK.scenario_name,
                      episodes=2 if args.smoke else protocol.episodes, seeds=[protocol.seed_base],
                      turbulence_sigma_mps=protocol.headline_level, compute_benefit=True,
                      duration_s=5.0 if args.smoke else None, n_boot=1000 if args.smoke else 10_000)
    print(report["table_markdown"])
    for name in ("model", "station_keeper"):
        s = report["policies"][name]["summary"]
        print(f"{name}: formation saving {s['formation_saving']:.3f}, "
              f"collisions {s['collisions']}/{len(report['seeds'])}")


if __name__ == "__main__":
    main()
