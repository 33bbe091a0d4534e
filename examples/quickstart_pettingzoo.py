"""Quick start: the PettingZoo parallel env of the close_formation task.

A follower holds the induced-drag optimum 2 spans behind and 0.93 span starboard of the leader, in the leader's
wake. The env is the task's benchmark configuration (set-point actions, its reward, its turbulence draw); the
observation is asked for as named groups (``obs_mode="dict"``) so that each one can be printed. Two controllers
fly the same seeded episode: the thesis PID (a zero set-point offset: the PID flies the slot itself) and random
set-point offsets. Each step prints the UAV's reward, the wind its leader's wake induces on it and its
induced-drag saving (infos); the end prints what each controller harvested.

    python examples/quickstart_pettingzoo.py            # one full 60 s episode per controller
    python examples/quickstart_pettingzoo.py --smoke    # 20 decisions (2 s) per controller
"""

import argparse

import numpy as np

import formation_env


def fly(env, controller: str, steps: int | None, seed: int = 0) -> dict:
    """One episode (or its first ``steps`` decisions) of ``env`` flown by ``controller`` ("pid" or "random")."""
    obs, infos = env.reset(seed=seed)
    for space in map(env.action_space, env.agents):
        space.seed(seed)
    rewards, savings, slot_errors, n = [], [], [], 0
    while env.agents and (steps is None or n < steps):
        if controller == "pid":  # set-point offsets of zero: the thesis PID flies the slot
            actions = {agent: np.zeros(4, np.float32) for agent in env.agents}
        else:  # offsets of up to 5 m (along, starboard, below the slot) and 2 m/s
            actions = {agent: env.action_space(agent).sample() for agent in env.agents}
        obs, reward, terminated, truncated, infos = env.step(actions)
        n += 1
        for agent in reward:
            rewards.append(reward[agent])
            savings.append(infos[agent]["induced_drag_saving"])
            slot_errors.append(infos[agent]["slot_error_m"])
            if n <= 3 or n % 100 == 0:  # the first decisions, then every 10 s
                wind = infos[agent]["induced_wind_ned_mps"]
                print(f"  t = {infos[agent]['time_s']:5.1f} s  {agent}: reward {reward[agent]:+8.3f}, slot error "
                      f"{infos[agent]['slot_error_m']:5.2f} m, induced wind (N, E, D) "
                      f"({wind[0]:+.2f}, {wind[1]:+.2f}, {wind[2]:+.2f}) m/s, "
                      f"induced-drag saving {infos[agent]['induced_drag_saving']:.3f}")
    return {"decisions": n, "return": float(np.sum(rewards)), "mean_saving": float(np.mean(savings)),
            "rms_slot_error_m": float(np.sqrt(np.mean(np.square(slot_errors))))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--smoke", action="store_true", help="20 decisions per controller instead of full episodes")
    args = parser.parse_args()
    steps = 20 if args.smoke else None

    # the task's benchmark env with the benchmark's learners (the follower; the leader flies the thesis PID on its
    # track); obs_mode="dict" names the observation groups (learning code keeps the flat vector)
    env = formation_env.parallel_env("close_formation", learning="followers", obs_mode="dict")
    obs, infos = env.reset(seed=0)
    print(f"agents: {env.agents}")
    print(f"action space: {env.action_space(env.agents[0])} ({env.config.action_mode})")
    for agent, groups in obs.items():
        print(f"{agent}'s observation groups:")
        for name, values in groups.items():
            print(f"  {name:22s} {values.shape[0]:3d}  {np.array2string(values[:4], precision=3)}"
                  + (" ..." if values.shape[0] > 4 else ""))
    print(f"info keys: {sorted(infos[env.agents[0]])}")

    results = {}
    for controller in ("pid", "random"):
        print(f"\n{controller}:")
        results[controller] = fly(env, controller, steps)
    env.close()

    print("\ncontroller  decisions  return     RMS slot error  mean induced-drag saving")
    for controller, r in results.items():
        print(f"{controller:10s}  {r['decisions']:9d}  {r['return']:+9.1f}  {r['rms_slot_error_m']:11.2f} m  "
              f"{r['mean_saving']:.3f}")


if __name__ == "__main__":
    main()
