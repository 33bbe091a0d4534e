"""One evaluation over several turbulence levels (train.evaluation.levels; `formation-env evaluate --turbulence 0 1`)."""

from __future__ import annotations

import json

import pytest

from train.evaluation.levels import evaluate_levels, levels_table


def test_levels_share_seeds_and_the_table_lists_every_level(tmp_path):
    res = evaluate_levels(["pid"], scenario="close_formation", levels=(0.0, 1.5), episodes=2, seeds=[5],
                          compute_benefit=True, duration_s=6.0, out_dir=tmp_path / "lv", plots=False, n_boot=100)
    calm, rough = res["reports"]["sigma_0"], res["reports"]["sigma_1.5"]
    assert calm["seeds"] == rough["seeds"] == [5, 6]
    assert calm["turbulence_sigma_mps"] == 0.0 and rough["turbulence_sigma_mps"] == 1.5
    c, r = calm["policies"]["pid"]["summary"], rough["policies"]["pid"]["summary"]
    # the same controller in calm air holds the slot across the track better than in turbulence
    assert c["rms_lateral_m"] + c["rms_vertical_m"] < r["rms_lateral_m"] + r["rms_vertical_m"]
    assert "| pid | sigma 0 |" in res["table_markdown"] and "| pid | sigma 1.5 |" in res["table_markdown"]
    assert (tmp_path / "lv" / "sigma_0" / "results.json").is_file() and (tmp_path / "lv" / "levels.md").is_file()
    saved = json.loads((tmp_path / "lv" / "levels.json").read_text())
    assert saved["levels"] == [0.0, 1.5] and set(saved["summaries"]) == {"sigma_0", "sigma_1.5"}
    with pytest.raises(FileExistsError):  # never silently overwritten
        evaluate_levels(["pid"], scenario="close_formation", levels=(0.0,), episodes=1, out_dir=tmp_path / "lv",
                        plots=False, duration_s=1.0)


@pytest.mark.parametrize("levels", [(), (0.0, 0.0), (-1.0,), (float("nan"),), (True,)])
def test_bad_levels_are_refused(levels):
    with pytest.raises(ValueError, match="turbulence levels"):
        evaluate_levels(["pid"], scenario="close_formation", levels=levels, episodes=1)


def test_table_marks_missing_metrics():
    t = levels_table({"sigma_1": {"pid": {"rms_lateral_m": 0.5, "collisions": 0}}})
    assert "| pid | sigma 1 | - | - | 0.500 |" in t
