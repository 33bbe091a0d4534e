"""Resume from a checkpoint, and determinism of a re-run with the same seed."""

import csv

import numpy as np
import pytest

from train.sb3.run_files import latest_checkpoint
from train.sb3.train import train

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")


def _params(path):
    from stable_baselines3 import PPO

    return {k: v.detach().numpy().copy() for k, v in PPO.load(str(path), device="cpu").policy.state_dict().items()}


def _curve(path):
    with open(path) as fh:
        return list(csv.reader(fh))


def test_train_same_seed_same_curve_and_parameters(tmp_path, tiny):
    runs = []
    for name in ("a", "b"):
        train(scenario="formation_keeping", algo="ppo", seed=7, steps=256, out_dir=tmp_path / name, overrides=tiny("ppo"),
              progress_bar=False, log=lambda m: None)
        runs.append(tmp_path / name)
    assert _curve(runs[0] / "curve.csv") == _curve(runs[1] / "curve.csv")
    pa, pb = _params(runs[0] / "final_model.zip"), _params(runs[1] / "final_model.zip")
    assert all(np.array_equal(pa[k], pb[k]) for k in pa)
    (ea, eb) = ((r / "evaluations.json").read_text() for r in runs)
    assert ea == eb
    # a different seed gives a different run
    train(scenario="formation_keeping", algo="ppo", seed=8, steps=256, out_dir=tmp_path / "c", overrides=tiny("ppo"),
          progress_bar=False, log=lambda m: None)
    pc = _params(tmp_path / "c" / "final_model.zip")
    assert not all(np.array_equal(pa[k], pc[k]) for k in pa)


@pytest.mark.parametrize("algo", ["ppo", "sac"])
def test_train_resume_from_checkpoint(tmp_path, tiny, algo):
    out = tmp_path / "run"
    train(scenario="formation_keeping", algo=algo, seed=1, steps=256, out_dir=out, overrides=tiny(algo),
          progress_bar=False, log=lambda m: None)
    ck, steps = latest_checkpoint(out)
    assert steps == 256
    # nothing to do at the same total
    with pytest.raises(ValueError, match="already at 256"):
        train(out_dir=out, resume=True, progress_bar=False, log=lambda m: None)
    s = train(out_dir=out, resume=True, steps=384, progress_bar=False, log=lambda m: None)
    assert s["num_timesteps"] == 384 and s["resumed_from"] == 256
    assert latest_checkpoint(out)[1] == 384
    assert (out / "summary-resume-256.json").is_file() and (out / "summary.json").is_file()
    rows = _curve(out / "curve.csv")[1:]
    steps_col = [int(r[0]) for r in rows]
    assert steps_col == sorted(steps_col) and steps_col[-1] > 256
    if algo == "sac":
        assert (out / "checkpoints" / "replay_buffer.pkl").is_file()
    # resuming is deterministic: the same checkpoint resumed twice gives the same model
    import shutil

    for name in ("x", "y"):
        d = tmp_path / name
        shutil.copytree(out, d)
        for p in (d / "checkpoints").glob("model_384_steps.zip"):
            p.unlink()
        train(out_dir=d, resume=True, steps=384, progress_bar=False, log=lambda m: None)
    from stable_baselines3 import PPO, SAC

    cls = PPO if algo == "ppo" else SAC
    px = cls.load(str(tmp_path / "x" / "final_model.zip"), device="cpu").policy.state_dict()
    py = cls.load(str(tmp_path / "y" / "final_model.zip"), device="cpu").policy.state_dict()
    assert all(np.array_equal(px[k].numpy(), py[k].numpy()) for k in px)


def test_train_resume_errors(tmp_path):
    with pytest.raises(ValueError, match="needs --out"):
        train(resume=True, log=lambda m: None)
    with pytest.raises(ValueError, match="no config.yaml"):
        train(out_dir=tmp_path, resume=True, log=lambda m: None)
