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
