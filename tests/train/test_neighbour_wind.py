"""The neighbours' winds (EnvConfig.neighbour_wind), and alike every optional observation group (its switch in
formation_env.sim.layout.OPTIONS: the neighbours' attitudes, ...), as observation options through training,
publication and evaluation: a run trained with one records its layout, its published sidecar carries it, load_policy
and evaluate fly the policy with it (the observation it was trained on), ablation knows the group, and a bad value is
refused."""

import json

import numpy as np
import pytest

from formation_env.envs.observations import observation_size
from formation_env.sim.layout import OPTIONS, ObservationLayout
from train.evaluation.ablation import ablated
from train.evaluation.evaluate import evaluate
from train.evaluation.policy_loader import load_policy
from train.publish import publish as publish_mod
from train.sb3.config import TrainConfig
from train.sb3.train import train


@pytest.mark.parametrize("key", OPTIONS)
def test_config_refuses_a_bad_value(key):
    with pytest.raises(ValueError, match=rf"{key} must be True or False, got 'yes'"):
        TrainConfig(scenario="echelon3", algo="ppo", action_mode="setpoints", seed=0, n_timesteps=10,
                    env_kwargs={key: "yes"})


@pytest.mark.parametrize("key", OPTIONS)
def test_a_run_with_a_neighbour_group_is_flown_with_it(tmp_path, tiny, monkeypatch, key):
    over = tiny("ppo")
    over["env_kwargs"][key] = True
    over["action_guard"] = True  # the guard in the loop, in validation and in the published policy: told the layout
    out = tmp_path / "r"
    train(scenario="echelon3", algo="ppo", action_mode="setpoints", seed=0, steps=128, out_dir=out, overrides=over,
          progress_bar=False, log=lambda m: None)
    meta = json.loads((out / "best_model.json").read_text())
    trained, plain = ObservationLayout.of(3, 2, **{key: True}), ObservationLayout.of(3, 2)  # echelon3: each sees 2
    (group,) = trained.optional
    assert meta["observation"] == trained.to_dict() and meta["action_guard"] is True
    assert dict(meta["observation"]["groups"]).keys() == plain.groups.keys() | {group}
    pub = tmp_path / "pub"
    pub.mkdir()
    monkeypatch.setattr(publish_mod, "POLICIES", pub)
    publish_mod.publish(out, "p")
    side = json.loads((pub / "p.json").read_text())
    assert side["env"]["observation"] == trained.to_dict()
    pol = load_policy(str(pub / "p.zip"))
    assert pol.observation == trained and pol.observation.options == {key: True}
    # evaluate flies it with the observation it was trained on (with the plain one the network would be fed 59
    # values for its longer input and fail)
    res = evaluate([str(pub / "p.zip")], scenario="echelon3", episodes=1, duration_s=2.0, plots=False, n_boot=10,
                   ablations=[group])
    assert set(res["policies"]) == {"p", f"p-without-{group}"}
    # the ablated copy masks exactly the new group of the longer observation and refuses the shorter one
    hid = ablated(pol, [group], trained)
    obs = np.ones((2, observation_size(3, 2, **{key: True})), np.float32)
    assert hid.act(obs).shape == (2, 4) and trained.size > plain.size == 59
    with pytest.raises(ValueError, match=f"observation length 59, expected {trained.size}"):
        hid.act(np.ones((2, observation_size(3, 2)), np.float32))


def _paired_observations(n_steps=12):
    """The same echelon3 flight observed without and with the neighbours' winds (sigma 1, followers pushed about)."""
    import formation_env
    from formation_env.sim.config import Randomisation

    envs = [formation_env.parallel_env("echelon3", action_mode="setpoints", neighbour_wind=w,
                                       randomisation=Randomisation(turbulence_sigma_mps=1.0, initial_offset_m=4.0))
            for w in (False, True)]
    for env in envs:
        env.reset(seed=7)
    rng = np.random.default_rng(3)
    pairs = []
    for _ in range(n_steps):
        act = {a: rng.uniform(-1, 1, 4) for a in envs[0].agents}
        (o0, *_), (o1, *_) = (env.step(act) for env in envs)
        pairs.append((np.stack([o0[a] for a in sorted(o0)]), np.stack([o1[a] for a in sorted(o1)])))
    return pairs


def test_the_classical_agents_read_the_longer_observation_when_told():
    """Told the layout, the guard, the station keeper and the formation PID act on the observation with the
    neighbours' winds exactly as on the one without; its length alone (65 = 47 + 6 x 3) would read as a third
    neighbour, so they must be told."""
    from agents.common import observation_groups
    from agents.pid_formation import PIDFormation
    from agents.separation_guard import GuardGains, SeparationGuard
    from agents.station_keeper import StationKeeper

    pairs = _paired_observations()
    told = ObservationLayout(optional=("neighbour_wind",))  # any formation: the length gives the neighbours
    plain, winds = SeparationGuard(GuardGains(guard_m=30.0)), SeparationGuard(GuardGains(guard_m=30.0), layout=told)
    keepers = StationKeeper(), StationKeeper(layout=told)
    pids = PIDFormation(), PIDFormation(layout=told)
    for agent in keepers + pids:
        agent.reset(3)  # the env flies every UAV: three rows
    rng = np.random.default_rng(0)
    shifted = 0
    for o0, o1 in pairs:
        assert o1.shape[1] == o0.shape[1] + 6
        a = rng.uniform(-1, 1, (o0.shape[0], 4))
        g0 = plain.filter(o0, a)
        np.testing.assert_array_equal(winds.filter(o1, a), g0)
        shifted += int(np.any(g0 != a))
        np.testing.assert_array_equal(keepers[1].act(o1), keepers[0].act(o0))
        np.testing.assert_array_equal(pids[1].act(o1), pids[0].act(o0))
    assert shifted > 0  # the guard (a wide zone here) acted on some rows: the neighbours were read alike
    _, wrong = observation_groups(pairs[0][1], "test")
    assert wrong["neighbours"].shape[1] == 18  # untold: three neighbours, the third made of the winds
    with pytest.raises(ValueError, match=r"test.act: observation length 59 is not that of an observation with "
                                         r"neighbour_wind \(47 \+ 9 k, k >= 1\)"):
        observation_groups(pairs[0][0], "test", told)
