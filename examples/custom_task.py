"""Write your own task in one Python file: find and hold the station behind the leader where the follower burns the
least fuel.

The engine is used as it is (no compiled code here, and defining the task recompiles nothing). The task takes
wake_surfing's scenario under a new name (the follower moves its set-point within a safe box behind the leader)
and poses it with Python terms composed after the compiled decision step (:mod:`formation_env.tasks.terms`):

* a reward term paying the follower's fuel-flow saving against the leader's (the 6-DOF engine's fuel flow, where
  every effect of the wake on the aircraft ends up), beside the compiled box and along-track terms;
* an observation group: that saving, appended after the compiled observation;
* a termination: the follower more than 30 m off its slot;
* a per-episode metric: the mean fuel-flow saving.

It is registered as a task (its Gymnasium id ``custom/FuelSlot-v0``), trained with Stable-Baselines3 PPO on the
batched vector env and evaluated against the thesis PID by the project's evaluation, whose episodes carry the
task's metric beside the generic ones.

    python examples/custom_task.py            # 300k PPO steps, then 20 held-out episodes
    python examples/custom_task.py --smoke    # 2,048 steps, then 4 short held-out episodes
"""

import argparse
import dataclasses
import weakref
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3 import PPO

import formation_env.own_packages  # noqa: F401  `train` below is the project's, even beside a user's train.py
from formation_env.envs import FormationVecEnv, register_envs
from formation_env.scenarios import get_scenario
from formation_env.sim.config import RewardWeights
from formation_env.tasks import EvaluationProtocol, Task, register_task
from formation_env.tasks.terms import MetricTerm, ObservationTerm, RewardTerm, TaskTerms, TerminationTerm
from formation_env.tasks.wake_surfing import WAKE_SURFING_TRAINING_RANDOMISATION
from train.evaluation.evaluate import evaluate
from train.sb3.reward_scale import ScaleReward


class FuelFlowSaving:
    """Each UAV's fuel-flow saving over the last decision, 1 - its fuel flow / the leader's, (B, V). One object serves
    every term (its ``reset`` is called after each reset): per simulation it keeps the fuel at the previous decision
    and computes the saving once per decision."""

    def __init__(self) -> None:
        self.state = weakref.WeakKeyDictionary()  # simulation -> its previous fuel, decision time and saving

    def reset(self, sim, indices) -> None:
        fuel = sim.aircraft[:, :, 13]  # kg, every UAV (the state's fuel column)
        st = self.state.setdefault(sim, {"fuel": fuel.copy(), "saving": np.zeros_like(fuel)})
        st["fuel"][indices] = sim.aircraft[indices, :, 13]
        st["saving"][indices] = 0.0
        st["time"] = sim.time_s.copy()

    def __call__(self, sim) -> np.ndarray:
        st = self.state[sim]
        if not np.array_equal(st["time"], sim.time_s):  # a new decision
            fuel = sim.aircraft[:, :, 13]
            burnt = st["fuel"] - fuel  # kg over the decision, per UAV
            st["saving"] = np.clip(1.0 - burnt / np.maximum(burnt[:, :1], 1e-12), -1.0, 1.0)
            st["fuel"], st["time"] = fuel.copy(), sim.time_s.copy()
        return st["saving"]


fuel_saving = FuelFlowSaving()
SCENARIO = dataclasses.replace(get_scenario("wake_surfing"), name="fuel_slot",
                               description="hold the station of least fuel flow in wake_surfing's safe box")
# the compiled terms keep the follower in the box at its along-track distance; the saving is the Python term's
REWARD = RewardWeights(slot=1.0, progress=1.0, benefit=0.0, box=4.0, box_scale_b=0.1, effort=0.01, rate=0.05)

TASK = register_task(Task(
    "fuel_slot", SCENARIO, "custom/FuelSlot", version=0, baselines=("pid",),
    options={"action_mode": "setpoints", "reward": REWARD, "randomisation": WAKE_SURFING_TRAINING_RANDOMISATION},
    evaluation=EvaluationProtocol(levels=(0.0, 0.25), headline_level=0.25, episodes=20),
    description="hold the station of least fuel flow behind the leader",
    terms=TaskTerms(
        rewards=(RewardTerm("fuel_flow_saving", fuel_saving, weight=2.0),),
        observations=(ObservationTerm("fuel_flow_saving", fuel_saving, size=1),),
        terminations=(TerminationTerm("lost_slot", lambda sim: sim.info.slot_error_m[:, 1] > 30.0),),
        metrics=(MetricTerm("fuel_flow_saving", fuel_saving),))))
register_envs()  # the new Gymnasium id


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--smoke", action="store_true", help="a few thousand steps and 4 short held-out episodes")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default="runs/example-custom-task", help="where the model goes")
    args = parser.parse_args()
    steps, n_formations = (2_048, 4) if args.smoke else (300_000, 16)

    env = gym.make(TASK.gym_id)  # the single-agent id, as any Gymnasium env
    obs, info = env.reset(seed=0)
    obs, reward, *_, info = env.step(env.action_space.sample())
    print(f"{TASK.gym_id}: observation {obs.shape[0]} (the last: the fuel-flow saving {obs[-1]:+.3f}), reward "
          f"{reward:+.3f} of which fuel_flow_saving {info['reward_fuel_flow_saving']:+.3f}")
    env.close()

    torch.set_num_threads(1)
    venv = ScaleReward(FormationVecEnv(n_formations, TASK.default_config(), seed=args.seed), 0.05)
    model = PPO("MlpPolicy", venv, n_steps=128, batch_size=128, gamma=0.99, seed=args.seed, device="cpu",
                policy_kwargs=dict(net_arch=[64, 64], log_std_init=-1.0))
    model.learn(total_timesteps=steps)
    print(f"trained {model.num_timesteps:,} steps")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    model.save(out / "model.zip")

    # held-out episodes, the policy and the thesis PID on the same ones; each episode has the task's metric
    protocol = TASK.evaluation
    report = evaluate([str(out / "model.zip"), "pid"], scenario=TASK.scenario_name, action_mode="setpoints",
                      episodes=4 if args.smoke else protocol.episodes, seeds=[protocol.seed_base],
                      turbulence_sigma_mps=protocol.headline_level, duration_s=10.0 if args.smoke else None,
                      plots=False, n_boot=1000)
    for name, r in report["policies"].items():
        saving = [e["fuel_flow_saving"] for e in r["episodes"]]
        print(f"{name}: fuel-flow saving {np.mean(saving):+.3f} (mean of {len(saving)} episodes), "
              f"RMS slot error {r['summary']['rms_slot_error_m']:.2f} m")


if __name__ == "__main__":
    main()
