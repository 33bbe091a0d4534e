"""close_formation in TorchRL: the PettingZoo env and the Gymnasium id wrapped as TorchRL envs.

``PettingZooWrapper`` over ``formation_env.parallel_env`` gives a multi-agent TensorDict env (the UAVs under one
group, their flat infos as tensors: every reward term and the induced-drag saving); ``GymEnv`` over the task's
Gymnasium id gives the single-agent view (the follower learns, the leader flies the thesis PID). Both are checked
with TorchRL's ``check_env_specs`` and rolled out, once with random set-point offsets and once with zero offsets
(the thesis PID flying the slot). From here TorchRL's collectors, losses and BenchMARL's task classes take over.

    python examples/torchrl_close_formation.py            # full 60 s episodes (600 decisions)
    python examples/torchrl_close_formation.py --smoke    # 10 decisions

Needs TorchRL (the ``compat`` extra: ``pip install -e ".[compat]"``).
"""

import argparse
import warnings

import torch
from torchrl.envs import GymEnv, PettingZooWrapper
from torchrl.envs.utils import check_env_specs

import formation_env
from formation_env.tasks import get_task

# TorchRL's PettingZoo wrapper is tested with an older PettingZoo release than the project's; it works with it
warnings.filterwarnings("ignore", message="PettingZoo in TorchRL is tested using version")

TASK = get_task("close_formation")


def pid_policy(env):
    """The thesis PID as a TorchRL policy: every set-point offset zero (the env's action spec, zeroed)."""
    zeros = env.full_action_spec.zero()
    return lambda td: td.update(zeros)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--smoke", action="store_true", help="10 decisions instead of full episodes")
    args = parser.parse_args()
    steps = 10 if args.smoke else 600

    # multi-agent: the PettingZoo parallel env, the benchmark's learners (the followers) under the group "uav"
    env = PettingZooWrapper(formation_env.parallel_env(TASK.name, learning="followers"), use_mask=True)
    check_env_specs(env, seed=0)
    print(f"PettingZooWrapper groups: {env.group_map}")
    (group,) = env.group_map
    for name, policy in (("random", None), ("pid", pid_policy(env))):
        env.set_seed(0)
        rollout = env.rollout(steps, policy=policy)
        info = rollout["next", group, "info"]
        print(f"  {name:6s}: {rollout.batch_size[0]} decisions, return {rollout['next', group, 'reward'].sum():+.1f}, "
              f"mean induced-drag saving {info['induced_drag_saving'].mean():.3f}, "
              f"final slot error {info['slot_error_m'][-1].max():.2f} m")
    env.close()

    # single-agent: the Gymnasium id of the task
    env = GymEnv(TASK.gym_id)
    check_env_specs(env, seed=0)
    print(f"GymEnv({TASK.gym_id!r}): observation {tuple(env.observation_spec['observation'].shape)}, "
          f"action {tuple(env.action_spec.shape)}")
    for name, policy in (("random", None), ("pid", pid_policy(env))):
        env.set_seed(0)
        rollout = env.rollout(steps, policy=policy)
        print(f"  {name:6s}: {rollout.batch_size[0]} decisions, return {rollout['next', 'reward'].sum():+.1f}, "
              f"done {bool(rollout['next', 'done'][-1])}")
    env.close()


if __name__ == "__main__":
    main()
