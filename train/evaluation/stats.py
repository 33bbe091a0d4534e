"""Statistics for evaluation claims: bootstrap intervals, paired comparisons, Wilson intervals and the
spread across training seeds. Pure numpy (plus the standard library); every random draw comes from a
seeded generator, so the same inputs always give the same intervals.

* :func:`bootstrap_ci` - percentile bootstrap confidence interval of a statistic.
* :func:`paired_comparison` - candidate vs baseline on the *same* episodes (paired by seed): mean and
  median of the per-episode reduction ``baseline - candidate`` and the relative reduction of the mean,
  each with a bootstrap interval (episodes resampled jointly), the fraction of episodes where the
  candidate is better and a two-sided sign test.
* :func:`paired_rate_difference` - the same for a per-episode success indicator (difference of rates).
* :func:`wilson_interval` - Wilson score interval of a binomial proportion.
* :func:`sign_test_p` - exact two-sided sign test (binomial, p = 1/2).
* :func:`seed_spread` - mean, sample std, min, max of one number per training seed.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from statistics import NormalDist

import numpy as np

__all__ = ["bootstrap_ci", "paired_comparison", "paired_rate_difference", "wilson_interval", "sign_test_p",
           "seed_spread", "N_BOOT", "CONFIDENCE"]

N_BOOT = 10_000
CONFIDENCE = 0.95

_VECTORISED = {"mean": lambda x: np.mean(x, axis=1), "median": lambda x: np.median(x, axis=1)}


def _check_confidence(confidence: float) -> float:
    if isinstance(confidence, bool) or not isinstance(confidence, (int, float)) or not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be a number in (0, 1), got {confidence!r}")
    return float(confidence)


def _check_n_boot(n_boot: int) -> int:
    if isinstance(n_boot, bool) or not isinstance(n_boot, (int, np.integer)) or n_boot < 1:
        raise ValueError(f"n_boot must be an integer >= 1, got {n_boot!r}")
    return int(n_boot)


def _resample_indices(n: int, n_boot: int, seed: int) -> np.ndarray:
    """(n_boot, n) episode indices drawn with replacement from a generator seeded with ``seed``."""
    return np.random.default_rng(seed).integers(0, n, size=(n_boot, n))


def _percentiles(boot: np.ndarray, confidence: float) -> tuple[float, float]:
    alpha = 1.0 - confidence
    lo, hi = np.percentile(boot, [100.0 * alpha / 2.0, 100.0 * (1.0 - alpha / 2.0)])
    return float(lo), float(hi)


def bootstrap_ci(values, statistic: str | Callable = "mean", n_boot: int = N_BOOT, confidence: float = CONFIDENCE,
                 seed: int = 0, *, vectorized: bool = False) -> tuple[float, float]:
    """Percentile bootstrap interval ``(low, high)`` of ``statistic(values)``.

    ``values``: shape (n,) or (n, ...) - the rows (episodes) are resampled with replacement, so the
    columns of a row stay together (a paired sample). ``statistic``: "mean", "median" or a callable;
    a callable gets one resample (same shape as ``values``) and returns a number, or, with
    ``vectorized=True``, all resamples at once (shape (n_boot, n, ...)) and returns (n_boot,) numbers.
    The draws come from ``numpy.random.default_rng(seed)``: the interval is reproducible. A constant
    sample gives the degenerate interval (v, v); NaN values propagate (a NaN interval).
    """
    x = np.asarray(values, dtype=float)
    if x.ndim == 0 or len(x) == 0:
        raise ValueError("bootstrap_ci needs at least one value")
    n_boot, confidence = _check_n_boot(n_boot), _check_confidence(confidence)
    samples = x[_resample_indices(len(x), n_boot, seed)]      # (n_boot, n, ...)
    if isinstance(statistic, str):
        if statistic not in _VECTORISED:
            raise ValueError(f"statistic must be 'mean', 'median' or a callable, got {statistic!r}")
        boot = _VECTORISED[statistic](samples)
    elif vectorized:
        boot = np.asarray(statistic(samples), dtype=float).reshape(n_boot)
    else:
        boot = np.array([float(statistic(s)) for s in samples])
    if np.isnan(boot).any():
        return float("nan"), float("nan")
    return _percentiles(boot, confidence)


def sign_test_p(n_better: int, n_worse: int) -> float:
    """Exact two-sided sign test: the probability, under "better and worse equally likely", of a split
    at least as uneven as ``n_better : n_worse`` (ties are left out before calling). 1.0 without pairs.
    Equals ``scipy.stats.binomtest(n_better, n_better + n_worse, 0.5).pvalue``."""
    n = int(n_better) + int(n_worse)
    if n == 0:
        return 1.0
    k = min(int(n_better), int(n_worse))
    tail = sum(math.comb(n, i) for i in range(k + 1))
    return float(min(1.0, 2 * tail / 2 ** n))


def _paired_arrays(baseline, candidate) -> tuple[np.ndarray, np.ndarray, int]:
    b = np.asarray(baseline, dtype=float).reshape(-1)
    c = np.asarray(candidate, dtype=float).reshape(-1)
    if b.shape != c.shape:
        raise ValueError(f"paired samples must have the same length, got {len(b)} (baseline) and {len(c)} (candidate)")
    keep = np.isfinite(b) & np.isfinite(c)
    if not keep.any():
        raise ValueError("no episode with finite values for both the baseline and the candidate")
    return b[keep], c[keep], int((~keep).sum())


def paired_comparison(baseline, candidate, n_boot: int = N_BOOT, confidence: float = CONFIDENCE, seed: int = 0, *,
                      lower_is_better: bool = True) -> dict:
    """Paired comparison of one per-episode metric (same episodes, same order) of a candidate against a
    baseline. The per-episode reduction is ``d = baseline - candidate`` in the metric's units (positive:
    the candidate's value is lower).

    Returns a dict: ``n`` (pairs used; pairs with a non-finite value are left out and counted in
    ``n_excluded``), ``baseline_mean``, ``candidate_mean``, ``mean_reduction`` (mean of d) and
    ``mean_reduction_ci``, ``median_reduction`` (median of d) and ``median_reduction_ci``,
    ``relative_reduction_pct`` = 100 (mean(baseline) - mean(candidate)) / mean(baseline) (ratio of
    means) and ``relative_reduction_pct_ci``, ``n_better`` / ``n_worse`` / ``n_ties``,
    ``fraction_better`` (n_better / n), ``sign_test_p`` (exact two-sided sign test, ties left out),
    ``confidence`` and ``n_boot``. The intervals are percentile bootstrap intervals in which the
    episodes are resampled jointly (one set of resampled indices for all three statistics, drawn from
    ``default_rng(seed)``). "Better" is lower when ``lower_is_better`` (errors), higher otherwise.
    """
    b, c, excluded = _paired_arrays(baseline, candidate)
    n_boot, confidence = _check_n_boot(n_boot), _check_confidence(confidence)
    d = b - c
    idx = _resample_indices(len(d), n_boot, seed)
    bb, cc, dd = b[idx], c[idx], d[idx]
    mb = bb.mean(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel_boot = 100.0 * (mb - cc.mean(axis=1)) / mb
        rel = 100.0 * (b.mean() - c.mean()) / b.mean() if b.mean() != 0 else float("nan")
    better = d > 0 if lower_is_better else d < 0
    worse = d < 0 if lower_is_better else d > 0
    n_better, n_worse = int(better.sum()), int(worse.sum())
    rel_ci = _percentiles(rel_boot, confidence) if np.all(np.isfinite(rel_boot)) else (float("nan"), float("nan"))
    return {
        "n": int(len(d)), "n_excluded": excluded,
        "baseline_mean": float(b.mean()), "candidate_mean": float(c.mean()),
        "mean_reduction": float(d.mean()), "mean_reduction_ci": _percentiles(dd.mean(axis=1), confidence),
        "median_reduction": float(np.median(d)), "median_reduction_ci": _percentiles(np.median(dd, axis=1), confidence),
        "relative_reduction_pct": float(rel), "relative_reduction_pct_ci": rel_ci,
        "n_better": n_better, "n_worse": n_worse, "n_ties": int(len(d) - n_better - n_worse),
        "fraction_better": n_better / len(d), "sign_test_p": sign_test_p(n_better, n_worse),
        "confidence": confidence, "n_boot": n_boot,
    }


def paired_rate_difference(baseline, candidate, n_boot: int = N_BOOT, confidence: float = CONFIDENCE,
                           seed: int = 0) -> dict:
    """Paired comparison of a per-episode success indicator (0/1, or a fraction in [0, 1] such as the
    success averaged over training seeds): ``difference`` = candidate rate - baseline rate (positive:
    the candidate succeeds more often) with a bootstrap interval (episodes resampled jointly),
    ``baseline_rate``, ``candidate_rate``, ``n_better`` / ``n_worse`` / ``n_ties`` (episodes where the
    candidate's value is higher / lower / equal) and ``sign_test_p`` (on the discordant episodes: the
    exact McNemar test for 0/1 data)."""
    b, c, excluded = _paired_arrays(baseline, candidate)
    n_boot, confidence = _check_n_boot(n_boot), _check_confidence(confidence)
    d = c - b
    n_better, n_worse = int((d > 0).sum()), int((d < 0).sum())
    return {
        "n": int(len(d)), "n_excluded": excluded,
        "baseline_rate": float(b.mean()), "candidate_rate": float(c.mean()),
        "difference": float(d.mean()), "difference_ci": bootstrap_ci(d, "mean", n_boot, confidence, seed),
        "n_better": n_better, "n_worse": n_worse, "n_ties": int(len(d) - n_better - n_worse),
        "sign_test_p": sign_test_p(n_better, n_worse), "confidence": confidence, "n_boot": n_boot,
    }


def wilson_interval(successes: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """Wilson score interval ``(low, high)`` of a proportion ``successes / n`` (e.g. 95 / 100 ->
    (0.888, 0.978)). Unlike the normal approximation it stays inside [0, 1] and is not degenerate at
    0 / n or n / n. ``n`` = 0 gives (0, 1)."""
    confidence = _check_confidence(confidence)
    if isinstance(successes, bool) or isinstance(n, bool) or int(successes) != successes or int(n) != n:
        raise ValueError(f"successes and n must be integers, got {successes!r}, {n!r}")
    k, n = int(successes), int(n)
    if n < 0 or not 0 <= k <= n:
        raise ValueError(f"need 0 <= successes <= n, got successes={k}, n={n}")
    if n == 0:
        return 0.0, 1.0
    z = NormalDist().inv_cdf(1.0 - (1.0 - confidence) / 2.0)
    p = k / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4 * n * n)) / denom
    return (0.0 if k == 0 else max(0.0, centre - half)), (1.0 if k == n else min(1.0, centre + half))


def seed_spread(values_per_seed: Sequence[float]) -> dict:
    """One number per training seed -> ``{"mean", "std" (sample std, ddof=1; NaN for one seed), "min",
    "max", "n"}`` (non-finite values propagate into mean/std/min/max)."""
    x = np.asarray(values_per_seed, dtype=float).reshape(-1)
    if len(x) == 0:
        raise ValueError("seed_spread needs at least one value")
    return {"mean": float(x.mean()), "std": float(x.std(ddof=1)) if len(x) > 1 else float("nan"),
            "min": float(x.min()), "max": float(x.max()), "n": int(len(x))}
