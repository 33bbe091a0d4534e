"""Training smoke runs: every algorithm x action mode, a few hundred steps, tiny nets."""

import json

import pytest

from train.sb3.train import train

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")


@pytest.mark.parametrize("mode", ["residual", "surfaces", "setpoints"])
@pytest.mark.parametrize("algo", ["ppo", "sac", "td3"])
def test_train_smoke(tmp_path, tiny, algo, mode):
    out = tmp_path / "run"
    steps = 256 if algo == "ppo" else 160
    s = train(scenario="formation_keeping", algo=algo, action_mode=mode, seed=3, steps=steps, out_dir=out,
              overrides=tiny(algo), progress_bar=False, log=lambda m: None)
    assert s["num_timesteps"] >= steps
    for name in ("config.yaml", "final_model.zip", "final_model.json", "best_model.zip", "curve.csv",
                 "evaluations.json", "summary.json", "logs/progress.csv"):
        assert (out / name).is_file(), name
    assert (out / "checkpoints" / "model_128_steps.zip").is_file()
    meta = json.loads((out / "final_model.json").read_text())
    assert meta["algo"] == algo and meta["action_mode"] == mode
    assert len((out / "curve.csv").read_text().splitlines()) > 1  # 3 s episodes finished
    assert not list(out.rglob(".*.zip"))  # no temporary files left behind


def test_train_reconfiguration_smoke(tmp_path, tiny):
    s = train(scenario="reconfiguration", algo="ppo", action_mode="residual", seed=0, steps=128,
              out_dir=tmp_path / "r", overrides=tiny("ppo"), progress_bar=False, log=lambda m: None)
    ev = json.loads((tmp_path / "r" / "evaluations.json").read_text())
    assert "reconfig_success_rate" in ev[0]
    assert s["num_timesteps"] == 128


def test_init_policy_starts_a_run_from_another_runs_parameters(tmp_path, tiny):
    """``init_policy`` (fine-tuning): the new model starts with the given zip's policy parameters exactly; a zip
    whose sizes differ, or a missing file, is one clear error."""
    import torch

    from train.sb3.config import TrainConfig
    from train.sb3.train import build_model, make_train_env

    train(scenario="formation_keeping", algo="ppo", action_mode="setpoints", seed=1, steps=128,
          out_dir=tmp_path / "a", overrides=tiny("ppo"), progress_bar=False, log=lambda m: None)
    src = str(tmp_path / "a" / "final_model.zip")
    params = {**tiny("ppo"), "n_timesteps": 64, "init_policy": src}
    algo_keys = {k: params.pop(k) for k in ("n_steps", "batch_size", "n_epochs")}
    cfg = TrainConfig(scenario="formation_keeping", algo="ppo", action_mode="setpoints", seed=5,
                      algo_kwargs=algo_keys, **{k: v for k, v in params.items() if k != "env_kwargs"},
                      env_kwargs=params["env_kwargs"])
    model = build_model(cfg, make_train_env(cfg, 5))
    from stable_baselines3 import PPO

    ref = PPO.load(src, device="cpu").policy.state_dict()
    for k, v in model.policy.state_dict().items():
        assert torch.equal(v, ref[k]), k
    with pytest.raises(ValueError, match="init_policy"):
        TrainConfig(scenario="formation_keeping", algo="ppo", action_mode="setpoints", seed=0, n_timesteps=64,
                    init_policy=str(tmp_path / "missing.zip"))
    # "{seed}" stands for the run's seed (each training seed fine-tuned from its own policy)
    import shutil

    shutil.copy(src, tmp_path / "pol_seed7.zip")
    placeheld = TrainConfig(scenario="formation_keeping", algo="ppo", action_mode="setpoints", seed=7, n_timesteps=64,
                            init_policy=str(tmp_path / "pol_seed{seed}.zip"))
    assert placeheld.init_policy == str(tmp_path / "pol_seed7.zip")
    with pytest.raises(ValueError, match="pol_seed8.zip"):
        TrainConfig(scenario="formation_keeping", algo="ppo", action_mode="setpoints", seed=8, n_timesteps=64,
                    init_policy=str(tmp_path / "pol_seed{seed}.zip"))
    wide = {**tiny("ppo"), "init_policy": src, "policy_kwargs": {"net_arch": [8, 8]}}
    with pytest.raises(ValueError, match="does not fit"):
        train(scenario="formation_keeping", algo="ppo", action_mode="setpoints", seed=0, steps=64,
              out_dir=tmp_path / "b", overrides=wide, progress_bar=False, log=lambda m: None)


def test_a_linear_learning_rate_decays_to_zero_and_the_zip_loads_alone(tmp_path, tiny):
    """``learning_rate: lin_<initial>`` (the RL Zoo's form): the Adam step size falls linearly from the initial
    value toward 0 over the run, the saved config keeps the string, and the zip loads with SB3 alone."""
    from stable_baselines3 import PPO

    rates = []
    over = {**tiny("ppo"), "learning_rate": "lin_1.0e-3"}
    train(scenario="formation_keeping", algo="ppo", action_mode="setpoints", seed=1, steps=256, out_dir=tmp_path / "a",
          overrides=over, progress_bar=False, log=lambda m: None)
    assert "lin_1.0e-3" in (tmp_path / "a" / "config.yaml").read_text()
    model = PPO.load(str(tmp_path / "a" / "final_model.zip"), device="cpu")
    for remaining, want in ((1.0, 1e-3), (0.5, 5e-4), (0.0, 0.0)):
        rates.append(model.lr_schedule(remaining))
        assert rates[-1] == pytest.approx(want, abs=1e-12)
    # the optimiser holds the step size of the last update, set at the run's end (SB3 updates it before each one)
    assert model.policy.optimizer.param_groups[0]["lr"] == 0.0
