"""`formation-env evaluate` with 3 seeds of a recipe: the rliable aggregates printed and stored, the
performance-profile figure and marl_eval.json written (a tiny evaluation: 3 short episodes); and the
committed records recomputed from their stored episodes reproduce their intervals."""

import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rliable")

import train.evaluation.evaluate as ev  # noqa: E402
from formation_env.cli import main  # noqa: E402

POLICIES = Path(__file__).resolve().parents[2] / "train" / "policies"


@pytest.fixture
def three_seeds(seeded_candidates):
    """'cand_seed<k>': the PID plus a constant throttle residual of 0.1 k (a different controller per seed)."""
    seeded_candidates(0.1)


def test_cli_evaluate_three_seeds_reports_rliable_aggregates(tmp_path, capsys, three_seeds):
    out = tmp_path / "ev"
    argv = ["evaluate", "--scenario", "formation_keeping", "--episodes", "3", "--duration", "2", "--seeds", "7",
            "--bootstrap-resamples", "200", "--out", str(out)]
    for p in ("cand_seed0", "cand_seed1", "cand_seed2", "pid"):
        argv += ["--policy", p]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "IQM [95 % CI]" in printed and "probability of improvement" in printed and "| cand | 3 x 3 |" in printed
    for name in ("results.json", "results.md", "marl_eval.json", "performance_profile.png", "metrics.png"):
        assert (out / name).is_file(), name
    rep = json.loads((out / "results.json").read_text())
    e = rep["aggregates"]["scores"]["rms_slot_error_m"]
    assert rep["aggregates"]["statistics"]["n_boot"] == 200
    cand, pid = e["policies"]["cand"], e["policies"]["pid"]
    assert (cand["runs"], cand["episodes"], pid["runs"]) == (3, 3, 1)
    per = [ep["rms_slot_error_m"] for n in ("cand_seed0", "cand_seed1", "cand_seed2")
           for ep in rep["policies"][n]["episodes"]]
    assert cand["mean"]["value"] == pytest.approx(np.mean(per))
    for s in ("iqm", "mean", "median"):
        assert cand[s]["ci"][0] <= cand[s]["value"] <= cand[s]["ci"][1]
    poi = e["probability_of_improvement"]["cand"]["pid"]
    assert 0.0 <= poi["ci"][0] <= poi["value"] <= poi["ci"][1] <= 1.0
    assert "## Aggregates over training seeds and episodes" in (out / "results.md").read_text()
    m = json.loads((out / "marl_eval.json").read_text())["formation_env"]["formation_keeping"]
    assert set(m) == {"cand", "pid"} and list(m["cand"]) == ["seed_0", "seed_1", "seed_2"] and len(m["pid"]) == 3


def test_seed_groups_of_different_sizes_evaluate_every_level_without_marl_eval(tmp_path, capsys, three_seeds):
    """marl-eval's format needs as many runs in every group: with 3 seeds of one recipe and 2 of another the
    evaluation still writes every level (no marl_eval.json, a note instead), where it used to stop after the first."""
    out = tmp_path / "ev"
    argv = ["evaluate", "--scenario", "formation_keeping", "--episodes", "2", "--duration", "1", "--seeds", "7",
            "--bootstrap-resamples", "100", "--no-plots", "--turbulence", "0", "1", "--out", str(out)]
    for p in ("cand_seed0", "cand_seed1", "cand_seed2", "candb_seed0", "candb_seed1", "pid"):
        argv += ["--policy", p]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "marl_eval.json not written" in printed and "[2, 3]" in printed
    for level in ("sigma_0", "sigma_1"):
        rep = json.loads((out / level / "results.json").read_text())
        assert "the seed groups have [2, 3]" in rep["marl_eval"]
        assert not (out / level / "marl_eval.json").exists()
        assert rep["aggregates"]["scores"]["rms_slot_error_m"]["policies"]["candb"]["runs"] == 2


@pytest.mark.parametrize("task", ["formation_keeping", "reconfiguration", "wake_surfing"])
def test_committed_records_recompute_to_their_intervals(task):
    """The library estimators on the stored per-episode data give the committed intervals: SciPy draws
    the same resamples from default_rng(0) as the former code did, so they agree to rounding (the
    wake-surfing record stores 5 decimals), far inside the Monte-Carlo noise (about 1 % of a width)."""
    from train.publish.recompute import _leaves, record_path, recompute_statistics

    path = record_path(task)
    if not path.is_file():
        pytest.skip(f"no committed {task} record")
    rec = json.loads(path.read_text())
    old = _leaves({k: rec[k] for k in ("policies", "controllers", "comparisons", "groups") if k in rec})
    new = _leaves(recompute_statistics(task, rec))
    tol = 2e-5 if task == "wake_surfing" else 1e-9
    common = [p for p in old if p in new]
    assert len(common) > 40
    for p in common:
        assert np.allclose(old[p], new[p], rtol=0, atol=tol, equal_nan=True), (p, old[p], new[p])
