"""train/evaluation/aggregates.py (rliable): closed-form answers, rliable's own functions called directly,
SciPy's bootstrap as an independent reference, reproducibility, and the aggregates of a committed record."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
import scipy.stats

pytest.importorskip("rliable")
from rliable import metrics  # noqa: E402

from train.evaluation import aggregates as agg  # noqa: E402

RECORD = Path(__file__).resolve().parents[2] / "train" / "policies" / "formation_keeping_ppo_setpoints_evaluation.json"


def test_iqm_mean_median_closed_form():
    x = np.array([[1.0, 2.0, 3.0, 10.0], [4.0, 5.0, 6.0, 100.0]])  # 2 runs x 4 episodes
    r = agg.aggregate(x, n_boot=200)
    # IQM: sorted 1 2 3 4 5 6 10 100, the middle half 3 4 5 6; median over episodes of the run means
    # 2.5 3.5 4.5 55 -> 4.0
    assert r["iqm"]["value"] == 4.5 == metrics.aggregate_iqm(x)
    assert r["mean"]["value"] == pytest.approx(131 / 8) and r["median"]["value"] == 4.0
    for s in r.values():
        assert s["ci"][0] <= s["value"] <= s["ci"][1]
    const = agg.aggregate(np.full((3, 5), 2.5), n_boot=100)
    assert all(v["ci"] == [2.5, 2.5] and v["value"] == 2.5 for v in const.values())


def test_aggregate_is_reproducible_and_leaves_the_global_generator_alone():
    x = np.random.default_rng(1).normal(size=(3, 40))
    np.random.seed(123)
    before = np.random.get_state()[1].copy()
    a, b = agg.aggregate(x, n_boot=300), agg.aggregate(x, n_boot=300)
    assert a == b                                            # bit for bit
    assert np.array_equal(np.random.get_state()[1], before)  # the caller's global state is restored
    assert agg.aggregate(x, n_boot=300, seed=1) != a
    with pytest.raises(ValueError):
        agg.aggregate(x, ["mode"])
    with pytest.raises(ValueError):
        agg.aggregate(np.ones(4))


def test_one_run_stratified_bootstrap_is_the_episode_bootstrap():
    """With one run, rliable's stratified bootstrap resamples episodes only: its percentile interval of the
    mean is SciPy's, up to the Monte-Carlo noise of the two (independent) sets of 4000 resamples."""
    x = np.random.default_rng(7).normal(0.0, 1.0, 60)
    n_boot = 4000
    r = agg.aggregate(x[None, :], ["mean"], n_boot=n_boot)["mean"]["ci"]
    s = scipy.stats.bootstrap((x,), np.mean, n_resamples=n_boot, method="percentile", rng=np.random.default_rng(0))
    # sd of a 2.5 % bootstrap quantile: sqrt(p (1 - p) / B) / pdf(z_p) x the sd of the mean (normal theory)
    se = math.sqrt(0.025 * 0.975 / n_boot) / scipy.stats.norm.pdf(1.96) * x.std(ddof=1) / math.sqrt(len(x))
    tol = 5.0 * math.sqrt(2.0) * se  # two independent draws, 5 sd
    assert abs(r[0] - s.confidence_interval.low) < tol and abs(r[1] - s.confidence_interval.high) < tol


def test_probability_of_improvement_closed_form_and_rliable():
    x = np.array([[3.0, 1.0], [5.0, 2.0]])   # 2 runs x 2 episodes
    y = np.array([[4.0, 2.0]])               # a one-run baseline
    # episode 0: 5 > 4 in 1 of 2 pairs -> 0.5; episode 1: 1 < 2, 2 = 2 (half) -> 0.25; mean 0.375
    hi = agg.probability_of_improvement(x, y, n_boot=200)
    assert hi["value"] == pytest.approx(0.375) == metrics.probability_of_improvement(x, y)
    lo = agg.probability_of_improvement(x, y, higher_is_better=False, n_boot=200)
    assert lo["value"] == pytest.approx(0.625)               # ties count half either way
    for r in (hi, lo):
        assert 0.0 <= r["ci"][0] <= r["value"] <= r["ci"][1] <= 1.0
    rng = np.random.default_rng(3)
    a, b = rng.integers(0, 4, (3, 30)).astype(float), rng.integers(0, 4, (3, 30)).astype(float)  # many ties
    stacked = np.stack([a, b], axis=-1)
    assert agg._poi_stacked(stacked)[0] == pytest.approx(metrics.probability_of_improvement(a, b))
    tiled = np.stack([a, np.repeat(b[:1], 3, axis=0)], axis=-1)
    assert agg._poi_stacked(tiled)[0] == pytest.approx(metrics.probability_of_improvement(a, b[:1]))
    sure = agg.probability_of_improvement(a + 10.0, b, n_boot=100)
    assert sure == {"value": 1.0, "ci": [1.0, 1.0]}
    with pytest.raises(ValueError, match="runs"):
        agg.probability_of_improvement(np.ones((3, 2)), np.ones((2, 2)))


