"""The committed multi-level record: summaries and comparisons of every policy, per-episode columns of the
controllers only, never overwritten silently; a directory without levels.json is refused with status 2."""

import json

from formation_env.cli import main as cli_main
from train.publish import levels_record as lr


def _levels(argv: list[str]) -> int:
    """``formation-env publish levels ARGV``'s exit status."""
    return cli_main(["publish", "levels", *argv])


def _results(tmp_path):
    def ep(seed, harvest):
        return {"seed": seed, "duration_s": 60.0, "harvest_ratio": harvest, "rms_along_track_m": 1.0,
                "rms_lateral_m": 0.3, "rms_vertical_m": 0.2, "min_separation_m": 5.0, "collision": False,
                "series": {"slot_error_m": [1.0]}, "saving_series": [0.3]}

    for lv in (0.0, 1.0):
        d = tmp_path / f"sigma_{lv:g}"
        d.mkdir()
        pols = {"a_seed0": {"summary": {"harvest_ratio": 0.9 - lv / 10, "wall_s": 3.0}, "episodes": [ep(1, 0.9), ep(2, 0.8)]},
                "a_seed0-without-ambient_wind": {"summary": {"harvest_ratio": 0.5}, "episodes": [ep(1, 0.5), ep(2, 0.5)]},
                "pid": {"summary": {"harvest_ratio": 0.1}, "episodes": [ep(1, 0.1), ep(2, 0.2)]}}
        (d / "results.json").write_text(json.dumps({"scenario": "close_formation", "turbulence_sigma_mps": lv,
                                                    "seeds": [1, 2], "policies": pols,
                                                    "comparisons": {"a_seed0": {"pid": {"harvest_ratio": {"n": 2}}}}}))
    (tmp_path / "levels.json").write_text(json.dumps({"scenario": "close_formation", "levels": [0.0, 1.0]}))
    return tmp_path


def test_record_keeps_summaries_and_the_controllers_episode_columns(tmp_path):
    rec = lr.levels_record(_results(tmp_path), command="cmd")
    assert rec["levels"] == [0.0, 1.0] and rec["command"] == "cmd"
    s1 = rec["by_level"]["sigma_1"]
    assert s1["summaries"]["a_seed0"] == {"harvest_ratio": 0.8}  # wall time dropped
    assert "a_seed0-without-ambient_wind" in s1["summaries"]
    assert set(s1["episodes"]) == {"a_seed0", "pid"}  # ablated copies: summaries only
    assert s1["episodes"]["pid"]["harvest_ratio"] == [0.1, 0.2] and "series" not in s1["episodes"]["pid"]
    assert s1["comparisons"]["a_seed0"]["pid"]["harvest_ratio"]["n"] == 2


def test_cli_writes_once_and_refuses_a_bad_directory(tmp_path, capsys):
    src = _results(tmp_path / "r") if (tmp_path / "r").mkdir() is None else None
    out = tmp_path / "rec.json"
    assert _levels([str(src), str(out)]) == 0 and json.loads(out.read_text())["scenario"] == "close_formation"
    assert _levels([str(src), str(out)]) == 2 and "overwrite" in capsys.readouterr().err
    assert _levels([str(src), str(out), "--overwrite"]) == 0
    assert _levels([str(tmp_path), str(tmp_path / "x.json")]) == 2
    assert "no levels.json" in capsys.readouterr().err


def test_one_level_directory_is_recorded_as_its_level(tmp_path):
    """``formation-env evaluate --turbulence 1`` writes results.json in the directory itself: one level."""
    rec = lr.levels_record(_results(tmp_path) / "sigma_1")
    assert rec["levels"] == [1.0] and list(rec["by_level"]) == ["sigma_1"]
    assert rec["by_level"]["sigma_1"] == lr.levels_record(tmp_path)["by_level"]["sigma_1"]


def test_task_records_are_added_never_dropped(tmp_path, capsys):
    """``--task``: the N-UAV records' format, {"_about", "records": {task: [record, ...]}}; a new file needs
    --about, an existing one keeps its records (and its about unless --overwrite replaces it)."""
    src = _results(tmp_path / "r") if (tmp_path / "r").mkdir() is None else None
    out = tmp_path / "rec.json"
    assert _levels([str(src), str(out), "--task", "vee5"]) == 2 and "--about" in capsys.readouterr().err
    assert not out.exists()
    assert _levels([str(src), str(out), "--task", "vee5", "--about", "A", "--command", "c1"]) == 0
    assert _levels([str(src / "sigma_1"), str(out), "--task", "vee5", "--command", "c2"]) == 0
    assert _levels([str(src), str(out), "--task", "vee9"]) == 0
    whole = json.loads(out.read_text())
    assert whole["_about"] == "A" and list(whole["records"]) == ["vee5", "vee9"]
    assert [r["command"] for r in whole["records"]["vee5"]] == ["c1", "c2"]
    assert whole["records"]["vee5"][1] == lr.levels_record(src / "sigma_1", command="c2")
    assert _levels([str(src), str(out), "--task", "vee9", "--about", "B"]) == 2  # another about: refused
    assert "--overwrite" in capsys.readouterr().err and json.loads(out.read_text()) == whole
    assert _levels([str(src), str(out), "--task", "vee9", "--about", "B", "--overwrite"]) == 0
    again = json.loads(out.read_text())
    assert again["_about"] == "B" and len(again["records"]["vee9"]) == 2 and again["records"]["vee5"] == whole["records"]["vee5"]
    single = tmp_path / "single.json"
    assert _levels([str(src), str(single)]) == 0
    assert _levels([str(src), str(single), "--task", "vee5"]) == 2 and "not a multi-task record" in capsys.readouterr().err
    assert _levels([str(src), str(tmp_path / "x.json"), "--about", "A"]) == 2  # --about without --task
