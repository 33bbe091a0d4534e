"""Bad arguments give clear errors; existing output is never silently overwritten."""

import pytest

from formation_env.cli import main
from train.sb3.config import TrainConfig, load_hyperparams
from train.evaluation.evaluate import evaluate, load_policy
from train.sb3.train import train


def _err(capsys, argv):
    code = main(argv)
    return code, capsys.readouterr().err


def test_train_cli_unknown_algo_and_mode(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["train", "--scenario", "formation_keeping", "--algo", "dqn"])
    assert exc.value.code == 2
    assert "invalid choice: 'dqn'" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["train", "--scenario", "formation_keeping", "--algo", "ppo", "--action-mode", "thrust"])
    assert "--action-mode" in capsys.readouterr().err


def test_train_cli_negative_steps(capsys):
    with pytest.raises(SystemExit):
        main(["train", "--scenario", "formation_keeping", "--algo", "ppo", "--steps", "-5"])
    assert "--steps: must be an integer in [1, 1000000000], got '-5'" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["train", "--scenario", "formation_keeping", "--algo", "ppo", "--seed", "-1"])


def test_train_cli_unknown_scenario(capsys, tmp_path):
    code, err = _err(capsys, ["train", "--scenario", "airshow", "--algo", "ppo", "--out", str(tmp_path / "x")])
    assert code == 2 and "unknown scenario 'airshow'" in err
    assert not (tmp_path / "x").exists()


def test_train_api_errors(tmp_path):
    with pytest.raises(ValueError, match="unknown algo 'a2c'"):
        load_hyperparams("a2c", "formation_keeping")
    with pytest.raises(ValueError, match="steps must be a positive integer"):
        train(scenario="formation_keeping", algo="ppo", steps=-10, out_dir=tmp_path / "a")
    with pytest.raises(ValueError, match="unknown action mode 'thrust'"):
        TrainConfig(scenario="formation_keeping", algo="ppo", action_mode="thrust", seed=0, n_timesteps=10)
    with pytest.raises(ValueError, match="unknown ppo hyperparameter"):
        train(scenario="formation_keeping", algo="ppo", steps=10, out_dir=tmp_path / "b", overrides={"n_stepz": 3})
    with pytest.raises(ValueError, match="Randomisation"):
        train(scenario="formation_keeping", algo="ppo", steps=10, out_dir=tmp_path / "c",
              overrides={"env_kwargs": {"randomisation": {"turbulence_sigma_mps": -1}}})
    with pytest.raises(ValueError, match="reward_scale must be"):
        train(scenario="formation_keeping", algo="ppo", steps=10, out_dir=tmp_path / "e", overrides={"reward_scale": 0})
    with pytest.raises(ValueError, match="does not exist"):
        train(scenario="formation_keeping", algo="ppo", steps=10, config_file=tmp_path / "nope.yml", out_dir=tmp_path / "d")


def test_train_refuses_existing_output(tmp_path, capsys):
    out = tmp_path / "run"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    code, err = _err(capsys, ["train", "--scenario", "formation_keeping", "--algo", "ppo", "--steps", "10",
                              "--out", str(out)])
    assert code == 2 and "not empty" in err and "--overwrite" in err
    assert [p.name for p in out.iterdir()] == ["keep.txt"]
    code, err = _err(capsys, ["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--out", str(out)])
    assert code == 2 and "not empty" in err
    assert [p.name for p in out.iterdir()] == ["keep.txt"]


def test_evaluate_errors(tmp_path, capsys):
    code, err = _err(capsys, ["evaluate", "--policy", str(tmp_path / "missing.zip"), "--scenario", "formation_keeping",
                              "--out", str(tmp_path / "e")])
    assert code == 2 and "missing.zip" in err and "does not exist" in err
    assert not (tmp_path / "e").exists()
    with pytest.raises(ValueError, match="unknown scenario"):
        evaluate(["pid"], scenario="airshow")
    with pytest.raises(ValueError, match="episodes must be"):
        evaluate(["pid"], scenario="formation_keeping", episodes=0)
    bogus = tmp_path / "bogus.zip"
    bogus.write_text("not a zip")
    with pytest.raises(ValueError, match="bogus.zip' is not a readable policy"):  # before its action mode is asked
        load_policy(str(bogus))
    with pytest.raises(ValueError, match="is not a readable policy"):
        load_policy(str(bogus), action_mode="residual")
    with pytest.raises(SystemExit):
        main(["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--turbulence", "-1"])