def test_performance_profiles_known_fractions(tmp_path):
    s = {"a": np.array([[1.0, 2.0, 3.0, 4.0]])}
    taus = np.array([0.5, 2.5, 4.5])
    p, c = agg.performance_profiles(s, taus, n_boot=200)
    assert p["a"].tolist() == [1.0, 0.5, 0.0] and c["a"].shape == (2, 3)
    p, c = agg.performance_profiles(s, taus, higher_is_better=False, n_boot=200)
    assert p["a"].tolist() == [0.0, 0.5, 1.0]
    assert np.all(c["a"][0] <= p["a"]) and np.all(p["a"] <= c["a"][1])
    panel = {"score": agg.SCORES["rms_slot_error_m"], "taus": taus, "profiles": p, "cis": c}
    out = agg.plot_profiles(tmp_path / "profile.png", [panel], title="t")
    assert out.is_file() and out.stat().st_size > 1000
    with pytest.raises(FileExistsError):           # never silently overwritten
        agg.plot_profiles(tmp_path / "profile.png", [panel], title="t")
    agg.plot_profiles(tmp_path / "profile.png", [panel], title="t", overwrite=True)


def test_score_matrix_and_normalisation_checks():
    eps = [[{"seed": 1, "rms_slot_error_m": 2.0}, {"seed": 2, "rms_slot_error_m": 4.0}]]
    assert agg.score_matrix(eps, "rms_slot_error_m").tolist() == [[2.0, 4.0]]
    with pytest.raises(ValueError, match="same episodes"):
        agg.score_matrix(eps + [[{"seed": 2, "rms_slot_error_m": 1.0}, {"seed": 1, "rms_slot_error_m": 1.0}]], "rms_slot_error_m")
    with pytest.raises(ValueError, match="non-finite"):
        agg.score_matrix([[{"seed": 1, "rms_slot_error_m": float("nan")}]], "rms_slot_error_m")
    rms = agg.SCORES["rms_slot_error_m"]
    assert agg.normalised_score(rms, [0.0, 5.0, 10.0], 10.0).tolist() == [1.0, 0.5, 0.0]
    assert agg.normalised_score(agg.SCORES["saving_ratio"], [0.3]).tolist() == [0.3]
    with pytest.raises(ValueError, match="baseline"):
        agg.normalised_score(rms, [1.0], 0.0)


@pytest.mark.skipif(not RECORD.is_file(), reason="no committed formation_keeping record")
def test_aggregates_of_the_committed_record():
    """From the stored per-episode data (no simulation): the group's stratified mean is the mean of its
    3 x 100 scores, its interval is wider than the seed-averaged episode bootstrap's (it adds the seeds),
    and the policy beats the thesis PID in most episode pairs."""
    rec = json.loads(RECORD.read_text())
    eps = {n: r["episodes"] for n, r in rec["policies"].items()}
    groups = {g: r["policies"] for g, r in rec["groups"].items()}
    res = agg.evaluation_aggregates(eps, groups, list(rec["baselines"].values()), n_boot=300)
    e = res["scores"]["rms_slot_error_m"]
    g = e["policies"]["formation_keeping_ppo_setpoints"]
    assert (g["runs"], g["episodes"]) == (3, 100)
    per = [ep["rms_slot_error_m"] for n in groups["formation_keeping_ppo_setpoints"] for ep in eps[n]]
    assert g["mean"]["value"] == pytest.approx(np.mean(per)) and g["iqm"]["value"] == pytest.approx(
        scipy.stats.trim_mean(per, 0.25))
    assert g["iqm"]["value"] < g["mean"]["value"]  # the failures' long tail is trimmed
    assert e["probability_of_improvement"]["formation_keeping_ppo_setpoints"]["pid"]["value"] > 0.95
    assert set(e["profile"]["profiles"]) == {"formation_keeping_ppo_setpoints", "pid", "pid_formation"}
    assert "| formation_keeping_ppo_setpoints | 3 x 100 |" in agg.aggregates_table(res)
