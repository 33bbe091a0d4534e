"""Task ``vee_rotation`` (issue 25): vee5's leader hands the apex to vehicle 1 and drops back to a trailing slot.
The schedule starts and ends in vee5's joint-optimum vee, never brings two slots closer than the vee's own
rank spacing, and the task is a registered, flyable unit judged by the reconfiguration success."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import formation_env
from formation_env.constants import AEROSONDE_SPAN_M as SPAN
from formation_env.scenarios import SlotSchedule, get_scenario
from formation_env.sim.config import EnvConfig
from formation_env.sim.params import hold_remaining_decisions
from formation_env.tasks import get_task
from formation_env.tasks.close_formations import optimum as opt
from formation_env.tasks.close_formations.rotation import PHASES_S, rotation_keyframes


def _positions(t):
    """(5, T, 3) every UAV's nominal slot, m from vehicle 0 (vehicle 0 at the origin)."""
    sc = get_scenario("vee_rotation")
    return np.stack([np.zeros((len(t), 3))] + [s.offset_and_rate(t)[0] for s in sc.slots])


def test_starts_and_ends_in_the_vee5_optimum_with_vehicle_1_at_the_apex():
    """At t = 0 the followers fly vee5's slots; after the last keyframe the five UAVs form the same vee (every
    offset from the apex equal to one of vee5's slots, each used once) with vehicle 1 at the apex and vehicle 0
    at the end of the starboard side (vee5's starboard rank 2)."""
    slots = np.asarray(opt.optimum("vee5")["slots_b"]) * SPAN
    p = _positions(np.array([0.0, PHASES_S[-2], PHASES_S[-1]]))
    np.testing.assert_allclose(p[1:, 0], slots, atol=1e-9)
    np.testing.assert_allclose(p[:, 1], p[:, 2], atol=1e-12)  # held after the last keyframe
    rel = p[:, -1] - p[1, -1]  # from the new apex
    assert np.allclose(rel[0], slots[2])  # vehicle 0: starboard rank 2
    others = sorted(map(tuple, np.round(np.delete(rel, 1, axis=0), 9)))
    assert others == sorted(map(tuple, np.round(slots, 9)))


def test_no_two_slots_ever_closer_than_the_vees_rank_spacing():
    """Over the whole schedule (10 ms samples) every pair of nominal slots stays at least 5.1 m apart (the
    rank-1 spacing of the vee, 3.5x the 1.45 m collision separation); the passes are abeam at >= 1.78 b."""
    t = np.arange(0.0, PHASES_S[-1] + 1e-9, 0.01)
    p = _positions(t)
    d = min(np.min(np.linalg.norm(p[i] - p[j], axis=-1)) for i in range(5) for j in range(i + 1, 5))
    assert d > 5.1, d
    # vehicle 1 passes vehicle 0 abeam: at x = 0 its lateral offset is two rank-1 steps
    x1 = p[1, :, 0]
    k = np.argmin(np.abs(x1))
    assert abs(p[1, k, 1]) > 1.75 * SPAN


def test_the_hold_phase_and_the_success_window_fit_the_episode():
    """The last keyframe is 18 s before the time limit: the 5 s success window starts after it for every
    follower (the hold phase of RewardWeights.hold is 180 decisions at 10 Hz)."""
    sc = get_scenario("vee_rotation")
    assert sc.duration_s == PHASES_S[-1]
    assert all(s.keyframes[-1][0] == PHASES_S[-2] for s in sc.slots)
    np.testing.assert_array_equal(hold_remaining_decisions(sc, sc.duration_s, 10.0), [-1, 180, 180, 180, 180])


def test_bad_phases_are_refused():
    slots = opt.optimum("vee5")["slots_b"]
    for bad in ((15.0, 10.0, 50.0, 62.0, 80.0), (0.0, 25.0, 50.0, 62.0, 80.0), (15.0, 25.0, 50.0, 62.0)):
        with pytest.raises(ValueError, match="phases_s"):
            rotation_keyframes(slots, bad)
    SlotSchedule(rotation_keyframes(slots)[0])  # the default is a valid schedule


def test_registered_task_and_gym_id_fly():
    """The task is registered with its baselines, the Gymnasium id steps, and every follower learns in the
    PettingZoo env (4 agents)."""
    task = get_task("vee_rotation")
    assert task.baselines == ("pid", "station_keeper")
    assert EnvConfig(scenario="vee_rotation").scenario == "vee_rotation"
    env = gym.make(task.gym_id, action_mode="setpoints")
    obs, _ = env.reset(seed=3)
    obs, r, term, trunc, _ = env.step(env.action_space.sample())
    assert np.all(np.isfinite(obs)) and np.isfinite(r) and not term
    env.close()
    par = formation_env.parallel_env("vee_rotation", action_mode="setpoints", learning="followers")
    obs, _ = par.reset(seed=1)
    assert len(par.agents) == 4
    par.close()


def test_station_keeper_rotates_a_calm_vee_and_pid_cannot():
    """Judged as the task is evaluated (every UAV an agent, the success over the followers only: vehicle 0 has no
    slot): in calm air the station keeper on every UAV flies the rotation within 1 span of every final slot for
    the last 5 s without a collision (measured 30 of 30 from seeds 7200000000..); the thesis PID, whose vehicle 0
    swings in the new vee's wake, does not (26 collisions in 30)."""
    from train.evaluation.episodes import eval_env_config, run_episodes
    from train.evaluation.policy_loader import load_policy

    keeper = load_policy("station_keeper")
    cfg = eval_env_config("vee_rotation", keeper.action_mode, turbulence_sigma_mps=0.0)
    assert cfg.learning == "all"
    (m,) = run_episodes(keeper, cfg, [7200000001])
    assert m["reconfig_success"] and not m["collision"] and m["min_separation_m"] > 4.0
    assert 40.0 < m["reconfig_time_s"] < 50.0  # from the schedule's start (15 s) to within 1 span for good (~58 s)
    pid = load_policy("pid")
    (m,) = run_episodes(pid, eval_env_config("vee_rotation", pid.action_mode, turbulence_sigma_mps=0.0), [7200000001])
    assert not m["reconfig_success"]
