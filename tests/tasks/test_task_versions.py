"""Every Gymnasium id is its task's benchmark, at a recorded version.

* ``gym.make(id)`` gives exactly the task's benchmark configuration (``Task.default_config``), and every committed
  policy trained on it (its sidecar's environment equals the task's, departures none, version recorded);
* each id's behaviour matches the fingerprint recorded for its version (formation_env/data/task_versions.json): a
  change of behaviour without a version bump fails here.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import gymnasium as gym
import pytest

import formation_env  # noqa: F401  (registers the ids)
from formation_env.tasks import TASKS, get_task
from formation_env.tasks.versions import compare, fingerprint, load_versions

REPO = Path(__file__).resolve().parents[2]
IDS = sorted(t.gym_id for t in TASKS.values() if t.gym_id)


def test_every_id_is_versioned_and_in_the_table():
    table = load_versions()
    for t in TASKS.values():
        if t.gym_id:
            assert t.gym_id.endswith(f"-v{t.version}") and t.gym_id in gym.registry
            assert t.gym_id in table, f"{t.gym_id}: run formation-env data task-versions to record it"
            assert table[t.gym_id]["task"] == t.name and table[t.gym_id]["version"] == t.version


@pytest.mark.parametrize("gym_id", IDS)
def test_fingerprint_matches_its_version(gym_id):
    recorded = load_versions()[gym_id]["fingerprint"]
    bad = compare(recorded, fingerprint(gym_id))
    assert not bad, (f"{gym_id} behaves differently from its recorded version ({'; '.join(bad)}): a task whose "
                     "behaviour changes needs a new Task.version")


def test_the_fingerprint_sees_a_change_of_the_benchmark():
    """The comparison fails on a change as small as one reward weight (so the test above can fail)."""
    task = get_task("formation_keeping")
    base = fingerprint(task.gym_id, decisions=10)
    changed = dataclasses.replace(task.options["reward"], effort=task.options["reward"].effort * 1.01)
    gym.register("formation_env_test/Changed-v1", entry_point="formation_env.envs.gym_env:FormationGymEnv",
                 max_episode_steps=gym.spec(task.gym_id).max_episode_steps,
                 kwargs={"scenario": "formation_keeping", "reward": changed})
    try:
        other = fingerprint("formation_env_test/Changed-v1", decisions=10)
    finally:
        del gym.registry["formation_env_test/Changed-v1"]
    assert compare(base, base) == []
    assert compare(base, other) and base["digest"] != other["digest"]


@pytest.mark.parametrize("name", [t.name for t in TASKS.values() if t.gym_id])
def test_gym_make_is_the_benchmark(name):
    task = get_task(name)
    env = gym.make(task.gym_id)
    try:
        cfg = env.unwrapped.config
        assert cfg == task.default_config(learning=(task.gym_learner,))
        for key, value in task.options.items():
            assert getattr(cfg, key) == value, key
    finally:
        env.close()
    # the PettingZoo env flies the same configuration (every UAV an agent unless learning= names the task's)
    par = formation_env.parallel_env(name)
    assert par.config == task.default_config(learning="all")
    if task.get_scenario().n_vehicles > 1:
        assert formation_env.parallel_env(name, learning=task.learning).config == task.default_config()


def _sidecars():
    for f in sorted((REPO / "train" / "policies").glob("*_seed[0-9].json")):
        yield pytest.param(f, id=f.stem)


@pytest.mark.parametrize("path", list(_sidecars()))
def test_committed_policies_trained_on_the_benchmark(path):
    from train.config import env_config_for, env_departures

    data = json.loads(path.read_text())
    env, cfg = data["env"], data["config"]
    task = get_task(env["task"])
    assert env["task_version"] == task.version and env["departures"] == {}
    assert task.scenario_name == cfg["scenario"] and task.action_mode == cfg["action_mode"]
    assert env_departures(cfg["scenario"], cfg["env_kwargs"]) == {}
    trained = env_config_for(cfg["scenario"], cfg["action_mode"], cfg["env_kwargs"])
    assert trained == task.default_config(learning=trained.learning, obs_mode="flat")


@pytest.mark.parametrize("name", ["close_formation", "formation_keeping", "vee5", "wake_surfing"])
def test_train_with_no_flags_trains_the_benchmark(name):
    """`formation-env train --scenario NAME --algo ppo` (no other flag): the task's action mode and environment."""
    from train.sb3.config import TrainConfig, load_hyperparams, make_env_config
    from train.sb3.train import default_action_mode

    task = get_task(name)
    mode = default_action_mode(name)
    assert mode == task.action_mode == "setpoints"
    for algo in ("ppo", "sac"):
        cfg = TrainConfig.from_hyperparams(load_hyperparams(algo, name), scenario=name, algo=algo, action_mode=mode,
                                           seed=0)
        env = make_env_config(cfg)
        assert env == task.default_config(learning=env.learning, obs_mode="flat")


def test_a_config_files_env_kwargs_is_a_recorded_departure(tmp_path):
    from train.sb3.config import TrainConfig, load_hyperparams
    from train.sb3.run_files import run_metadata

    f = tmp_path / "c.yml"
    f.write_text("close_formation:\n  env_kwargs:\n    reward:\n      benefit: 4.0\n")
    params = load_hyperparams("ppo", "close_formation", f)
    cfg = TrainConfig.from_hyperparams(params, scenario="close_formation", algo="ppo", action_mode="setpoints", seed=0)
    meta = run_metadata(cfg, 0)
    assert meta["task"] == "close_formation" and meta["task_version"] == 1
    assert meta["departures"] == {"reward": {"benefit": 4.0}}
    assert cfg.env_kwargs["reward"]["slot_scale_m"] == 0.29  # the rest of the benchmark kept


def test_evaluate_warns_on_another_task_version():
    from train.evaluation.policy_loader import warn_task_version

    with pytest.warns(UserWarning, match="version 0 of task 'close_formation'"):
        warn_task_version("p.zip", {"scenario": "close_formation", "task_version": 0})
    with pytest.warns(UserWarning, match="unrecorded version"):
        warn_task_version("p.zip", {"scenario": "close_formation"})
    assert warn_task_version("p.zip", {"scenario": "close_formation", "task_version": 1}) is None
