"""train/evaluation/marl_eval.py: the marl-eval raw-data JSON of a small fixed evaluation, exactly, and the
structure marl-eval's data_process_pipeline / create_matrices_for_rliable read (marl-eval itself is not
installed: its sdist does not build here)."""

import json

import pytest

from train.evaluation.marl_eval import marl_eval_data, training_steps, write_marl_eval


def _eps(values, success=None):
    return [{"seed": 10 + i, "rms_slot_error_m": v, "return": -v, "collision": False,
             **({} if success is None else {"reconfig_success": success[i]})} for i, v in enumerate(values)]


EPISODES = {"PPO_seed0": _eps([1.0, 2.0]), "PPO_seed3": _eps([1.5, 2.5]), "pid": _eps([9.0, 8.0])}


def test_small_fixed_evaluation_exactly():
    data = marl_eval_data("Formation_Keeping", EPISODES, {"PPO": ["PPO_seed0", "PPO_seed3"]}, ["pid"],
                          step_counts={"PPO_seed0": 900000, "PPO_seed3": 800000})
    run = lambda v, steps: {"step_0": {"step_count": steps, "return": [-x for x in v], "rms_slot_error_m": v,  # noqa: E731
                                       "collision": [0.0, 0.0]},
                            "absolute_metrics": {"return": [-x for x in v], "rms_slot_error_m": v, "collision": [0.0, 0.0]}}
    assert data == {"formation_env": {"formation_keeping": {
        "ppo": {"seed_0": run([1.0, 2.0], 900000), "seed_3": run([1.5, 2.5], 800000)},
        # the deterministic baseline as many identical runs as the groups have (marl-eval needs equal counts)
        "pid": {"seed_0": run([9.0, 8.0], 0), "seed_1": run([9.0, 8.0], 0)}}}}
    assert json.loads(json.dumps(data)) == data  # plain JSON


def test_structure_marl_eval_reads(tmp_path):
    eps = {k: _eps([1.0, 2.0, 3.0], [True, False, True]) for k in ("a_seed0", "a_seed1", "a_seed2", "pid", "pf")}
    data = marl_eval_data("reconfiguration", eps, {"a": ["a_seed0", "a_seed1", "a_seed2"]}, ["pid", "pf"])
    algos = data["formation_env"]["reconfiguration"]
    # every algorithm the same runs, every run the same steps, an absolute_metrics entry, one list entry per
    # evaluation episode, the same metrics everywhere, lower-case names without commas
    assert {len(r) for r in algos.values()} == {3}
    metrics = None
    for name, runs in algos.items():
        assert name == name.lower() and "," not in name
        for run in runs.values():
            assert list(run) == ["step_0", "absolute_metrics"] and isinstance(run["step_0"]["step_count"], int)
            m = {k for k in run["step_0"] if k != "step_count"}
            assert m == set(run["absolute_metrics"]) and (metrics is None or m == metrics)
            metrics = m
            assert all(len(v) == 3 for v in run["absolute_metrics"].values())
    assert algos["a"]["seed_0"]["absolute_metrics"]["reconfig_success"] == [1.0, 0.0, 1.0]
    out = write_marl_eval(tmp_path / "m.json", data)
    assert json.loads(out.read_text()) == data
    with pytest.raises(FileExistsError):
        write_marl_eval(tmp_path / "m.json", data)


def test_bad_inputs():
    with pytest.raises(ValueError, match="same number of runs"):
        marl_eval_data("t", EPISODES, {"a": ["PPO_seed0", "PPO_seed3"], "b": ["pid"]}, [])
    with pytest.raises(ValueError, match="commas"):
        marl_eval_data("t", {"a,b": EPISODES["pid"]}, {}, ["a,b"])
    with pytest.raises(ValueError, match="same episodes"):
        marl_eval_data("t", {**EPISODES, "x": _eps([1.0])}, {"g": ["PPO_seed0"]}, ["x"])
    with pytest.raises(ValueError, match="finite"):
        marl_eval_data("t", {"p": _eps([float("nan"), 1.0])}, {}, ["p"])
    with pytest.raises(ValueError, match="nothing"):
        marl_eval_data("t", EPISODES, {}, [])


def test_training_steps_from_the_sidecar(tmp_path):
    (tmp_path / "p.json").write_text(json.dumps({"num_timesteps": 1234}))
    assert training_steps(str(tmp_path / "p.zip")) == 1234
    assert training_steps("pid") == 0 and training_steps(None) == 0
