"""The Ray RLlib backend: a loopback-only Ray with 2 CPUs trains with 2 env runners, checkpoints,
restores and evaluates, and leaves no Ray process behind; clear errors for a missing extra and an
unreachable cluster; nothing outside the backend imports ray."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from formation_env.cli import main
from formation_env.errors import MissingDependencyError

pytest.importorskip("ray.rllib", reason="needs the 'distributed' extra (ray[rllib]); `make test` installs it")

REPO = Path(__file__).resolve().parents[2]
CLI = [sys.executable, "-m", "formation_env.cli"]
TINY = {"training": {"train_batch_size_per_learner": 200, "minibatch_size": 100, "num_epochs": 1},
        "model": {"fcnet_hiddens": [16]}, "env_kwargs": {"duration_s": 3.0}, "checkpoint_every": 1}


# ray_tmpdir, ray_processes (leftover checks) and loopback_only_prefix are shared fixtures: tests/train/conftest.py


def _cli(args, tmpdir, cwd, prefix):
    env = dict(os.environ, RAY_TMPDIR=tmpdir, PYTHONPATH=str(REPO))
    env.pop("RAY_ADDRESS", None)
    return subprocess.run(prefix + CLI + args, cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=480)


def test_rllib_trains_checkpoints_restores_and_evaluates_on_loopback_ray(tmp_path, ray_tmpdir, ray_processes,
                                                                         loopback_only_prefix):
    cfg = tmp_path / "tiny.yml"
    cfg.write_text(yaml.safe_dump(TINY))
    run = tmp_path / "run"
    # A relative --out, as users type it (RLlib itself wants absolute checkpoint paths).
    base = ["train", "--backend", "rllib", "--scenario", "formation_keeping", "--num-cpus", "2", "--out", "run"]

    r = _cli(base + ["--num-env-runners", "2", "--iterations", "2", "--seed", "3", "--config", str(cfg)],
             ray_tmpdir, tmp_path, loopback_only_prefix)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    if loopback_only_prefix:  # inside the namespace the only address Ray can find is loopback
        assert "node address 127.0.0.1" in r.stdout  # read back from ray.nodes()
    ray_processes.assert_none_left()
    ck2 = run / "checkpoints" / "iter_000002"
    meta = json.loads((ck2 / "formation_env.json").read_text())
    assert meta["modules"] == ["shared"] and meta["iteration"] == 2 and meta["env_steps"] == 400
    assert (ck2 / "learner_group" / "learner" / "rl_module" / "shared").is_dir()
    assert not [p for p in (run / "checkpoints").iterdir() if p.name.startswith(".")]  # no temporaries left
    rows = (run / "progress.csv").read_text().splitlines()
    assert len(rows) == 3 and rows[0].startswith("iteration,env_steps_lifetime")
    assert all(float(r.split(",")[-1]) > 0 for r in rows[1:])  # sampled env steps/s recorded
    summary = json.loads((run / "summary.json").read_text())
    assert summary["num_env_runners"] == 2 and summary["iterations"] == 2

    # The same directory is never silently reused.
    r = _cli(base + ["--iterations", "1"], ray_tmpdir, tmp_path, loopback_only_prefix)
    assert r.returncode == 2 and "not empty" in r.stderr

    # Resume: restores iteration 2 (weights, optimiser, counters) and goes on to 3.
    r = _cli(base + ["--resume", "--iterations", "3", "--num-env-runners", "1"], ray_tmpdir, tmp_path,
             loopback_only_prefix)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    assert "resuming" in r.stdout and "iter_000002" in r.stdout
    ray_processes.assert_none_left()
    meta3 = json.loads((run / "checkpoints" / "iter_000003" / "formation_env.json").read_text())
    assert meta3["iteration"] == 3 and meta3["env_steps"] == 600
    assert len((run / "progress.csv").read_text().splitlines()) == 4

    # The restored weights are the saved ones, and training moved them on.
    from train.rllib.backend import load_rllib_policy

    obs = np.random.default_rng(0).normal(size=(8, _obs_size(2))).astype(np.float32)
    a2 = load_rllib_policy(ck2).act(obs)
    a3 = load_rllib_policy(run).act(obs)  # a run directory means its latest checkpoint
    assert a2.shape == (8, 4) and np.all(np.abs(a2) <= 1.0)
    assert np.array_equal(a2, load_rllib_policy(ck2).act(obs))
    assert not np.array_equal(a2, a3)

    # RLlib-, SB3- and PID-flown episodes in one table.
    sb3 = sorted((REPO / "train" / "policies").glob("formation_keeping_*.zip"))[0]
    out = tmp_path / "eval"
    r = _cli(["evaluate", "--scenario", "formation_keeping", "--policy", str(run), "--policy", str(sb3),
              "--policy", "pid", "--episodes", "2", "--duration", "3", "--no-plots", "--out", str(out)],
             ray_tmpdir, tmp_path, loopback_only_prefix)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    res = json.loads((out / "results.json").read_text())
    names = list(res["policies"])
    assert len(names) == 3 and names[0].startswith("rllib-") and names[2] == "pid"
    for p in res["policies"].values():
        assert p["summary"]["episodes"] == 2 and np.isfinite(p["summary"]["rms_slot_error_m"])
    header = (out / "results.md").read_text()
    assert all(n in header for n in names)
    ray_processes.assert_none_left()


def test_rllib_per_role_policies_train_leader_and_follower(tmp_path, ray_tmpdir, ray_processes, monkeypatch):
    import ray

    from train.rllib.backend import load_rllib_policy, train_rllib

    monkeypatch.setenv("RAY_TMPDIR", ray_tmpdir)
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    s = train_rllib(scenario="echelon", action_mode="surfaces", learning="all", policies="per-role", iterations=1,
                    num_env_runners=0, num_cpus=1, out_dir=tmp_path / "run", overrides=TINY, log=lambda m: None)
    assert not ray.is_initialized()
    ray_processes.assert_none_left()
    assert s["modules"] == ["leader", "follower"]
    ck = Path(s["checkpoint"])
    for m in ("leader", "follower"):
        assert (ck / "learner_group" / "learner" / "rl_module" / m).is_dir()
    row = (tmp_path / "run" / "progress.csv").read_text().splitlines()[1].split(",")
    assert int(row[3]) == 3 * int(row[2])  # agent steps: all three UAVs acted at every env step
    leader = load_rllib_policy(ck, module_id="leader").act(np.zeros((2, _obs_size(3)), np.float32))
    assert leader.shape == (2, 4)
    with pytest.raises(ValueError, match="no module 'shared'"):
        load_rllib_policy(ck, module_id="shared")


def test_rllib_same_seed_reproduces_the_run_with_two_env_runners(tmp_path, ray_tmpdir, ray_processes, monkeypatch):
    import ray
    import yaml as _yaml

    from train.rllib.backend import RLlibTrainConfig, build_algo_config, connect, load_rllib_policy, train_rllib

    monkeypatch.setenv("RAY_TMPDIR", ray_tmpdir)
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    quiet = {"log": lambda m: None}
    obs = np.random.default_rng(1).normal(size=(16, _obs_size(2))).astype(np.float32)

    def returns(run, upto=2):
        return [r.split(",")[:6] for r in (run / "progress.csv").read_text().splitlines()[1:upto + 1]]

    assert connect(None, num_cpus=2, **quiet)  # one instance for every run below
    try:
        runs = {}
        for name, seed in (("a", 7), ("b", 7), ("c", 8)):
            runs[name] = tmp_path / name
            train_rllib(scenario="formation_keeping", seed=seed, iterations=2, num_env_runners=2, out_dir=runs[name],
                        overrides=TINY, **quiet)
        act = {k: load_rllib_policy(v).act(obs) for k, v in runs.items()}
        assert returns(runs["a"]) == returns(runs["b"]) and np.array_equal(act["a"], act["b"])
        assert returns(runs["a"]) != returns(runs["c"]) and not np.array_equal(act["a"], act["c"])

        # restore_from_path really puts the checkpoint's weights into the Algorithm.
        cfg = RLlibTrainConfig(**_yaml.safe_load((runs["a"] / "config.yaml").read_text())["config"])
        algo = build_algo_config(cfg).build_algo()
        try:
            def module_actions():
                import torch

                m = algo.get_module("shared")
                with torch.no_grad():
                    out = m.forward_inference({"obs": torch.from_numpy(obs)})["action_dist_inputs"][:, :4]
                return np.clip(out.numpy(), -1, 1)

            fresh = module_actions()
            algo.restore_from_path(str(runs["a"] / "checkpoints" / "iter_000002"))
            assert algo.iteration == 2
            assert np.allclose(module_actions(), act["a"], atol=1e-6) and not np.allclose(fresh, act["a"], atol=1e-3)
        finally:
            algo.stop()

        # A resume given only --steps runs to those steps (the first run's iteration cap no longer applies).
        s = train_rllib(out_dir=runs["c"], resume=True, steps=600, **quiet)
        assert s["iterations"] == 3 and s["env_steps"] == 600 and s["resumed_from_iteration"] == 2
        with pytest.raises(ValueError, match="already at iteration 3"):
            train_rllib(out_dir=runs["c"], resume=True, steps=600, **quiet)
        with pytest.raises(ValueError, match="seed 9 differs"):
            train_rllib(out_dir=runs["c"], resume=True, seed=9, steps=800, **quiet)

        # The sampling benchmark (formation-env bench --rllib) on the same instance, tiny.
        from train.rllib.backend import benchmark_sampling

        bench = benchmark_sampling((0, 2), rounds=1, batch=100, **quiet)
        assert set(bench["results"]) == {0, 2}
        assert all(r["env_steps_per_s_sampling"] > 0 and r["env_steps_per_s_training"] > 0
                   for r in bench["results"].values())
        assert ray.is_initialized()  # it did not shut down an instance it did not start

        # --overwrite replaces the earlier run's checkpoints and logs instead of mixing with them.
        train_rllib(scenario="formation_keeping", seed=7, iterations=1, num_env_runners=2, out_dir=runs["c"],
                    overwrite=True, overrides=TINY, **quiet)
        assert sorted(p.name for p in (runs["c"] / "checkpoints").iterdir()) == ["iter_000001"]
        assert len((runs["c"] / "progress.csv").read_text().splitlines()) == 2
        assert not list(runs["c"].glob("summary-resume-*.json"))
    finally:
        ray.shutdown()
    ray_processes.assert_none_left()


def _obs_size(n_vehicles: int) -> int:
    from formation_env.envs.observations import observation_size

    return observation_size(n_vehicles)


def test_rllib_env_wrapper_keeps_agent_order_and_scales_rewards():
    import formation_env
    from train.rllib.env import FormationMultiAgentEnv, role_policy, shared_policy

    cfg = {"scenario": "echelon", "action_mode": "surfaces", "learning": "all", "env_kwargs": {}, "reward_scale": 0.5}
    env = FormationMultiAgentEnv(cfg)
    assert env.possible_agents == ["uav_0", "uav_1", "uav_2"]
    from formation_env.sim.config import Randomisation

    # env_kwargs {}: the generic posing, not the task's (a run's env_kwargs arrive merged over the task's)
    ref = formation_env.parallel_env("echelon", learning="all", action_mode="surfaces", obs_mode="flat",
                                     randomisation=Randomisation())
    obs, _ = env.reset(seed=4)
    obs_ref, _ = ref.reset(seed=4)
    assert all(np.array_equal(obs[a], obs_ref[a]) for a in ref.possible_agents)
    act = {a: np.full(4, 0.1, np.float32) for a in env.agents}
    _, rew, term, trunc, _ = env.step(act)
    _, rew_ref, _, _, _ = ref.step(act)
    assert all(rew[a] == pytest.approx(0.5 * rew_ref[a], rel=1e-12) for a in rew_ref)
    assert term["__all__"] is False and trunc["__all__"] is False
    assert [role_policy(a) for a in env.possible_agents] == ["leader", "follower", "follower"]
    assert {shared_policy(a) for a in env.possible_agents} == {"shared"}


def test_rllib_env_runners_and_resumes_draw_distinct_episodes():
    # RLlib seeds runner i's sub-env j with seed + i + j: runner 1 / sub-env 1 and runner 2 / sub-env 0
    # get the same number, and a resumed run reseeds its runners. Their episodes must still differ.
    from ray.rllib.env.env_context import EnvContext

    from train.rllib.env import FormationMultiAgentEnv

    cfg = {"scenario": "formation_keeping", "action_mode": "residual", "learning": "followers",
           "env_kwargs": {"randomisation": {"initial_offset_m": 2.0}}}

    def first_obs(worker, seed, stream=0):
        env = FormationMultiAgentEnv(EnvContext(dict(cfg, episode_stream=stream), worker_index=worker))
        return env.reset(seed=seed)[0]["uav_1"]

    base = first_obs(1, 100 + 1 + 1)
    assert np.array_equal(base, first_obs(1, 102))                 # reproducible
    assert not np.array_equal(base, first_obs(2, 100 + 2 + 0))     # another runner, same RLlib seed
    assert not np.array_equal(base, first_obs(1, 102, stream=40))  # the same runner after a resume


def test_address_parsing_and_unreachable_cluster_errors(capsys, tmp_path, monkeypatch, ray_tmpdir):
    from train.rllib.backend import ClusterUnreachableError, check_reachable, connect, parse_address

    assert parse_address(None) is None and parse_address("local") is None and parse_address("auto") == "auto"
    assert parse_address("10.0.0.5:6379") == ("10.0.0.5", 6379)
    assert parse_address("[::1]:6379") == ("::1", 6379)
    for bad in ("10.0.0.5", "host:", ":6379", "host:70000", "host:port"):
        with pytest.raises(ValueError, match="HOST:PORT"):
            parse_address(bad)
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    t0 = time.perf_counter()
    with pytest.raises(ClusterUnreachableError, match=f"127.0.0.1:{port}.*ray start --head"):
        check_reachable("127.0.0.1", port)
    assert time.perf_counter() - t0 < 30  # refused at once, not after Ray's minute of retries
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    monkeypatch.setenv("RAY_TMPDIR", ray_tmpdir)
    # "auto" falls back to any GCS process Ray finds on the machine (ray._private.services.find_gcs_addresses, a
    # process scan): with test_multinode.py's cluster alive on the other xdist worker it joined that cluster, which
    # was then torn down, and ray.init waited on its GCS for ever (the suite hung twice, measured). This test is
    # about a machine without a cluster: make the scan see none.
    import functools

    import ray._private.services as ray_services

    @functools.lru_cache  # Ray clears the real one's cache
    def no_gcs_processes():
        return []

    monkeypatch.setattr(ray_services, "find_gcs_addresses", no_gcs_processes)
    with pytest.raises(ClusterUnreachableError, match="no running Ray cluster"):
        connect("auto", log=lambda m: None)
    out = tmp_path / "run"
    code = main(["train", "--backend", "rllib", "--scenario", "formation_keeping", "--address", f"127.0.0.1:{port}",
                 "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and f"cannot reach a Ray cluster at 127.0.0.1:{port}" in err
    assert not out.exists()  # nothing written for a run that never started
    code = main(["train", "--backend", "rllib", "--scenario", "formation_keeping", "--address", "nowhere"])
    assert code == 2 and "HOST:PORT" in capsys.readouterr().err


def test_missing_ray_gives_the_install_command(capsys, monkeypatch, tmp_path):
    from train.rllib.backend import require_rllib

    monkeypatch.setitem(sys.modules, "ray", None)  # import ray -> ImportError, as when it is not installed
    with pytest.raises(MissingDependencyError, match=r'pip install -e "\.\[distributed\]"'):
        require_rllib()
    code = main(["train", "--backend", "rllib", "--scenario", "formation_keeping", "--out", str(tmp_path / "r")])
    assert code == 2 and "[distributed]" in capsys.readouterr().err
    (tmp_path / "ck").mkdir()
    (tmp_path / "ck" / "formation_env.json").write_text("{}")
    code = main(["evaluate", "--scenario", "formation_keeping", "--policy", str(tmp_path / "ck"), "--no-plots",
                 "--out", str(tmp_path / "e")])
    assert code == 2 and "[distributed]" in capsys.readouterr().err


def test_nothing_outside_the_backend_imports_ray():
    code = ("import sys, formation_env, formation_env.envs, formation_env.cli, formation_env.runs.runner, "
            "agents.station_keeper, train.sb3.train, train.evaluation.evaluate, train.rllib.backend\n"
            "formation_env.cli.build_parser()\n"
            "env = formation_env.parallel_env('formation_keeping'); env.reset(seed=0)\n"
            "print('ray' in sys.modules)")
    r = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.strip() == "False"


def test_cli_backend_options_do_not_mix(capsys, tmp_path):
    for argv, msg in (
            (["train", "--scenario", "formation_keeping", "--algo", "ppo", "--num-env-runners", "2"],
             "--num-env-runners: only with --backend rllib"),
            (["train", "--backend", "rllib", "--scenario", "formation_keeping", "--algo", "sac"], "PPO only"),
            (["train", "--backend", "rllib", "--scenario", "formation_keeping", "--no-progress-bar"],
             "only with --backend sb3"),
            (["train", "--backend", "rllib", "--scenario", "formation_keeping", "--address", "ray://h:10001"],
             "not supported"),
            (["train", "--backend", "rllib", "--scenario", "formation_keeping", "--address", "auto", "--num-cpus", "2"],
             "local Ray instance"),
            (["bench", "--runners", "2"], "only with --rllib")):
        assert main(argv) == 2, argv
        assert msg in capsys.readouterr().err, argv
    run = tmp_path / "run"
    run.mkdir()
    (run / "config.yaml").write_text(yaml.safe_dump({"backend": "rllib", "config": {"scenario": "formation_keeping"}}))
    assert main(["train", "--out", str(run), "--resume"]) == 2
    assert "resume it with --backend rllib" in capsys.readouterr().err
    assert main(["train", "--backend", "rllib", "--out", str(run), "--resume", "--config", "x.yml"]) == 2
    assert "--config applies to new runs only" in capsys.readouterr().err


def test_rllib_config_rejects_bad_values():
    from train.rllib.backend import RLlibTrainConfig

    with pytest.raises(ValueError, match="policies must be one of"):
        RLlibTrainConfig(scenario="formation_keeping", policies="each")
    with pytest.raises(ValueError, match="unknown training key"):
        RLlibTrainConfig(scenario="formation_keeping", training={"learning_rate": 1e-3})
    with pytest.raises(ValueError, match="num_env_runners must be an integer >= 0"):
        RLlibTrainConfig(scenario="formation_keeping", num_env_runners=-1)
    with pytest.raises(ValueError, match="no followers"):
        RLlibTrainConfig(scenario="tracking")
    with pytest.raises(ValueError, match="unknown scenario"):
        RLlibTrainConfig(scenario="airshow")
    with pytest.raises(ValueError, match="give the run an end"):
        RLlibTrainConfig(scenario="formation_keeping", n_timesteps=None, iterations=None)
    assert RLlibTrainConfig(scenario="echelon", learning="all", policies="per-role").modules == ["leader", "follower"]
    assert RLlibTrainConfig(scenario="echelon", policies="per-role").modules == ["follower"]
