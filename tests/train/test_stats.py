"""train/evaluation/stats.py: thin wrappers of SciPy, checked against SciPy (and statsmodels) called
directly and against closed-form answers."""

import math

import numpy as np
import pytest
import scipy.stats

from train.evaluation.stats import (N_BOOT, bootstrap_ci, paired_comparison, paired_rate_difference, seed_spread,
                                    sign_test_p, wilson_interval)


def _scipy(samples, statistic, **kw):
    """scipy.stats.bootstrap with the wrappers' conventions (seed 0, 10,000 resamples, percentile)."""
    kw = {"n_resamples": N_BOOT, "method": "percentile", "rng": np.random.default_rng(0), **kw}
    ci = scipy.stats.bootstrap(samples, statistic, **kw).confidence_interval
    return np.asarray(ci.low), np.asarray(ci.high)


def test_bootstrap_ci_is_scipy_bootstrap_bit_for_bit():
    x = np.random.default_rng(5).lognormal(0.0, 0.8, 80)
    lo, hi = _scipy((x,), np.mean)
    assert bootstrap_ci(x) == (float(lo), float(hi))
    lo, hi = _scipy((x,), np.median, method="BCa")
    assert bootstrap_ci(x, "median", method="BCa") == (float(lo), float(hi))
    assert bootstrap_ci(x) == bootstrap_ci(x)                          # seeded: reproducible
    assert bootstrap_ci(x, seed=1) != bootstrap_ci(x)
    # percentile of the means of x[default_rng(0).integers(0, n, (B, n))]: the resamples the committed
    # evaluations were drawn with, so their intervals recompute exactly
    boot = x[np.random.default_rng(0).integers(0, len(x), (N_BOOT, len(x)))].mean(axis=1)
    assert bootstrap_ci(x) == pytest.approx(tuple(np.percentile(boot, [2.5, 97.5])), rel=1e-12)


def test_bootstrap_ci_width_and_edge_cases():
    x = np.arange(1.0, 101.0)
    lo, hi = bootstrap_ci(x, "mean")
    # normal theory: 2 x 1.96 x sd / sqrt(n) (sd = 28.9); percentile bootstrap within 10 %
    assert lo < 50.5 < hi and hi - lo == pytest.approx(2 * 1.96 * x.std() / 10, rel=0.1)
    lo90, hi90 = bootstrap_ci(x, "mean", confidence=0.9)
    assert lo < lo90 < hi90 < hi
    assert bootstrap_ci(x, lambda s, axis=-1: np.mean(s, axis=axis), n_boot=2000) == bootstrap_ci(x, n_boot=2000)
    assert bootstrap_ci([3.0, 3.0, 3.0], "median") == (3.0, 3.0)
    assert bootstrap_ci([2.0], "mean") == (2.0, 2.0)
    assert all(math.isnan(v) for v in bootstrap_ci([1.0, float("nan")]))
    for bad in ({"values": []}, {"values": x, "statistic": "mode"}, {"values": x, "confidence": 1.5},
                {"values": x, "method": "studentized"}, {"values": np.ones((3, 2))}, {"values": x, "n_boot": 0}):
        with pytest.raises(ValueError):
            bootstrap_ci(**bad)


def test_paired_comparison_is_one_paired_scipy_bootstrap():
    rng = np.random.default_rng(42)
    base = rng.normal(10.0, 2.0, 100)
    cand = base - rng.normal(0.5, 1.0, 100)  # true mean reduction 0.5
    r = paired_comparison(base, cand)
    lo, hi = _scipy((base, cand), lambda b, c, axis: np.stack([np.mean(b - c, axis=axis), np.median(b - c, axis=axis),
                                                                100 * (np.mean(b, axis=axis) - np.mean(c, axis=axis))
                                                                / np.mean(b, axis=axis)]), paired=True, axis=-1)
    assert r["mean_reduction_ci"] == (lo[0], hi[0]) and r["median_reduction_ci"] == (lo[1], hi[1])
    assert r["relative_reduction_pct_ci"] == pytest.approx((lo[2], hi[2]), rel=1e-12)
    assert lo[0] < 0.5 < hi[0] and lo[0] > 0.0
    assert hi[0] - lo[0] < 0.5  # about 2 x 1.96 x 1 / sqrt(100) = 0.39
    assert r["sign_test_p"] < 0.05 and r["fraction_better"] > 0.6
    assert paired_comparison(base, cand, seed=1)["mean_reduction_ci"] != r["mean_reduction_ci"]
    assert paired_comparison(base, cand, lower_is_better=False)["n_better"] == r["n_worse"]
    bca = paired_comparison(base, cand, method="BCa")
    assert bca["method"] == "BCa" and bca["mean_reduction_ci"] != r["mean_reduction_ci"]


