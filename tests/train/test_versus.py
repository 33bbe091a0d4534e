"""``formation-env publish versus``: two seed groups of one levels record compared paired by episode on the task's
headline metric (the difference of the seed-averaged episodes with its interval, and the probability of
improvement)."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("rliable")


def _record(scenario: str, key: str, cand, ref) -> dict:
    eps = {}
    for group, runs in (("new", cand), ("old", ref)):
        for k, values in enumerate(runs):
            eps[f"{scenario}_{group}_setpoints_seed{k}"] = {"seed": list(range(20, 20 + len(values))),
                                                             key: [float(v) for v in values]}
    eps["pid"] = {"seed": list(range(20, 20 + len(cand[0]))), key: [0.0] * len(cand[0])}
    return {"scenario": scenario, "levels": [1.0],
            "by_level": {"sigma_1": {"turbulence_sigma_mps": 1.0, "episodes": eps}}}


def test_versus_pairs_the_episodes_of_the_headline_metric(tmp_path, capsys):
    from formation_env.cli import main
    from train.publish.versus import versus

    rng = np.random.default_rng(0)
    base = rng.uniform(0.4, 0.8, 60)  # hard and easy episodes, shared by both groups
    ref = [base + rng.normal(0, 0.01, 60) for _ in range(3)]
    cand = [base + 0.02 + rng.normal(0, 0.01, 60) for _ in range(3)]
    rec = _record("close_formation", "harvest_ratio", cand, ref)
    out = versus(rec, "close_formation_new_setpoints", "close_formation_old_setpoints", n_boot=500)
    lv = out["levels"]["sigma_1"]
    assert out["metric"] == "harvest_ratio" and out["higher_is_better"]
    assert lv["difference"] == pytest.approx(np.mean(cand) - np.mean(ref))
    # paired by episode: the episodes' spread (0.4-0.8) cancels, the interval is tight around +0.02
    assert 0 < lv["difference_ci"][0] < 0.02 < lv["difference_ci"][1] < 0.03 and lv["better"]
    assert lv["probability_of_improvement"]["value"] > 0.8
    assert lv["candidate_runs"] == [f"close_formation_new_setpoints_seed{k}" for k in range(3)]
    # the reverse comparison: the same interval, negated
    new, old = "close_formation_new_setpoints", "close_formation_old_setpoints"
    back = versus(rec, old, new, n_boot=500)["levels"]["sigma_1"]
    assert back["difference"] == pytest.approx(-lv["difference"]) and not back["better"]

    path = tmp_path / "rec.json"
    path.write_text(json.dumps(rec))
    assert main(["publish", "versus", str(path), new, old, str(tmp_path / "o.json")]) == 0
    assert "sigma_1: harvest_ratio" in capsys.readouterr().out
    assert json.loads((tmp_path / "o.json").read_text())["levels"]["sigma_1"]["better"]
    # one clear error, status 2: an unknown group, an existing output
    assert main(["publish", "versus", str(path), "close_formation_sac_setpoints", old, str(tmp_path / "p.json")]) == 2
    assert "no policy close_formation_sac_setpoints_seed<k>" in capsys.readouterr().err
    assert main(["publish", "versus", str(path), new, old, str(tmp_path / "o.json")]) == 2
    assert "refusing to overwrite existing file" in capsys.readouterr().err
    assert main(["publish", "versus", str(path), new, old, str(tmp_path / "o.json"), "--overwrite"]) == 0


def test_versus_a_success_rate():
    from train.publish.versus import versus

    ref = [np.r_[np.ones(30), np.zeros(30)]] * 3
    cand = [np.ones(60)] * 3
    rec = _record("reconfiguration", "reconfig_success", cand, ref)
    lv = versus(rec, "reconfiguration_new_setpoints", "reconfiguration_old_setpoints", n_boot=500)["levels"]["sigma_1"]
    assert lv["difference"] == pytest.approx(0.5) and lv["better"]
    assert lv["paired"]["candidate_rate"] == 1.0 and lv["paired"]["baseline_rate"] == 0.5


def test_the_results_page_shows_each_versus_record_of_a_task(tmp_path):
    from formation_env.tasks import get_task
    from train.publish.results_page import versus_markdown
    from train.publish.versus import versus

    rng = np.random.default_rng(1)
    base = rng.uniform(0.4, 0.8, 40)
    rec = _record("close_formation", "harvest_ratio", [base + 0.03 + rng.normal(0, 0.01, 40) for _ in range(3)],
                  [base + rng.normal(0, 0.01, 40) for _ in range(3)])
    rec["by_level"]["sigma_1"]["episodes"] = {k.replace("_new_", "_sac_").replace("_old_", "_ppo_"): v
                                              for k, v in rec["by_level"]["sigma_1"]["episodes"].items()}
    out = versus(rec, "close_formation_sac_setpoints", "close_formation_ppo_setpoints", n_boot=300)
    task = get_task("close_formation")
    assert versus_markdown(task, tmp_path) == []  # no record: no section
    (tmp_path / "close_formation_sac_setpoints_versus_ppo.json").write_text(json.dumps(out))
    other = dict(out, task="vee5")  # another task's record under a misleading name is not shown
    (tmp_path / "close_formation_td3_setpoints_versus_ppo.json").write_text(json.dumps(other))
    lines = versus_markdown(task, tmp_path)
    rows = [ln for ln in lines if ln.startswith("| SAC |")]
    lv = out["levels"]["sigma_1"]
    assert len(rows) == 1 and "close_formation_td3" not in "\n".join(lines)
    assert f"{lv['difference']:+.3f} [{lv['difference_ci'][0]:+.3f}, {lv['difference_ci'][1]:+.3f}]" in rows[0]
    assert rows[0].startswith(f"| SAC | sigma 1 | {lv['candidate_mean']:.3f} | {lv['reference_mean']:.3f} |")
