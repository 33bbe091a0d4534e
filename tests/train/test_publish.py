"""Publishing: the held-out evaluation attached to a committed policy's metadata, without the series."""

import json

import pytest

from formation_env.cli import main as cli_main
from train.publish import publish


def test_attach_evaluation_writes_a_slim_record_and_updates_the_metadata(tmp_path, monkeypatch):
    monkeypatch.setattr(publish, "POLICIES", tmp_path)
    (tmp_path / "p_seed0.json").write_text(json.dumps({"seed": 0, "evaluation": None}))
    ep = {"seed": 20000000000, "rms_slot_error_m": 1.5, "series": {"t": [0.1], "slot_error_m": [1.0]},
          "saving_series": [0.3]}
    rep = {"scenario": "formation_keeping", "seeds": [20000000000, 20000000001], "wake": True,
           "turbulence_sigma_mps": 1.0, "out_dir": "x", "plots": ["a.png"],
           "policies": {"p_seed0": {"summary": {"rms_slot_error_m": 1.5}, "episodes": [ep, ep]},
                        "pid": {"summary": {"rms_slot_error_m": 9.0}, "episodes": [ep, ep]}},
           "comparisons": {"p_seed0": {"pid": {"rms_slot_error_m": {"mean_reduction": 7.5}}}}}
    src = tmp_path / "results.json"
    src.write_text(json.dumps(rep))
    publish.attach_evaluation(["p_seed0"], src, tmp_path / "record.json")
    rec = json.loads((tmp_path / "record.json").read_text())
    assert not {"series", "saving_series"} & set(rec["policies"]["pid"]["episodes"][0]) and "out_dir" not in rec
    assert rec["policies"]["p_seed0"]["episodes"][1]["rms_slot_error_m"] == 1.5
    meta = json.loads((tmp_path / "p_seed0.json").read_text())
    assert meta["seed"] == 0 and meta["evaluation"]["episodes"] == 2
    assert meta["evaluation"]["comparisons"]["pid"]["rms_slot_error_m"]["mean_reduction"] == 7.5
    with pytest.raises(FileExistsError):  # the record is never silently overwritten
        publish.attach_evaluation(["p_seed0"], src, tmp_path / "record.json")


def _fake_evaluate(calls):
    """train.evaluation.evaluate.evaluate without flying: a report of the right shape (and its files)."""
    from pathlib import Path

    def evaluate(policies, *, scenario, episodes, out_dir=None, overwrite=False, seeds=None, plots=True, log=None):
        calls.append(scenario)
        names = [Path(p).stem if p.endswith(".zip") else p for p in policies]
        ep = {"seed": 20000000000, "rms_slot_error_m": 1.0, "series": {"slot_error_m": [1.0]}}
        rep = {"scenario": scenario, "seeds": [20000000000], "wake": True, "turbulence_sigma_mps": 1.0,
               "policies": {n: {"summary": {"rms_slot_error_m": 1.0 + i}, "episodes": [ep]} for i, n in enumerate(names)},
               "comparisons": {}, "table_markdown": "| table |", "comparison_markdown": "", "groups_markdown": ""}
        if out_dir is not None:
            out = Path(out_dir)
            out.mkdir(parents=True, exist_ok=overwrite)
            (out / "results.json").write_text(json.dumps(rep))
            (out / "results.md").write_text("# results\n")
            (out / "slot_error.png").write_bytes(b"\x89PNG fake")
        return rep

    return evaluate


def _tracked_state():
    from train.publish.report_committed import FIGURES

    files = sorted(publish.POLICIES.glob("*.json")) + sorted(FIGURES.glob("*.png"))
    return {str(f): f.stat().st_mtime_ns for f in files}