def test_constant_reduction_gives_degenerate_intervals():
    base = np.random.default_rng(0).uniform(5.0, 15.0, 50)
    r = paired_comparison(base, base - 1.0)
    assert r["n"] == 50 and r["n_excluded"] == 0
    assert r["mean_reduction"] == pytest.approx(1.0) and r["median_reduction"] == pytest.approx(1.0)
    assert r["mean_reduction_ci"] == pytest.approx((1.0, 1.0)) and r["median_reduction_ci"] == pytest.approx((1.0, 1.0))
    assert r["relative_reduction_pct"] == pytest.approx(100.0 / base.mean())
    lo, hi = r["relative_reduction_pct_ci"]
    assert lo <= r["relative_reduction_pct"] <= hi  # the ratio of means still varies with the resample
    assert r["fraction_better"] == 1.0 and r["n_better"] == 50 and r["n_worse"] == r["n_ties"] == 0
    assert r["sign_test_p"] == pytest.approx(2 * 0.5 ** 50)
    same = paired_comparison([2.0, 2.0, 2.0], [2.0, 2.0, 2.0])
    assert same["mean_reduction_ci"] == (0.0, 0.0) and same["sign_test_p"] == 1.0


def test_no_difference_is_not_significant():
    rng = np.random.default_rng(3)
    base = rng.normal(10.0, 2.0, 100)
    r = paired_comparison(base, base + rng.normal(0.0, 1.0, 100))
    lo, hi = r["mean_reduction_ci"]
    assert lo < 0.0 < hi and r["sign_test_p"] > 0.05


def test_paired_comparison_leaves_out_non_finite_pairs_and_checks_lengths():
    r = paired_comparison([1.0, 2.0, float("nan"), 4.0], [0.5, 1.5, 1.0, float("inf")])
    assert r["n"] == 2 and r["n_excluded"] == 2 and r["mean_reduction"] == pytest.approx(0.5)
    with pytest.raises(ValueError, match="same length"):
        paired_comparison([1.0, 2.0], [1.0])
    with pytest.raises(ValueError, match="finite"):
        paired_comparison([float("nan")], [1.0])


def test_sign_test_closed_form_and_scipy():
    # 3 better of 17: 2 * (C(17,0) + C(17,1) + C(17,2) + C(17,3)) / 2^17 = 2 * 834 / 131072
    assert sign_test_p(3, 14) == pytest.approx(2 * 834 / 2 ** 17, rel=1e-12)
    assert sign_test_p(14, 6) == scipy.stats.binomtest(14, 20, 0.5).pvalue
    assert sign_test_p(6, 14) == sign_test_p(14, 6)
    assert sign_test_p(10, 10) == 1.0 and sign_test_p(0, 0) == 1.0


def test_wilson_closed_form_and_statsmodels():
    z = scipy.stats.norm.ppf(0.975)
    for k, n in ((95, 100), (0, 20), (20, 20), (3, 7)):
        p = k / n
        centre = (p + z * z / (2 * n)) / (1 + z * z / n)
        half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
        assert wilson_interval(k, n) == pytest.approx((centre - half, centre + half), abs=1e-12)
    lo, hi = wilson_interval(95, 100)
    assert lo == pytest.approx(0.8882, abs=5e-5) and hi == pytest.approx(0.9785, abs=5e-5)
    assert wilson_interval(0, 20)[0] == 0.0 and wilson_interval(20, 20)[1] == 1.0  # exact ends, not 1 - 1e-16
    assert wilson_interval(0, 0) == (0.0, 1.0)
    assert wilson_interval(50, 100, 0.99)[0] < wilson_interval(50, 100)[0]
    with pytest.raises(ValueError):
        wilson_interval(5, 3)
    proportion = pytest.importorskip("statsmodels.stats.proportion")
    for k, n in ((95, 100), (3, 7), (1, 40)):
        assert wilson_interval(k, n) == pytest.approx(proportion.proportion_confint(k, n, 0.05, "wilson"), abs=1e-12)


def test_rate_difference_and_seed_spread():
    base = np.array([0, 0, 1, 1, 0, 1, 0, 0, 1, 0] * 5, dtype=float)
    cand = np.ones(50)
    r = paired_rate_difference(base, cand)
    assert r["baseline_rate"] == pytest.approx(0.4) and r["candidate_rate"] == 1.0
    assert r["difference"] == pytest.approx(0.6) and r["difference_ci"] == bootstrap_ci(cand - base)
    assert r["difference_ci"][0] > 0.4
    assert r["n_better"] == 30 and r["n_worse"] == 0 and r["sign_test_p"] == pytest.approx(2 * 0.5 ** 30)
    s = seed_spread([1.0, 2.0, 4.0])
    assert s == {"mean": pytest.approx(7 / 3), "std": pytest.approx(math.sqrt(7 / 3)), "min": 1.0, "max": 4.0, "n": 3}
    one = seed_spread([5.0])
    assert one["mean"] == 5.0 and math.isnan(one["std"]) and one["n"] == 1
