"""Statistics for evaluation claims, on SciPy: thin, documented wrappers that fix the project's
conventions (95 %, 10,000 resamples, a seeded generator, NaN-free pair handling) and keep the names the
rest of the evaluation uses. Nothing here re-implements an estimator.

* :func:`bootstrap_ci` - ``scipy.stats.bootstrap`` interval of a statistic of one sample (percentile by
  default, ``method="BCa"`` or ``"basic"`` on request).
* :func:`paired_comparison` - candidate vs baseline on the *same* episodes: mean and median of the
  per-episode reduction ``baseline - candidate`` and the relative reduction of the mean, their intervals
  from one ``scipy.stats.bootstrap(..., paired=True)`` (episodes resampled jointly, the three statistics
  from the same resamples), episodes better / worse and a sign test.
* :func:`paired_rate_difference` - the same for a per-episode success indicator (difference of rates).
* :func:`wilson_interval` - Wilson score interval, ``scipy.stats.binomtest(k, n).proportion_ci(method=
  "wilson")`` (identical to statsmodels' ``proportion_confint(k, n, method="wilson")``, which the tests
  check; SciPy's is used so that training, which summarises its validation episodes, needs no extra).
* :func:`sign_test_p` - exact two-sided sign test, ``scipy.stats.binomtest(n_better, n_better + n_worse,
  0.5).pvalue``.
* :func:`seed_spread` - mean, sample std, min, max of one number per training seed (descriptive only;
  the rliable aggregates of :mod:`train.evaluation.aggregates` resample runs and episodes together).

Every bootstrap draws from ``numpy.random.default_rng(seed)``: the same inputs give the same intervals,
bit for bit.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Sequence

import numpy as np
import scipy.stats

__all__ = ["bootstrap_ci", "paired_comparison", "paired_rate_difference", "wilson_interval", "sign_test_p",
           "seed_spread", "N_BOOT", "CONFIDENCE", "METHODS"]

N_BOOT = 10_000
CONFIDENCE = 0.95
METHODS = ("percentile", "BCa", "basic")  # scipy.stats.bootstrap's methods

_STATISTICS = {"mean": np.mean, "median": np.median}
# SciPy 1.15 renamed the generator argument random_state -> rng (the old name is deprecated there)
_RNG_KW = "rng" if "rng" in inspect.signature(scipy.stats.bootstrap).parameters else "random_state"


def _check_confidence(confidence: float) -> float:
    if isinstance(confidence, bool) or not isinstance(confidence, (int, float)) or not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be a number in (0, 1), got {confidence!r}")
    return float(confidence)


def _check_n_boot(n_boot: int) -> int:
    if isinstance(n_boot, bool) or not isinstance(n_boot, (int, np.integer)) or n_boot < 1:
        raise ValueError(f"n_boot must be an integer >= 1, got {n_boot!r}")
    return int(n_boot)


def _check_method(method: str) -> str:
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    return method


def _scipy_interval(samples: tuple[np.ndarray, ...], statistic: Callable, *, paired: bool, n_boot: int,
                    confidence: float, seed: int, method: str) -> tuple[np.ndarray, np.ndarray]:
    """``scipy.stats.bootstrap`` over the last axis with a generator seeded by ``seed``: (low, high)."""
    res = scipy.stats.bootstrap(samples, statistic, n_resamples=n_boot, confidence_level=confidence, method=method,
                                paired=paired, axis=-1, **{_RNG_KW: np.random.default_rng(seed)})
    return np.asarray(res.confidence_interval.low, float), np.asarray(res.confidence_interval.high, float)


def bootstrap_ci(values, statistic: str | Callable = "mean", n_boot: int = N_BOOT, confidence: float = CONFIDENCE,
                 seed: int = 0, *, method: str = "percentile") -> tuple[float, float]:
    """Bootstrap interval ``(low, high)`` of ``statistic(values)``: ``scipy.stats.bootstrap`` with
    ``n_boot`` resamples drawn from ``default_rng(seed)``.

    ``values``: shape (n,). ``statistic``: "mean", "median" or a callable in SciPy's form (``f(sample,
    axis=-1)`` is vectorised; a callable without ``axis`` is called once per resample). ``method``:
    "percentile" (the default, as rliable), "BCa" or "basic". One value gives the degenerate interval
    (v, v) (SciPy needs two); a constant sample gives (v, v); a non-finite value gives (NaN, NaN).
    """
    x = np.asarray(values, dtype=float).reshape(-1) if np.ndim(values) <= 1 else None
    if x is None:
        raise ValueError(f"bootstrap_ci takes one sample of shape (n,), got shape {np.shape(values)}")
    if len(x) == 0:
        raise ValueError("bootstrap_ci needs at least one value")
    n_boot, confidence, method = _check_n_boot(n_boot), _check_confidence(confidence), _check_method(method)
    if isinstance(statistic, str):
        if statistic not in _STATISTICS:
            raise ValueError(f"statistic must be 'mean', 'median' or a callable, got {statistic!r}")
        statistic = _STATISTICS[statistic]
    if not np.all(np.isfinite(x)):
        return float("nan"), float("nan")
    if len(x) == 1 or np.all(x == x[0]):  # no spread to resample (SciPy's BCa would give NaN)
        v = float(statistic(x))
        return v, v
    lo, hi = _scipy_interval((x,), statistic, paired=False, n_boot=n_boot, confidence=confidence, seed=seed,
                             method=method)
    return float(lo), float(hi)


def sign_test_p(n_better: int, n_worse: int) -> float:
    """Exact two-sided sign test: ``scipy.stats.binomtest(n_better, n_better + n_worse, 0.5).pvalue``
    (ties are left out before calling); 1.0 without pairs."""
    n = int(n_better) + int(n_worse)
    if n == 0:
        return 1.0
    return float(scipy.stats.binomtest(int(n_better), n, 0.5).pvalue)


def _paired_arrays(baseline, candidate) -> tuple[np.ndarray, np.ndarray, int]:
    b = np.asarray(baseline, dtype=float).reshape(-1)
    c = np.asarray(candidate, dtype=float).reshape(-1)
    if b.shape != c.shape:
        raise ValueError(f"paired samples must have the same length, got {len(b)} (baseline) and {len(c)} (candidate)")
    keep = np.isfinite(b) & np.isfinite(c)
    if not keep.any():
        raise ValueError("no episode with finite values for both the baseline and the candidate")
    return b[keep], c[keep], int((~keep).sum())


def _reductions(b, c, axis=-1):
    """(mean of b - c, median of b - c, 100 (mean b - mean c) / mean b) along ``axis`` (SciPy's form)."""
    mb, mc = np.mean(b, axis=axis), np.mean(c, axis=axis)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = 100.0 * (mb - mc) / mb
    return np.stack([np.mean(b - c, axis=axis), np.median(b - c, axis=axis), rel])


def paired_comparison(baseline, candidate, n_boot: int = N_BOOT, confidence: float = CONFIDENCE, seed: int = 0, *,
                      lower_is_better: bool = True, method: str = "percentile") -> dict:
    """Paired comparison of one per-episode metric (same episodes, same order) of a candidate against a
    baseline. The per-episode reduction is ``d = baseline - candidate`` in the metric's units (positive:
    the candidate's value is lower).

    Returns a dict: ``n`` (pairs used; pairs with a non-finite value are left out and counted in
    ``n_excluded``), ``baseline_mean``, ``candidate_mean``, ``mean_reduction`` (mean of d) and
    ``mean_reduction_ci``, ``median_reduction`` (median of d) and ``median_reduction_ci``,
    ``relative_reduction_pct`` = 100 (mean(baseline) - mean(candidate)) / mean(baseline) (ratio of
    means) and ``relative_reduction_pct_ci``, ``n_better`` / ``n_worse`` / ``n_ties``,
    ``fraction_better`` (n_better / n), ``sign_test_p`` (:func:`sign_test_p`, ties left out),
    ``confidence``, ``n_boot`` and ``method``. The three intervals come from one
    ``scipy.stats.bootstrap((baseline, candidate), ..., paired=True)`` (the same resampled episodes for
    all three, drawn from ``default_rng(seed)``). "Better" is lower when ``lower_is_better`` (errors),
    higher otherwise. A relative reduction whose baseline mean is 0 (or is 0 in a resample) is NaN.
    """
    b, c, excluded = _paired_arrays(baseline, candidate)
    n_boot, confidence, method = _check_n_boot(n_boot), _check_confidence(confidence), _check_method(method)
    d = b - c
    point = _reductions(b, c)
    if len(d) == 1 or (np.all(b == b[0]) and np.all(c == c[0])):  # nothing to resample
        lo = hi = point
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            lo, hi = _scipy_interval((b, c), _reductions, paired=True, n_boot=n_boot, confidence=confidence, seed=seed,
                                     method=method)
    ci = [(float(lo[i]), float(hi[i])) if np.isfinite(lo[i]) and np.isfinite(hi[i]) else (float("nan"), float("nan"))
          for i in range(3)]
    better = d > 0 if lower_is_better else d < 0
    worse = d < 0 if lower_is_better else d > 0
    n_better, n_worse = int(better.sum()), int(worse.sum())
    return {
        "n": int(len(d)), "n_excluded": excluded,
        "baseline_mean": float(b.mean()), "candidate_mean": float(c.mean()),
        "mean_reduction": float(point[0]), "mean_reduction_ci": ci[0],
        "median_reduction": float(point[1]), "median_reduction_ci": ci[1],
        "relative_reduction_pct": float(point[2]) if np.isfinite(point[2]) else float("nan"),
        "relative_reduction_pct_ci": ci[2],
        "n_better": n_better, "n_worse": n_worse, "n_ties": int(len(d) - n_better - n_worse),
        "fraction_better": n_better / len(d), "sign_test_p": sign_test_p(n_better, n_worse),
        "confidence": confidence, "n_boot": n_boot, "method": method,
    }


def paired_rate_difference(baseline, candidate, n_boot: int = N_BOOT, confidence: float = CONFIDENCE,
                           seed: int = 0) -> dict:
    """Paired comparison of a per-episode success indicator (0/1, or a fraction in [0, 1] such as the
    success averaged over training seeds): ``difference`` = candidate rate - baseline rate (positive:
    the candidate succeeds more often) with the :func:`bootstrap_ci` of the per-episode difference (the
    episodes' pairs resampled), ``baseline_rate``, ``candidate_rate``, ``n_better`` / ``n_worse`` /
    ``n_ties`` (episodes where the candidate's value is higher / lower / equal) and ``sign_test_p`` (on
    the discordant episodes: the exact McNemar test for 0/1 data)."""
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
    """Wilson score interval ``(low, high)`` of a proportion ``successes / n``:
    ``scipy.stats.binomtest(successes, n).proportion_ci(confidence, method="wilson")`` (e.g. 95 / 100 ->
    (0.888, 0.978); exactly 0 at 0 / n and 1 at n / n, unlike the normal approximation never outside
    [0, 1]). ``n`` = 0 gives (0, 1)."""
    confidence = _check_confidence(confidence)
    if isinstance(successes, bool) or isinstance(n, bool) or int(successes) != successes or int(n) != n:
        raise ValueError(f"successes and n must be integers, got {successes!r}, {n!r}")
    k, n = int(successes), int(n)
    if n < 0 or not 0 <= k <= n:
        raise ValueError(f"need 0 <= successes <= n, got successes={k}, n={n}")
    if n == 0:
        return 0.0, 1.0
    ci = scipy.stats.binomtest(k, n).proportion_ci(confidence_level=confidence, method="wilson")
    return float(ci.low), float(ci.high)


def seed_spread(values_per_seed: Sequence[float]) -> dict:
    """One number per training seed -> ``{"mean", "std" (sample std, ddof=1; NaN for one seed), "min",
    "max", "n"}`` (non-finite values propagate into mean/std/min/max). Descriptive: the intervals over
    seeds are :mod:`train.evaluation.aggregates`' (rliable)."""
    x = np.asarray(values_per_seed, dtype=float).reshape(-1)
    if len(x) == 0:
        raise ValueError("seed_spread needs at least one value")
    return {"mean": float(x.mean()), "std": float(x.std(ddof=1)) if len(x) > 1 else float("nan"),
            "min": float(x.min()), "max": float(x.max()), "n": int(len(x))}