def test_report_committed_out_writes_only_under_out(tmp_path, monkeypatch, capsys):
    from train.publish import report_committed as rc

    calls = []
    monkeypatch.setattr(rc, "evaluate", _fake_evaluate(calls))
    before = _tracked_state()
    out = tmp_path / "eval"
    assert cli_main(["publish", "committed", "--out", str(out), "--episodes", "2", "--tasks", "formation_keeping"]) == 0
    # the test set, then the validation baselines (of every task, in the registry's order: the curves figure shows
    # them all)
    assert rc.TASKS == ("formation_keeping", "reconfiguration", "close_formation")
    assert calls == ["formation_keeping", "formation_keeping", "reconfiguration", "close_formation"]
    assert _tracked_state() == before  # nothing tracked is touched
    for f in ("formation_keeping/results.json", "policies/formation_keeping_ppo_setpoints_evaluation.json",
              "policies/formation_keeping_ppo_setpoints_seed2.json", "figures/eval_formation_keeping_slot_error.png",
              "figures/training_curves.png", "validation_baselines.json"):
        assert (out / f).is_file(), f
    meta = json.loads((out / "policies" / "formation_keeping_ppo_setpoints_seed0.json").read_text())
    assert meta["env"]["scenario"] == "formation_keeping" and meta["evaluation"]["summary"]["rms_slot_error_m"] == 1.0
    # Again into the same directory: refused up front, before any evaluation, in one line.
    calls.clear()
    capsys.readouterr()
    assert cli_main(["publish", "committed", "--out", str(out), "--tasks", "formation_keeping"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert calls == [] and len(err) == 1 and "not empty" in err[0]


def test_report_committed_checks_every_output_before_evaluating(tmp_path, monkeypatch, capsys):
    import shutil

    from train.publish import report_committed as rc

    calls = []
    monkeypatch.setattr(rc, "evaluate", _fake_evaluate(calls))
    pol, fig = tmp_path / "policies", tmp_path / "figures"
    shutil.copytree(publish.POLICIES, pol, ignore=shutil.ignore_patterns("*.zip", "*.csv"))
    for z in publish.POLICIES.glob("formation_keeping_*.zip"):
        (pol / z.name).write_bytes(b"zip")
    fig.write_text("a file where the figures directory should be\n")
    monkeypatch.setattr(publish, "POLICIES", pol)
    monkeypatch.setattr(rc, "FIGURES", fig)
    argv = ["publish", "committed", "--out", str(tmp_path / "eval"), "--overwrite", "--tasks", "formation_keeping"]
    assert cli_main(argv) == 2 and calls == []  # a tracked output that cannot be written: nothing flies
    assert "figures" in capsys.readouterr().err
    fig.unlink()
    fig.mkdir()
    old = (pol / "formation_keeping_ppo_setpoints_evaluation.json").read_text()
    assert cli_main(argv) == 0 and len(calls) == 4  # --overwrite: the tracked records are replaced
    assert (pol / "formation_keeping_ppo_setpoints_evaluation.json").read_text() != old
    assert (fig / "eval_formation_keeping_slot_error.png").read_bytes() == b"\x89PNG fake"
    assert not (tmp_path / "eval" / "policies").exists()


def test_publish_best_or_final_model(tmp_path, monkeypatch):
    """``model="best"`` copies the validation's choice with its validation; ``"final"`` the last model with the
    last validation (a run none of whose validations was collision-free); anything else is refused."""
    import yaml

    out = tmp_path / "policies"
    out.mkdir()
    monkeypatch.setattr(publish, "POLICIES", out)
    run = tmp_path / "run"
    run.mkdir()
    (run / "config.yaml").write_text(yaml.safe_dump({"command": "cmd", "config": {"seed": 3}}))
    env = {"algo": "ppo", "scenario": "vee5", "action_mode": "setpoints", "control_hz": 10.0}
    stamp = {"task": "vee5", "task_version": 1, "departures": {}}  # what the trainer stamps (train.config.task_stamp)
    (run / "best_model.json").write_text(json.dumps({**env, **stamp, "num_timesteps": 100,
                                                     "validation": {"score": -0.5}}))
    (run / "final_model.json").write_text(json.dumps({**env, "num_timesteps": 200}))
    (run / "evaluations.json").write_text(json.dumps([{"num_timesteps": 100, "score": -0.5},
                                                      {"num_timesteps": 200, "score": float("inf")}]))
    for name, body in (("best_model.zip", b"best"), ("final_model.zip", b"final"), ("curve.csv", b"s\n")):
        (run / name).write_bytes(body)
    publish.publish(run, "a_seed3")
    assert (out / "a_seed3.zip").read_bytes() == b"best"
    assert json.loads((out / "a_seed3.json").read_text())["num_timesteps"] == 100
    assert json.loads((out / "a_seed3.json").read_text())["env"] == {**env, **stamp}  # the task version carried
    publish.publish(run, "b_seed3", model="final", note="no collision-free validation")
    meta = json.loads((out / "b_seed3.json").read_text())
    assert (out / "b_seed3.zip").read_bytes() == b"final"
    assert meta["num_timesteps"] == 200 and meta["validation"]["num_timesteps"] == 200 and meta["note"]
    with pytest.raises(ValueError, match="model"):
        publish.publish(run, "c_seed3", model="last")
    # the command line: `formation-env publish run RUN_DIR NAME`; an existing NAME is refused in one line
    assert cli_main(["publish", "run", str(run), "d_seed3", "--model", "final", "--wall-s", "12.5",
                     "--stopped-at", "200"]) == 0
    meta = json.loads((out / "d_seed3.json").read_text())
    assert (out / "d_seed3.zip").read_bytes() == b"final" and meta["wall_s"] == 12.5 and meta["run_steps"] == 200
    assert cli_main(["publish", "run", str(run), "d_seed3"]) == 2


def test_publish_names_the_guard_the_policy_flies_with(tmp_path, monkeypatch):
    """``guard`` puts the separation guard's gains into the sidecar of a run trained with the guard; a run without
    the guard, an unknown gain or a bad value is refused before anything is written."""
    import yaml

    out = tmp_path / "policies"
    out.mkdir()
    monkeypatch.setattr(publish, "POLICIES", out)
    for guarded in (True, False):
        run = tmp_path / f"run{guarded}"
        run.mkdir()
        (run / "config.yaml").write_text(yaml.safe_dump({"command": "cmd", "config": {"seed": 0}}))
        env = {"algo": "ppo", "scenario": "close_formation", "action_mode": "setpoints", "control_hz": 10.0,
               **({"action_guard": True} if guarded else {})}
        (run / "best_model.json").write_text(json.dumps({**env, "num_timesteps": 100, "validation": {"score": -0.5}}))
        for name, body in (("best_model.zip", b"best"), ("curve.csv", b"s\n"), ("evaluations.json", b"[]")):
            (run / name).write_bytes(body)
    publish.publish(tmp_path / "runTrue", "g_seed0", guard={"clip_ramp": 0.25})
    assert json.loads((out / "g_seed0.json").read_text())["env"]["action_guard"] == {"clip_ramp": 0.25}
    publish.publish(tmp_path / "runTrue", "h_seed0")
    assert json.loads((out / "h_seed0.json").read_text())["env"]["action_guard"] is True
    for run, guard, match in (("runFalse", {"clip_ramp": 0.25}, "trained without the separation guard"),
                              ("runTrue", {"clip": 0.25}, "unknown separation-guard gain"),
                              ("runTrue", {"clip_ramp": 2.0}, "clip_ramp must be in")):
        with pytest.raises(ValueError, match=match):
            publish.publish(tmp_path / run, "x_seed0", guard=guard)
    assert not (out / "x_seed0.json").exists()
