"""Training configs are validated before anything is written (issue 22, item 8): SB3's own assertions and
failures after training become one-line ValueErrors and no run directory (so no config.yaml) is left behind."""

from __future__ import annotations

import pytest

from formation_env.cli import main
from train.sb3.config import TrainConfig, load_hyperparams

CASES = [
    ("ppo", "learning_rate: fast", "learning_rate"),
    ("ppo", "learning_rate: lin_2.0", "learning_rate"),
    ("ppo", "learning_rate: lin_x", "learning_rate"),
    ("ppo", "learning_rate: exp_3.0e-4", "learning_rate"),
    ("ppo", "n_steps: -5", "n_steps"),
    ("ppo", "batch_size: 0", "batch_size"),
    ("ppo", "batch_size: 1", "batch_size"),
    ("ppo", "policy_kwargs: {net_arch: [-4]}", "net_arch"),
    ("ppo", "policy_kwargs: {net_arch: {pi: [64], vf: [0]}}", "net_arch.vf"),
    ("ppo", "policy_kwargs: {activation_fn: sigmoid}", "activation_fn"),
    ("ppo", "policy_kwargs: {log_std_init: .nan}", "log_std_init"),
    ("ppo", "gamma: 5", "gamma"),
    ("ppo", "gae_lambda: -1", "gae_lambda"),
    ("ppo", "clip_range: -0.2", "clip_range"),
    ("ppo", "n_epochs: 2.5", "n_epochs"),
    ("ppo", "normalize_advantage: maybe", "normalize_advantage"),
    ("ppo", "policy: CnnPolicy", "policy"),
    ("ppo", "n_formations: 100000000", "n_formations"),
    ("ppo", "env_kwargs: {randomisation: 5}", "randomisation"),
    ("ppo", "env_kwargs: {randomisation: {turbulence_sigma_mps: 1.0e6}}", "turbulence_sigma_mps"),
    ("ppo", "env_kwargs: {compute_benefit: 'no'}", "compute_benefit"),
    ("ppo", "selection_collision_cost: -1", "selection_collision_cost"),
    ("ppo", "selection_collision_cost: .inf", "selection_collision_cost"),
    ("ppo", "selection_collision_cost: true", "selection_collision_cost"),
    ("sac", "ent_coef: lots", "ent_coef"),
    ("sac", "tau: 0", "tau"),
    ("sac", "buffer_size: 0", "buffer_size"),
    ("td3", "train_freq: 0", "train_freq"),
    ("td3", "gradient_steps: 0", "gradient_steps"),
    ("td3", "action_noise: -1", "action_noise"),
]


@pytest.mark.parametrize("algo, text, name", CASES, ids=[f"{a}:{t}" for a, t, _ in CASES])
def test_bad_config_is_one_line_exit_2_and_writes_nothing(algo, text, name, tmp_path, capsys):
    cfg = tmp_path / "bad.yml"
    cfg.write_text(text + "\n")
    out = tmp_path / "run"
    code = main(["train", "--scenario", "formation_keeping", "--algo", algo, "--steps", "64", "--config", str(cfg),
                 "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err and name in err, err
    assert not out.exists()


def test_absurd_step_counts_are_refused_before_the_run_directory(tmp_path, capsys):
    from train.sb3.train import train

    with pytest.raises(ValueError, match="n_timesteps"):
        train(scenario="formation_keeping", algo="ppo", steps=99999999999999999999999, out_dir=tmp_path / "a")
    assert not (tmp_path / "a").exists()
    cfg = tmp_path / "big.yml"
    cfg.write_text("n_timesteps: 99999999999999999999999\n")  # in a config file (no --steps)
    code = main(["train", "--scenario", "formation_keeping", "--algo", "ppo", "--config", str(cfg),
                 "--out", str(tmp_path / "b")])
    assert code == 2 and "n_timesteps" in capsys.readouterr().err and not (tmp_path / "b").exists()
    from formation_env.cli._args import MAX_TRAIN_STEPS
    from train.sb3.config import MAX_TIMESTEPS

    assert MAX_TIMESTEPS == MAX_TRAIN_STEPS


def test_good_values_and_the_special_forms_pass():
    base = load_hyperparams("sac", "formation_keeping")
    for extra in ({"ent_coef": "auto"}, {"ent_coef": "auto_0.1"}, {"ent_coef": 0.05}, {"target_entropy": "auto"},
                  {"gradient_steps": -1}, {"policy_kwargs": {"net_arch": {"pi": [32], "qf": [64, 64]}}}):
        p = {**base, **extra}
        TrainConfig.from_hyperparams(p, scenario="formation_keeping", algo="sac", action_mode="setpoints", seed=0)
    p = {**load_hyperparams("ppo", "formation_keeping"), "clip_range_vf": None, "target_kl": 0.02, "n_epochs": 4.0}
    cfg = TrainConfig.from_hyperparams(p, scenario="formation_keeping", algo="ppo", action_mode="setpoints", seed=0)
    assert cfg.algo_kwargs["n_epochs"] == 4 and isinstance(cfg.algo_kwargs["n_epochs"], int)


def test_a_saved_config_round_trips():
    p = load_hyperparams("td3", "reconfiguration")
    cfg = TrainConfig.from_hyperparams(p, scenario="reconfiguration", algo="td3", action_mode="residual", seed=1)
    assert TrainConfig.from_dict(cfg.to_dict()) == cfg
