"""Residual policies on the station keeper (train.sb3.residual): the training env adds the learner's scaled action to
the keeper's set-points (the keeper's rows restarting with their episodes), the run's sidecars say so, load_policy
flies the loaded model the same way, and bad settings are refused with one line."""

import json

import numpy as np
import pytest

from agents.station_keeper import StationKeeper
from train.evaluation.policy_loader import load_policy
from train.sb3.config import TrainConfig
from train.sb3.residual import ResidualVecEnv, check_residual_on
from train.sb3.train import train

SPEC = {"agent": "station_keeper", "scale": 0.5}


@pytest.mark.parametrize("spec, match", [
    ({"agent": "pid", "scale": 0.5}, r"residual_on.agent must be one of \['station_keeper'\], got 'pid'"),
    ({"agent": "station_keeper", "scale": 0.0}, r"residual_on.scale must be a number in \(0, 2\], got 0.0"),
    ({"agent": "station_keeper", "scale": 2.5}, r"residual_on.scale must be a number in \(0, 2\], got 2.5"),
    ({"agent": "station_keeper", "scale": True}, r"residual_on.scale must be a number in \(0, 2\], got True"),
    ({"agent": "station_keeper", "scale": float("nan")}, r"residual_on.scale must be a number in \(0, 2\], got nan"),
    ({"agent": "station_keeper"}, r"residual_on must be a mapping"),
    ("station_keeper", r"residual_on must be a mapping"),
])
def test_bad_settings_are_refused(spec, match):
    with pytest.raises(ValueError, match=match):
        check_residual_on(spec)


def test_config_refuses_residuals_without_set_points():
    with pytest.raises(ValueError, match=r"residual_on adds to an agent's set-points; action mode 'surfaces'"):
        TrainConfig(scenario="echelon3", algo="ppo", action_mode="surfaces", seed=0, n_timesteps=10, residual_on=SPEC)
    with pytest.raises(ValueError, match=r"residual_on: scenario 'wake_surfing' has a safe box"):
        TrainConfig(scenario="wake_surfing", algo="ppo", action_mode="setpoints", seed=0, n_timesteps=10,
                    residual_on=SPEC)
    cfg = TrainConfig(scenario="echelon3", algo="ppo", action_mode="setpoints", seed=0, n_timesteps=10,
                      residual_on={"agent": "station_keeper", "scale": 1})
    assert cfg.residual_on == {"agent": "station_keeper", "scale": 1.0}


class _Recorder:
    """Wraps a VecEnv's step_async to keep every action the residual wrapper sends it."""

    def __init__(self, venv):
        self.sent = []
        real = venv.step_async

        def step_async(actions):
            self.sent.append(np.array(actions))
            real(actions)

        venv.step_async = step_async


def test_the_env_adds_the_learners_action_to_the_keepers_and_restarts_its_rows():
    """Over episodes that end (2 s long), the actions sent equal clip(keeper(obs) + scale a) with an independent
    keeper fed the same observations and zeroed on the same rows: the wrapper's keeper restarts with the episodes."""
    from formation_env.envs import EnvConfig, FormationVecEnv
    from formation_env.scenarios import get_scenario

    env = FormationVecEnv(2, EnvConfig(scenario=get_scenario("echelon3"), learning="followers", action_mode="setpoints",
                                       duration_s=2.0), seed=3)
    rec = _Recorder(env)
    wrapped = ResidualVecEnv(env, SPEC)
    twin = StationKeeper()
    obs = wrapped.reset()
    twin.reset(wrapped.num_envs)
    rng = np.random.default_rng(0)
    restarted = 0
    for _ in range(45):  # 2 s = 20 decisions: two episode ends
        a = rng.uniform(-1, 1, (wrapped.num_envs, 4)).astype(np.float32)
        want = np.clip(np.asarray(twin.act(obs), float) + 0.5 * a.astype(float), -1, 1)  # in float64, as sent
        obs, _, done, _ = wrapped.step(a)
        np.testing.assert_array_equal(rec.sent[-1], want)
        if done.any():
            twin.reset_rows(np.nonzero(done)[0])
            restarted += 1
    assert restarted == 2
    assert np.abs(want).max() <= 1.0 and not np.array_equal(want, np.clip(a, -1, 1))


def test_a_residual_run_and_its_loaded_policy(tmp_path, tiny):
    from stable_baselines3 import PPO

    out = tmp_path / "r"
    train(scenario="echelon3", algo="ppo", action_mode="setpoints", seed=0, steps=128, out_dir=out,
          overrides={**tiny("ppo"), "residual_on": SPEC}, progress_bar=False, log=lambda m: None)
    meta = json.loads((out / "best_model.json").read_text())
    assert meta["residual_on"] == SPEC
    pol = load_policy(str(out / "best_model.zip"))
    model = PPO.load(str(out / "best_model.zip"), device="cpu")
    from formation_env.envs import EnvConfig, FormationVecEnv
    from formation_env.scenarios import get_scenario

    env = FormationVecEnv(2, EnvConfig(scenario=get_scenario("echelon3"), learning="followers", action_mode="setpoints"),
                          seed=5)
    obs = env.reset()
    keeper = StationKeeper()
    keeper.reset(len(obs))
    pol.reset(len(obs))
    for _ in range(3):  # the keeper's integrators advance alike
        want = np.clip(np.asarray(keeper.act(obs), float) + 0.5 * model.predict(obs, deterministic=True)[0].astype(float),
                       -1, 1)
        got = pol.act(obs)
        np.testing.assert_array_equal(got, want)
        obs, *_ = env.step(got)
    # a sidecar naming an agent that does not exist is refused with one line
    bad = tmp_path / "p.zip"
    bad.write_bytes((out / "best_model.zip").read_bytes())
    bad.with_suffix(".json").write_text(json.dumps({"env": {**{k: meta[k] for k in ("algo", "scenario", "action_mode")},
                                                            "residual_on": {"agent": "keeper", "scale": 0.5}}}))
    with pytest.raises(ValueError, match=r"its metadata's residual_on.agent must be one of"):
        load_policy(str(bad))
