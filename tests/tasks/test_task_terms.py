"""Task terms in Python (formation_env.tasks.terms): composed after the compiled step, they add to the reward,
append to the observation, end episodes and make per-episode metrics, every formation at once; the compiled step
underneath is untouched, and a task without terms flies the plain Simulation."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from formation_env.scenarios import SCENARIOS, get_scenario
from formation_env.sim import EnvConfig, Simulation
from formation_env.sim.composed import ComposedSimulation
from formation_env.tasks import TASKS, Task, get_task, register_task
from formation_env.tasks.compose import task_simulation
from formation_env.tasks.terms import MetricTerm, ObservationTerm, RewardTerm, TaskTerms, TerminationTerm

NAME = "terms_probe"


class Counter:
    """A stateful term: decisions since the formation's reset, per UAV."""

    def reset(self, sim, indices) -> None:
        if not hasattr(self, "n") or self.n.shape != (sim.batch_size, sim.n_vehicles):
            self.n = np.zeros((sim.batch_size, sim.n_vehicles))
        self.n[indices] = 0.0
        self.t = sim.time_s.copy()

    def __call__(self, sim):
        if not np.array_equal(self.t, sim.time_s):
            self.n += 1.0
            self.t = sim.time_s.copy()
        return self.n


@pytest.fixture
def probe():
    counter = Counter()
    sc = dataclasses.replace(get_scenario("formation_keeping"), name=NAME, duration_s=2.0)
    terms = TaskTerms(
        rewards=(RewardTerm("lateral", lambda sim: -np.abs(sim.info.slot_error_track_m[..., 1]), weight=0.5),),
        observations=(ObservationTerm("count", counter, size=1), ObservationTerm("alt", lambda sim: np.stack(
            [-sim.aircraft[..., 12] / 1000.0, np.zeros(sim.aircraft.shape[:2])], axis=-1), size=2)),
        terminations=(TerminationTerm("late", lambda sim: sim.time_s >= 1.0 - 1e-9),),
        metrics=(MetricTerm("count_last", counter, "last"), MetricTerm("lateral_mean",
                                                                       lambda sim: sim.info.slot_error_track_m[..., 1])))
    task = register_task(Task(NAME, sc, options={"action_mode": "setpoints"}, terms=terms))
    yield task, counter
    TASKS.pop(NAME)
    SCENARIOS.pop(NAME)


def test_the_terms_compose_after_the_compiled_step(probe):
    task, counter = probe
    cfg = task.default_config()
    composed, plain = task_simulation(cfg, batch_size=2), Simulation(cfg, batch_size=2)
    assert isinstance(composed, ComposedSimulation) and composed.obs_size == plain.obs_size + 3
    a, b = composed.reset(None, [3, 4]), plain.reset(None, [3, 4])
    d = plain.obs_size
    assert np.array_equal(a.observation[..., :d], b.observation) and np.all(a.observation[..., d] == 0.0)
    rng = np.random.default_rng(0)
    for k in range(1, 11):
        act = rng.uniform(-1, 1, (2, composed.n_agents, 4))
        a, b = composed.step(act), plain.step(act)
        lateral = -0.5 * np.abs(plain.info.slot_error_track_m[..., 1])
        assert np.array_equal(a.observation[..., :d], b.observation)  # the compiled observation untouched
        if k < 10:
            assert np.allclose(a.reward, b.reward + lateral, rtol=0, atol=1e-12)
            assert np.all(a.observation[..., d] == k)
            assert composed.infos(0)[1]["reward_lateral"] == pytest.approx(lateral[0, 1])
            assert composed.infos(0)[1]["reward_total"] == pytest.approx(a.reward[0, 1])
        else:  # the Python termination at 1 s: both formations end, terminated, and stay frozen
            assert a.terminated.all() and not a.truncated.any() and not b.terminated.any()
    ret = composed.state.episode_return.copy()
    again = composed.step(np.zeros((2, composed.n_agents, 4)))
    assert np.all(again.reward == 0.0) and np.array_equal(composed.state.episode_return, ret)
    composed.reset([1], [9])  # a reset resets the stateful term of that formation only
    assert counter.n[1, 0] == 0.0 and counter.n[0, 0] == 10.0


def test_the_envs_and_the_evaluation_fly_the_terms(probe):
    import gymnasium as gym  # noqa: F401

    from formation_env import parallel_env
    from formation_env.envs import FormationVecEnv
    from formation_env.rollout import ZeroPolicy
    from train.evaluation.episodes import run_episodes

    task, _ = probe
    env = parallel_env(NAME, obs_mode="dict", learning="followers")
    obs, _ = env.reset(seed=1)
    assert obs["uav_1"]["count"].shape == (1,) and obs["uav_1"]["alt"].shape == (2,)
    assert env.observation_space("uav_1")["alt"].shape == (2,)
    obs, rew, term, trunc, infos = env.step({"uav_1": np.zeros(4, np.float32)})
    assert obs["uav_1"]["count"][0] == 1.0 and "reward_lateral" in infos["uav_1"]
    venv = FormationVecEnv(2, task.default_config(), seed=0)
    o = venv.reset()
    assert o.shape == (2, Simulation(task.default_config()).obs_size + 3)
    for _ in range(10):
        o, r, done, infos = venv.step(np.zeros((2, 4), np.float32))
    assert done.all() and infos[0]["episode"]["l"] == 10 and not infos[0]["TimeLimit.truncated"]
    eps = run_episodes(ZeroPolicy(), dataclasses.replace(task.default_config(), learning="followers"), [5, 6])
    assert [e["count_last"] for e in eps] == [10.0, 10.0] and all(np.isfinite(e["lateral_mean"]) for e in eps)
    assert eps[0]["duration_s"] == pytest.approx(1.0)


def test_a_task_holds_objects_and_the_built_in_tasks_fly_the_compiled_step():
    for name in TASKS:
        t = get_task(name)
        assert t.terms is None and not isinstance(t.reference, str) and not isinstance(t.metrics, str)
        assert type(task_simulation(EnvConfig(scenario=t.scenario_name))) is Simulation
    with pytest.raises(ValueError, match="import string"):
        Task("x", "formation_keeping", reference="formation_env.tasks.close_formation.optimum")
    with pytest.raises(ValueError, match="compiled reward"):
        TaskTerms(rewards=(RewardTerm("slot", lambda sim: 0.0),))
    with pytest.raises(ValueError, match="size"):
        ObservationTerm("x", lambda sim: 0.0, size=0)
    assert get_task("wake_surfing").evaluator is not None and get_task("close_formation").evaluator is None
