"""The neighbours' winds as an observation option (EnvConfig.neighbour_wind) through training, publication and
evaluation: a run trained with it records it, its published sidecar carries it, load_policy and evaluate fly the
policy with it (the observation it was trained on), ablation knows the group, and a bad value is refused."""

import json

import numpy as np
import pytest

from formation_env.envs.observations import observation_size
from train.evaluation.ablation import ablated
from train.evaluation.evaluate import evaluate
from train.evaluation.policy_loader import load_policy
from train.publish import publish as publish_mod
from train.sb3.config import TrainConfig
from train.sb3.train import train


def test_config_refuses_a_bad_value():
    with pytest.raises(ValueError, match=r"neighbour_wind must be True or False, got 'yes'"):
        TrainConfig(scenario="echelon3", algo="ppo", action_mode="setpoints", seed=0, n_timesteps=10,
                    env_kwargs={"neighbour_wind": "yes"})


def test_a_run_with_neighbour_winds_is_flown_with_them(tmp_path, tiny, monkeypatch):
    over = tiny("ppo")
    over["env_kwargs"]["neighbour_wind"] = True
    out = tmp_path / "r"
    train(scenario="echelon3", algo="ppo", action_mode="setpoints", seed=0, steps=128, out_dir=out, overrides=over,
          progress_bar=False, log=lambda m: None)
    meta = json.loads((out / "best_model.json").read_text())
    assert meta["neighbour_wind"] is True
    pub = tmp_path / "pub"
    pub.mkdir()
    monkeypatch.setattr(publish_mod, "POLICIES", pub)
    publish_mod.publish(out, "p")
    side = json.loads((pub / "p.json").read_text())
    assert side["env"]["neighbour_wind"] is True
    pol = load_policy(str(pub / "p.zip"))
    assert pol.neighbour_wind
    # evaluate flies it with the observation it was trained on (3 UAVs, 2 neighbours, their winds: 6 more values;
    # with the plain one the network would be fed 59 values for its 65 and fail)
    res = evaluate([str(pub / "p.zip")], scenario="echelon3", episodes=1, duration_s=2.0, plots=False, n_boot=10,
                   ablations=["neighbour_wind"])
    assert set(res["policies"]) == {"p", "p-without-neighbour_wind"}
    # the ablated copy masks exactly the new group of the longer observation and refuses the shorter one
    hid = ablated(pol, ["neighbour_wind"], 3, 2, True)
    obs = np.ones((2, observation_size(3, 2, True)), np.float32)
    assert hid.act(obs).shape == (2, 4)
    with pytest.raises(ValueError, match="observation length 59, expected 65"):
        hid.act(np.ones((2, observation_size(3, 2)), np.float32))
