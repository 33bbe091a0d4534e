"""Publishing: the held-out evaluation attached to a committed policy's metadata, without the series."""

import json

import pytest

from train.publish import publish


def test_attach_evaluation_writes_a_slim_record_and_updates_the_metadata(tmp_path, monkeypatch):
    monkeypatch.setattr(publish, "POLICIES", tmp_path)
    (tmp_path / "p_seed0.json").write_text(json.dumps({"seed": 0, "evaluation": None}))
    ep = {"seed": 20000000000, "rms_slot_error_m": 1.5, "series": {"t": [0.1], "slot_error_m": [1.0]}}
    rep = {"scenario": "formation_keeping", "seeds": [20000000000, 20000000001], "wake": True,
           "turbulence_sigma_mps": 1.0, "out_dir": "x", "plots": ["a.png"],
           "policies": {"p_seed0": {"summary": {"rms_slot_error_m": 1.5}, "episodes": [ep, ep]},
                        "pid": {"summary": {"rms_slot_error_m": 9.0}, "episodes": [ep, ep]}},
           "comparisons": {"p_seed0": {"pid": {"rms_slot_error_m": {"mean_reduction": 7.5}}}}}
    src = tmp_path / "results.json"
    src.write_text(json.dumps(rep))
    publish.attach_evaluation(["p_seed0"], src, tmp_path / "record.json")
    rec = json.loads((tmp_path / "record.json").read_text())
    assert "series" not in rec["policies"]["pid"]["episodes"][0] and "out_dir" not in rec
    assert rec["policies"]["p_seed0"]["episodes"][1]["rms_slot_error_m"] == 1.5
    meta = json.loads((tmp_path / "p_seed0.json").read_text())
    assert meta["seed"] == 0 and meta["evaluation"]["episodes"] == 2
    assert meta["evaluation"]["comparisons"]["pid"]["rms_slot_error_m"]["mean_reduction"] == 7.5
    with pytest.raises(FileExistsError):  # the record is never silently overwritten
        publish.attach_evaluation(["p_seed0"], src, tmp_path / "record.json")
