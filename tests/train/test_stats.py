"""train/evaluation/stats.py on synthetic cases with known answers."""

import math

import numpy as np
import pytest

from train.evaluation.stats import (bootstrap_ci, paired_comparison, paired_rate_difference, seed_spread,
                                    sign_test_p, wilson_interval)


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


def test_known_mean_difference_is_covered_and_zero_excluded():
    rng = np.random.default_rng(42)
    base = rng.normal(10.0, 2.0, 100)
    cand = base - rng.normal(0.5, 1.0, 100)  # true mean reduction 0.5
    r = paired_comparison(base, cand)
    lo, hi = r["mean_reduction_ci"]
    assert lo < 0.5 < hi and lo > 0.0
    assert hi - lo < 0.5  # about 2 x 1.96 x 1 / sqrt(100) = 0.39
    assert r["median_reduction_ci"][0] > 0.0
    assert r["relative_reduction_pct_ci"][0] > 0.0
    assert r["sign_test_p"] < 0.05 and r["fraction_better"] > 0.6
    # reproducible: same seed, same interval; another seed, a (slightly) different one
    assert paired_comparison(base, cand)["mean_reduction_ci"] == r["mean_reduction_ci"]
    assert paired_comparison(base, cand, seed=1)["mean_reduction_ci"] != r["mean_reduction_ci"]
    # higher-is-better metrics count the other way
    assert paired_comparison(base, cand, lower_is_better=False)["n_better"] == r["n_worse"]


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


def test_sign_test_and_wilson_known_values():
    assert sign_test_p(14, 6) == pytest.approx(0.1153, abs=5e-4)   # 14 better of 20
    assert sign_test_p(6, 14) == sign_test_p(14, 6)
    assert sign_test_p(10, 10) == 1.0 and sign_test_p(0, 0) == 1.0
    assert sign_test_p(3, 14) == pytest.approx(0.012726, abs=1e-6)  # scipy.stats.binomtest(3, 17).pvalue
    lo, hi = wilson_interval(95, 100)
    assert lo == pytest.approx(0.8882, abs=5e-4) and hi == pytest.approx(0.9785, abs=5e-4)
    lo, hi = wilson_interval(0, 20)
    assert lo == 0.0 and hi == pytest.approx(0.1611, abs=5e-4)       # not degenerate at 0 / n
    assert wilson_interval(20, 20)[1] == 1.0 and wilson_interval(0, 0) == (0.0, 1.0)
    assert wilson_interval(50, 100, 0.99)[0] < wilson_interval(50, 100)[0]
    with pytest.raises(ValueError):
        wilson_interval(5, 3)


def test_bootstrap_ci_statistics():
    x = np.arange(1.0, 101.0)
    lo, hi = bootstrap_ci(x, "mean")
    assert lo < 50.5 < hi and hi - lo == pytest.approx(2 * 1.96 * x.std() / 10, rel=0.1)
    assert bootstrap_ci(x, "mean") == (lo, hi)                      # seeded
    assert bootstrap_ci(x, np.mean, n_boot=2000) == pytest.approx(bootstrap_ci(x, "mean", n_boot=2000))
    assert bootstrap_ci(x, lambda s: s.mean(axis=1), n_boot=2000, vectorized=True) == \
        pytest.approx(bootstrap_ci(x, "mean", n_boot=2000))
    assert bootstrap_ci([3.0, 3.0, 3.0], "median") == (3.0, 3.0)
    assert bootstrap_ci([2.0], "mean") == (2.0, 2.0)
    lo90, hi90 = bootstrap_ci(x, "mean", confidence=0.9)
    assert lo < lo90 < hi90 < hi
    with pytest.raises(ValueError):
        bootstrap_ci([], "mean")
    with pytest.raises(ValueError):
        bootstrap_ci(x, "mode")
    with pytest.raises(ValueError):
        bootstrap_ci(x, "mean", confidence=1.5)


def test_rate_difference_and_seed_spread():
    base = np.array([0, 0, 1, 1, 0, 1, 0, 0, 1, 0] * 5, dtype=float)
    cand = np.ones(50)
    r = paired_rate_difference(base, cand)
    assert r["baseline_rate"] == pytest.approx(0.4) and r["candidate_rate"] == 1.0
    assert r["difference"] == pytest.approx(0.6) and r["difference_ci"][0] > 0.4
    assert r["n_better"] == 30 and r["n_worse"] == 0 and r["sign_test_p"] == pytest.approx(2 * 0.5 ** 30)
    s = seed_spread([1.0, 2.0, 4.0])
    assert s == {"mean": pytest.approx(7 / 3), "std": pytest.approx(math.sqrt(7 / 3)), "min": 1.0, "max": 4.0, "n": 3}
    one = seed_spread([5.0])
    assert one["mean"] == 5.0 and math.isnan(one["std"]) and one["n"] == 1
