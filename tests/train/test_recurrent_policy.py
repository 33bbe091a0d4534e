"""Recurrent PPO (sb3-contrib) through training, the Policy protocol, ``load_policy``, ``evaluate`` and ``replay``: its
LSTM state is carried from one decision to the next, ``reset(n_rows)`` starts it, and the same observations after a
reset give the same actions bit for bit. One tiny policy (a few hundred steps) is trained once for the module."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("sb3_contrib")
pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")

SCENARIO = "reconfiguration"


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    from tests.train.conftest import TINY
    from train.sb3.train import train

    out = tmp_path_factory.mktemp("rppo") / "run"
    s = train(scenario=SCENARIO, algo="recurrent_ppo", seed=2, steps=256, out_dir=out, overrides=TINY["recurrent_ppo"],
              progress_bar=False, log=lambda m: None)
    assert s["num_timesteps"] == 256 and s["algo"] == "recurrent_ppo"
    return out


@pytest.fixture(scope="module")
def zip_path(run_dir):
    return run_dir / "final_model.zip"


def _obs(n_rows: int, n_steps: int, size: int, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).normal(0.0, 0.5, (n_steps, n_rows, size)).astype(np.float32)


def _fly(policy, obs: np.ndarray) -> np.ndarray:
    policy.reset(obs.shape[1])
    return np.stack([np.asarray(policy.act(o)) for o in obs])


def test_the_run_validates_and_checkpoints_a_recurrent_policy(run_dir):
    meta = json.loads((run_dir / "final_model.json").read_text())
    assert meta["algo"] == "recurrent_ppo" and meta["scenario"] == SCENARIO
    ev = json.loads((run_dir / "evaluations.json").read_text())
    assert [e["num_timesteps"] for e in ev] == [128, 256] and "reconfig_success_rate" in ev[0]
    assert (run_dir / "best_model.zip").is_file() and (run_dir / "checkpoints" / "model_128_steps.zip").is_file()
    cfg = (run_dir / "config.yaml").read_text()
    assert "MlpLstmPolicy" in cfg and "lstm_hidden_size: 8" in cfg


def test_load_policy_gives_the_policy_protocol_with_a_recurrent_state(zip_path):
    from formation_env.rollout import Policy
    from train.evaluation.policy_loader import load_policy
    from train.evaluation.safe_zip import load_sb3_model
    from train.recurrent import RecurrentActor, is_recurrent

    pol = load_policy(str(zip_path))
    assert isinstance(pol, Policy) and callable(pol.reset) and pol.action_mode == "setpoints"
    assert is_recurrent(load_sb3_model(zip_path))  # the algorithm read off the zip (no sidecar asked)
    size = load_sb3_model(zip_path).observation_space.shape[0]
    obs = _obs(3, 6, size)
    a = _fly(pol, obs)
    assert a.shape == (6, 3, 4) and np.all(np.isfinite(a))
    # a fresh reset reproduces the same actions bit for bit
    np.testing.assert_array_equal(_fly(pol, obs), a)
    # the state matters: the last observations acted on without the history before them give other actions
    pol.reset(3)
    fresh = np.asarray(pol.act(obs[-1]))
    assert np.max(np.abs(fresh - a[-1])) > 1e-3 * np.max(np.abs(a[-1]))  # far above the float rounding below
    # rows are independent: a row's actions depend on its own observations only (to the float rounding of another
    # batch size)
    np.testing.assert_allclose(_fly(pol, obs[:, 1:2]), a[:, 1:2], rtol=1e-4, atol=1e-8)
    # start(rows): only those rows begin afresh, the others keep their history
    actor = RecurrentActor(load_sb3_model(zip_path))
    actor.reset(3)
    for o in obs[:3]:
        actor.act(o)
    actor.start([1])
    b = actor.act(obs[3])
    np.testing.assert_array_equal(b[[0, 2]], a[3][[0, 2]])
    actor.reset(1)
    np.testing.assert_allclose(b[1], actor.act(obs[3][1:2])[0], rtol=1e-4, atol=1e-8)
    with pytest.raises(ValueError, match="reset for 1 rows, asked to act on 3"):
        actor.act(obs[0])


def test_evaluate_and_replay_fly_the_recurrent_state(zip_path, tmp_path, capsys):
    """The evaluation carries the state through the episode (its results differ from a policy that forgets it at
    every decision) and is reproducible; replay flies the same policy, seeded and reproducible."""
    from formation_env.cli import main
    from formation_env.replay import EpisodeLog
    from train.evaluation.episodes import eval_env_config, run_episodes
    from train.evaluation.evaluate import evaluate
    from train.evaluation.policy_loader import load_policy
    from train.evaluation.safe_zip import load_sb3_model
    from train.recurrent import RecurrentActor

    kw = dict(scenario=SCENARIO, episodes=2, duration_s=3.0, plots=False, n_boot=200)
    r1 = evaluate([str(zip_path), "pid"], **kw)
    r2 = evaluate([str(zip_path), "pid"], **kw)
    name = zip_path.stem
    assert r1["policies"][name]["episodes"] == r2["policies"][name]["episodes"]
    config = eval_env_config(SCENARIO, "setpoints", duration_s=3.0)
    carried = run_episodes(load_policy(str(zip_path)), config, [5, 6])
    actor = RecurrentActor(load_sb3_model(zip_path))

    class Forgetful:  # the same LSTM started afresh at every decision
        def reset(self, n_rows):
            actor.reset(n_rows)

        def act(self, obs):
            actor.start(np.arange(len(obs)))
            return actor.act(obs)

    forgot = run_episodes(Forgetful(), config, [5, 6])
    assert [e["rms_slot_error_m"] for e in carried] != [e["rms_slot_error_m"] for e in forgot]

    logs = []
    for d in ("a", "b"):
        assert main(["replay", "--policy", str(zip_path), "--scenario", SCENARIO, "--duration", "2", "--seed", "5",
                     "--out", str(tmp_path / d)]) == 0
        out = json.loads(capsys.readouterr().out)
        assert out["status"] == "completed" and out["samples"] == 21
        logs.append(EpisodeLog.load_npz(tmp_path / d / f"{SCENARIO}_log.npz"))
    np.testing.assert_array_equal(logs[0].position_ned, logs[1].position_ned)


def test_recurrent_ppo_resumes_from_its_checkpoint(run_dir, tmp_path):
    import shutil

    from train.sb3.train import train

    run = tmp_path / "run"
    shutil.copytree(run_dir, run)
    for p in (run / "checkpoints").glob("model_256_steps.zip"):
        p.unlink()
    s = train(out_dir=run, resume=True, steps=256, progress_bar=False, log=lambda m: None)
    assert s["resumed_from"] == 128 and s["num_timesteps"] == 256


def test_recurrent_ppo_configuration_errors_name_the_value():
    from train.sb3.config import TrainConfig

    with pytest.raises(ValueError, match="MlpLstmPolicy goes with algo recurrent_ppo.*'ppo'"):
        TrainConfig(scenario=SCENARIO, algo="ppo", action_mode="setpoints", seed=0, n_timesteps=64,
                    policy="MlpLstmPolicy")
    with pytest.raises(ValueError, match="'MlpPolicy' with algo 'recurrent_ppo'"):
        TrainConfig(scenario=SCENARIO, algo="recurrent_ppo", action_mode="setpoints", seed=0, n_timesteps=64)
    with pytest.raises(ValueError, match=r"unknown policy_kwargs key\(s\) \['lstm_hidden_size'\]"):
        TrainConfig(scenario=SCENARIO, algo="ppo", action_mode="setpoints", seed=0, n_timesteps=64,
                    policy_kwargs={"lstm_hidden_size": 8})
    with pytest.raises(ValueError, match="lstm_hidden_size must be an integer"):
        TrainConfig(scenario=SCENARIO, algo="recurrent_ppo", action_mode="setpoints", seed=0, n_timesteps=64,
                    policy="MlpLstmPolicy", policy_kwargs={"lstm_hidden_size": 0})


def test_without_sb3_contrib_recurrent_ppo_is_one_clear_error(monkeypatch):
    import sys

    from train.recurrent import recurrent_ppo_class

    monkeypatch.setitem(sys.modules, "sb3_contrib", None)
    with pytest.raises(ValueError, match="recurrent_ppo needs sb3-contrib"):
        recurrent_ppo_class()


def test_unknown_algo_names_the_value_and_the_choices(capsys):
    from formation_env.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["train", "--scenario", SCENARIO, "--algo", "dqn"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "'dqn'" in err and "recurrent_ppo" in err and "sac" in err
