"""The neighbours' attitude as an observation option (EnvConfig.neighbour_attitude) through training, publication and
evaluation, and the classical agents told the layout (as the neighbours' winds, tests/train/test_neighbour_wind.py)."""

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
    with pytest.raises(ValueError, match=r"neighbour_attitude must be True or False, got 'yes'"):
        TrainConfig(scenario="echelon3", algo="ppo", action_mode="setpoints", seed=0, n_timesteps=10,
                    env_kwargs={"neighbour_attitude": "yes"})


def test_a_run_with_neighbour_attitudes_is_flown_with_them(tmp_path, tiny, monkeypatch):
    over = tiny("ppo")
    over["env_kwargs"]["neighbour_attitude"] = True
    over["action_guard"] = True  # the guard in the loop, in validation and in the published policy: told the layout
    out = tmp_path / "r"
    train(scenario="echelon3", algo="ppo", action_mode="setpoints", seed=0, steps=128, out_dir=out, overrides=over,
          progress_bar=False, log=lambda m: None)
    meta = json.loads((out / "best_model.json").read_text())
    assert meta["neighbour_attitude"] is True and meta["action_guard"] is True and "neighbour_wind" not in meta
    pub = tmp_path / "pub"
    pub.mkdir()
    monkeypatch.setattr(publish_mod, "POLICIES", pub)
    publish_mod.publish(out, "p")
    side = json.loads((pub / "p.json").read_text())
    assert side["env"]["neighbour_attitude"] is True
    pol = load_policy(str(pub / "p.zip"))
    assert pol.neighbour_attitude and not pol.neighbour_wind
    res = evaluate([str(pub / "p.zip")], scenario="echelon3", episodes=1, duration_s=2.0, plots=False, n_boot=10,
                   ablations=["neighbour_attitude"])
    assert set(res["policies"]) == {"p", "p-without-neighbour_attitude"}
    hid = ablated(pol, ["neighbour_attitude"], 3, 2, False, True)
    assert hid.act(np.ones((2, observation_size(3, 2, False, True)), np.float32)).shape == (2, 4)
    with pytest.raises(ValueError, match="observation length 59, expected 65"):
        hid.act(np.ones((2, observation_size(3, 2)), np.float32))


def test_the_classical_agents_read_the_attitudes_when_told():
    """Told the layout, the guard, the station keeper and the formation PID act on the observation with the
    neighbours' attitudes (and with winds and attitudes) exactly as on the plain one."""
    import formation_env
    from agents.common import observation_groups
    from agents.pid_formation import PIDFormation
    from agents.separation_guard import GuardGains, SeparationGuard
    from agents.station_keeper import StationKeeper
    from formation_env.envs.config import Randomisation

    layouts = [(False, False), (False, True), (True, True)]
    envs = [formation_env.parallel_env("echelon3", action_mode="setpoints", neighbour_wind=w, neighbour_attitude=t,
                                       randomisation=Randomisation(turbulence_sigma_mps=1.0, initial_offset_m=4.0))
            for w, t in layouts]
    for env in envs:
        env.reset(seed=7)
    guards = [SeparationGuard(GuardGains(guard_m=30.0), neighbour_wind=w, neighbour_attitude=t) for w, t in layouts]
    keepers = [StationKeeper(neighbour_wind=w, neighbour_attitude=t) for w, t in layouts]
    pids = [PIDFormation(neighbour_wind=w, neighbour_attitude=t) for w, t in layouts]
    for agent in keepers + pids:
        agent.reset(3)
    rng = np.random.default_rng(3)
    shifted = 0
    for _ in range(12):
        act = {a: rng.uniform(-1, 1, 4) for a in envs[0].agents}
        obs = [np.stack([o[a] for a in sorted(o)]) for o, *_ in (env.step(act) for env in envs)]
        assert [o.shape[1] for o in obs] == [59, 65, 71]
        a = rng.uniform(-1, 1, (3, 4))
        g0 = guards[0].filter(obs[0], a)
        shifted += int(np.any(g0 != a))
        for i in (1, 2):
            np.testing.assert_array_equal(guards[i].filter(obs[i], a), g0)
        k0, p0 = keepers[0].act(obs[0]), pids[0].act(obs[0])
        for i in (1, 2):
            np.testing.assert_array_equal(keepers[i].act(obs[i]), k0)
            np.testing.assert_array_equal(pids[i].act(obs[i]), p0)
    assert shifted > 0
    with pytest.raises(ValueError, match=r"test.act: observation length 65 is not that of an observation with "
                                         r"neighbours' winds and attitudes \(47 \+ 12 k, k >= 1\)"):
        observation_groups(obs[1], "test", neighbour_wind=True, neighbour_attitude=True)
