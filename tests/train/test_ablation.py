"""Observation ablation (train.evaluation.ablation): the ablated copy sees exactly the named groups zeroed,
everything else as the policy would; bad group names are one clear error."""

from __future__ import annotations

import numpy as np
import pytest

from formation_env.envs.observations import group_sizes, observation_size, to_dict
from formation_env.sim.layout import ObservationLayout
from train.evaluation.ablation import ablated, parse_ablation
from train.evaluation.policy import EvalPolicy


def test_ablated_copy_zeroes_only_the_named_groups():
    seen = []

    def act(obs):
        seen.append(obs.copy())
        return np.zeros((obs.shape[0], 4))

    pol = EvalPolicy("p", "setpoints", act)
    copy = ablated(pol, "induced_wind,ambient_wind", ObservationLayout.of(2))
    assert copy.name == "p-without-induced_wind+ambient_wind" and copy.action_mode == "setpoints"
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(5, observation_size(2))).astype(np.float32)
    copy.act(obs)
    got, ref = to_dict(seen[0], 2), to_dict(obs, 2)
    for name in group_sizes(2):
        if name in ("induced_wind", "ambient_wind"):
            assert np.all(got[name] == 0.0)
        else:
            np.testing.assert_array_equal(got[name], ref[name])
    assert np.any(obs != 0.0)  # the caller's array is not modified
    with pytest.raises(ValueError, match="observation length"):
        copy.act(obs[:, :-1])
    # a group the observation lacks (an option the policy was not trained with) is refused, not silently kept
    with pytest.raises(ValueError, match=r"\['neighbour_wind'\] are not in the observation"):
        ablated(pol, "neighbour_wind", ObservationLayout.of(2))


@pytest.mark.parametrize("spec, match", [("wind", "unknown observation group.*'wind'.*allowed"),
                                         ("induced_wind,,engine", "separated by commas"),
                                         ("engine,engine", "named twice")])
def test_bad_ablations_are_refused(spec, match):
    with pytest.raises(ValueError, match=match):
        parse_ablation(spec)


def test_cli_refuses_a_bad_group_with_exit_status_2(capsys):
    from formation_env.cli import main

    assert main(["evaluate", "--scenario", "close_formation", "--policy", "pid", "--ablate", "nope"]) == 2
    assert "unknown observation group" in capsys.readouterr().err


def test_evaluate_flies_each_ablation_on_the_same_episodes():
    from pathlib import Path

    from train.evaluation.evaluate import evaluate

    zip_path = Path(__file__).resolve().parents[2] / "train" / "policies" / "close_formation_ppo_setpoints_seed0.zip"
    rep = evaluate([str(zip_path), "pid"], scenario="close_formation", episodes=2, duration_s=2.0, plots=False,
                   ablations=["induced_wind,induced_rotation"], n_boot=100)
    names = set(rep["policies"])
    assert {"close_formation_ppo_setpoints_seed0", "close_formation_ppo_setpoints_seed0-without-induced_wind+induced_rotation",
            "pid"} == names
    a, b = (rep["policies"][n]["episodes"] for n in sorted(names - {"pid"}))
    assert [e["seed"] for e in a] == [e["seed"] for e in b]
