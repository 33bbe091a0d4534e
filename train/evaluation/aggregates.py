"""Aggregates over training seeds and episodes the way RL papers report them, on ``rliable`` (Agarwal
et al., "Deep RL at the edge of the statistical precipice", NeurIPS 2021): interquartile mean (IQM),
mean and median with stratified bootstrap 95 % intervals, the probability of improvement of each
policy over each baseline, and performance profiles.

The score matrix of a policy is (runs, episodes): one row per training seed (a baseline controller is
one run), one column per held-out episode, every policy on the same episodes in the same order.
Episodes take the place of rliable's tasks, so:

* ``aggregate`` - IQM = ``rliable.metrics.aggregate_iqm`` (25 % trimmed mean of all runs x episodes),
  mean = ``aggregate_mean``, median = ``aggregate_median`` (median over episodes of the run-averaged
  score); intervals from ``rliable.library.get_interval_estimates(..., task_bootstrap=True)``: each
  resample draws the episodes with replacement and, within each drawn episode, the runs with
  replacement (runs and episodes resampled together), percentile intervals.
* ``probability_of_improvement`` - ``rliable.metrics.probability_of_improvement``: per episode the
  Mann-Whitney probability P(X > Y) + P(X = Y) / 2 over the runs of the two policies on that episode
  (so the comparison is paired by episode), averaged over episodes. Its interval resamples the episodes
  (the same ones for both policies) and, within them, each policy's runs independently, through
  rliable's ``StratifiedBootstrap`` on the two matrices stacked (a one-run baseline is repeated to the
  policy's run count, which leaves its resamples unchanged); the statistic in the bootstrap is the same
  U statistic vectorised (the tests check it equals rliable's on fixed inputs).
* ``performance_profiles`` - ``rliable.library.create_performance_profile`` with the same bootstrap:
  the fraction of runs x episodes with a score better than tau (above for scores where higher is
  better, below for errors), drawn with ``rliable.plot_utils.plot_performance_profiles``.

Scores are the task's own, in its units, never normalised within one evaluation (every policy flies
the same task): the RMS slot error (m, lower is better), the reconfiguration success (0/1: only the
mean is reported, the IQM and median of 0/1 data are not rates) and the wake-surfing harvest ratio
(saving / the reference optimum's, already a fraction of the optimum). Only a comparison across tasks
normalises (:func:`normalised_score`).

Reproducibility: rliable 1.2's bootstraps draw from NumPy's legacy global generator and ignore their
``random_state`` argument, so every call here runs inside :func:`seeded_global_rng` (seeded with
``seed``, the previous global state restored after): the same inputs give the same intervals, bit for
bit. rliable is in the ``evaluation`` extra (``pip install -e ".[evaluation]"``).
"""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path

import numpy as np

from .stats import CONFIDENCE, N_BOOT

__all__ = ["Score", "SCORES", "scores_of", "score_matrix", "seeded_global_rng", "aggregate",
           "probability_of_improvement", "performance_profiles", "tau_grid", "plot_profiles", "normalised_score",
           "evaluation_aggregates", "profile_panels", "aggregates_table", "INSTALL_HINT"]

INSTALL_HINT = 'the rliable aggregates need the evaluation extra: pip install -e ".[evaluation]"'


@dataclasses.dataclass(frozen=True)
class Score:
    """A per-episode score: its key in the episode dicts, a label, its direction, the aggregates that
    make sense for it, and whether its performance profile is drawn on a log axis."""

    key: str
    label: str
    higher_is_better: bool
    statistics: tuple[str, ...] = ("iqm", "mean", "median")
    log_scale: bool = False


SCORES = {s.key: s for s in (
    Score("rms_slot_error_m", "RMS slot error (m)", False, log_scale=True),
    Score("reconfig_success", "reconfiguration success (0/1)", True, ("mean",)),
    Score("saving_ratio", "harvest ratio (saving / reference optimum)", True),
    # close formation (issue 24): the mean saving over the calm-air saving at the task's reference optimum
    Score("harvest_ratio", "harvest ratio (saving / calm-air optimum)", True),
)}


def scores_of(episodes: Sequence[dict]) -> list[Score]:
    """The task's scores present in these episodes' metrics (in :data:`SCORES` order)."""
    return [s for k, s in SCORES.items() if episodes and k in episodes[0]]


def _rliable():
    try:
        from rliable import library, metrics, plot_utils
    except ImportError as exc:  # the evaluation extra is not installed
        raise ImportError(INSTALL_HINT) from exc
    return library, metrics, plot_utils


@contextlib.contextmanager
def seeded_global_rng(seed: int) -> Iterator[None]:
    """NumPy's legacy global generator seeded with ``seed`` inside the block, its state restored after
    (rliable's StratifiedBootstrap draws from it whatever random_state it is given)."""
    state = np.random.get_state()
    np.random.seed(int(seed) % 2 ** 32)
    try:
        yield
    finally:
        np.random.set_state(state)


def score_matrix(runs: Sequence[Sequence[dict]], key: str) -> np.ndarray:
    """(runs, episodes) matrix of ``key`` from each run's episode list; every run must have flown the same
    episodes (seeds) in the same order, and every value must be finite."""
    if not runs or not runs[0]:
        raise ValueError("a score matrix needs at least one run with at least one episode")
    seeds = [e["seed"] for e in runs[0]]
    for r in runs[1:]:
        if [e["seed"] for e in r] != seeds:
            raise ValueError("every run must fly the same episodes (seeds) in the same order")
    m = np.array([[float(e[key]) for e in r] for r in runs])
    if not np.all(np.isfinite(m)):
        raise ValueError(f"score {key!r} has non-finite values; the aggregates need finite scores")
    return m


def _check(n_boot: int, confidence: float) -> None:
    if isinstance(n_boot, bool) or not isinstance(n_boot, (int, np.integer)) or n_boot < 1:
        raise ValueError(f"n_boot must be an integer >= 1, got {n_boot!r}")
    if isinstance(confidence, bool) or not isinstance(confidence, (int, float)) or not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be a number in (0, 1), got {confidence!r}")


def _estimates(matrix: np.ndarray, func, *, n_boot: int, confidence: float, seed: int, task_bootstrap: bool = True):
    library, _, _ = _rliable()
    with seeded_global_rng(seed):
        point, ci = library.get_interval_estimates({"x": matrix}, func, reps=n_boot, task_bootstrap=task_bootstrap,
                                                   confidence_interval_size=confidence)
    return np.asarray(point["x"], float), np.asarray(ci["x"], float)


def aggregate(scores, statistics: Sequence[str] = ("iqm", "mean", "median"), *, n_boot: int = N_BOOT,
              confidence: float = CONFIDENCE, seed: int = 0, task_bootstrap: bool = True) -> dict:
    """``{statistic: {"value", "ci": [low, high]}}`` of a (runs, episodes) score matrix: rliable's IQM,
    mean and median with stratified bootstrap intervals over runs x episodes (module docstring). With
    ``task_bootstrap=False`` the columns stay fixed and only the runs within each are resampled
    (rliable's default for a fixed suite of tasks: the cross-task table of a (runs, tasks) matrix)."""
    _, metrics, _ = _rliable()
    funcs = {"iqm": metrics.aggregate_iqm, "mean": metrics.aggregate_mean, "median": metrics.aggregate_median}
    unknown = [s for s in statistics if s not in funcs]
    if unknown or not statistics:
        raise ValueError(f"statistics must be some of {sorted(funcs)}, got {list(statistics)!r}")
    _check(n_boot, confidence)
    m = np.asarray(scores, dtype=float)
    if m.ndim != 2 or 0 in m.shape:
        raise ValueError(f"scores must be a (runs, episodes) matrix, got shape {m.shape}")
    point, ci = _estimates(m, lambda x: np.array([funcs[s](x) for s in statistics]), n_boot=n_boot,
                           confidence=confidence, seed=seed, task_bootstrap=task_bootstrap)
    return {s: {"value": float(point[i]), "ci": [float(ci[0, i]), float(ci[1, i])]} for i, s in enumerate(statistics)}


def _poi_stacked(stacked: np.ndarray) -> np.ndarray:
    """P(X > Y) + P(X = Y) / 2 of a (runs, episodes, 2) stack [X, Y]: per episode over all run pairs,
    averaged over episodes (rliable's probability_of_improvement, vectorised)."""
    x, y = stacked[..., 0][:, None, :], stacked[..., 1][None, :, :]
    per_episode = np.mean(x > y, axis=(0, 1)) + 0.5 * np.mean(x == y, axis=(0, 1))
    return np.array([np.mean(per_episode)])


def probability_of_improvement(x, y, *, higher_is_better: bool = True, n_boot: int = N_BOOT,
                               confidence: float = CONFIDENCE, seed: int = 0) -> dict:
    """``{"value", "ci"}``: the probability that policy X scores better than policy Y on an episode
    (rliable's, paired by episode; "better" is higher unless ``higher_is_better`` is False). ``x`` and
    ``y``: (runs, episodes) matrices on the same episodes; one of them may have one run (a baseline
    controller), else they need the same number."""
    _, metrics, _ = _rliable()
    _check(n_boot, confidence)
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if x.ndim != 2 or y.ndim != 2 or x.shape[1] != y.shape[1] or 0 in x.shape or 0 in y.shape:
        raise ValueError(f"x and y must be (runs, episodes) matrices on the same episodes, got {x.shape} and {y.shape}")
    if not higher_is_better:
        x, y = -x, -y
    n = max(len(x), len(y))
    if {len(x), len(y)} - {1, n}:
        raise ValueError(f"runs must agree or one side have a single run, got {len(x)} and {len(y)}")
    point = float(metrics.probability_of_improvement(x, y))
    stacked = np.stack([np.repeat(x, n // len(x), axis=0), np.repeat(y, n // len(y), axis=0)], axis=-1)
    _, ci = _estimates(stacked, _poi_stacked, n_boot=n_boot, confidence=confidence, seed=seed)
    return {"value": point, "ci": [float(ci[0, 0]), float(ci[1, 0])]}


def tau_grid(score_dict: Mapping[str, np.ndarray], score: Score, n: int = 101) -> np.ndarray:
    """Thresholds spanning every policy's scores: log-spaced for a log-scale score, else linear."""
    pooled = np.concatenate([np.ravel(v) for v in score_dict.values()])
    lo, hi = float(pooled.min()), float(pooled.max())
    if score.log_scale and lo > 0:
        return np.geomspace(lo, hi if hi > lo else lo * 10.0, n)
    return np.linspace(lo, hi if hi > lo else lo + 1.0, n)


def performance_profiles(score_dict: Mapping[str, np.ndarray], taus, *, higher_is_better: bool = True,
                         n_boot: int = N_BOOT, confidence: float = CONFIDENCE, seed: int = 0) -> tuple[dict, dict]:
    """``(profiles, cis)``: for every policy the fraction of its runs x episodes with a score above tau
    (below, when lower is better) at every tau, and the (2, len(taus)) stratified bootstrap interval
    (``rliable.library.create_performance_profile``, each policy drawn from ``seed``)."""
    library, _, _ = _rliable()
    _check(n_boot, confidence)
    taus = np.asarray(taus, dtype=float)

    def profile(scores, tau_list):
        s = np.asarray(scores)[..., None]
        better = s > tau_list if higher_is_better else s < tau_list
        return better.reshape(-1, len(tau_list)).mean(axis=0)

    profiles, cis = {}, {}
    for name, m in score_dict.items():
        with seeded_global_rng(seed):
            p, c = library.create_performance_profile({name: np.asarray(m, float)}, taus, custom_profile_func=profile,
                                                      task_bootstrap=True, reps=n_boot,
                                                      confidence_interval_size=confidence)
        profiles[name], cis[name] = np.asarray(p[name], float), np.asarray(c[name], float)
    return profiles, cis


def plot_profiles(path, panels: Sequence[dict], *, title: str, overwrite: bool = False) -> Path:
    """One panel per score (``{"score": Score, "taus", "profiles", "cis"}``) drawn with rliable's
    ``plot_performance_profiles``; written atomically, refusing an existing file unless ``overwrite``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from formation_env.io import atomic_write

    _, _, plot_utils = _rliable()
    fig, axes = plt.subplots(1, len(panels), figsize=(max(7.0, 6.0 * len(panels)), 4.4), squeeze=False)
    for ax, p in zip(axes[0], panels):
        s = p["score"]
        plot_utils.plot_performance_profiles(
            p["profiles"], p["taus"], performance_profile_cis=p["cis"], ax=ax, xlabel=f"{s.label}, tau",
            ylabel=f"fraction of runs x episodes with score {'>' if s.higher_is_better else '<'} tau",
            labelsize="medium", ticklabelsize="small")
        if s.log_scale:
            ax.set_xscale("log")
        ax.legend(fontsize=8)
    fig.suptitle(title + "\nperformance profiles, 95 % stratified bootstrap bands (runs x episodes)", fontsize=9)
    fig.tight_layout()
    out = atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=110, format="png"), overwrite=overwrite)
    plt.close(fig)
    return out


def normalised_score(score: Score, values, reference: float | None = None) -> np.ndarray:
    """A score on a common scale for a comparison across tasks (0 = the thesis PID's level, 1 = perfect):
    the RMS slot error as 1 - RMS / ``reference`` (the PID's mean RMS on that task, the Atari
    human-normalised convention with the PID as the reference); the success (0/1) and the harvest ratio
    (already a fraction of the reference optimum) unchanged."""
    v = np.asarray(values, dtype=float)
    if score.higher_is_better:
        return v
    if reference is None or not np.isfinite(reference) or reference <= 0:
        raise ValueError(f"normalising {score.key!r} needs the baseline's mean (> 0), got {reference!r}")
    return 1.0 - v / float(reference)


def evaluation_aggregates(episodes: Mapping[str, list[dict]], groups: Mapping[str, Sequence[str]],
                          baselines: Sequence[str], *, n_boot: int = N_BOOT, confidence: float = CONFIDENCE,
                          seed: int = 0) -> dict:
    """The rliable aggregates of one evaluation: every seed group of two or more policies ({group:
    [policy names]}) and every baseline (one run), for each of the task's scores: ``aggregate`` per
    policy, ``probability_of_improvement`` of each group over each baseline and of each later baseline
    over each earlier one, and the performance-profile data. {} without a group of two or more runs."""
    multi = {g: list(m) for g, m in groups.items() if len(m) >= 2}
    if not multi:
        return {}
    entries = {**{g: [episodes[n] for n in m] for g, m in multi.items()}, **{b: [episodes[b]] for b in baselines}}
    first = next(iter(entries.values()))[0]
    out = {"scores": {}, "statistics": {
        "library": "rliable", "confidence": confidence, "n_boot": n_boot, "bootstrap_seed": seed,
        "bootstrap": "stratified (task_bootstrap=True): episodes resampled, and the runs within each episode",
        "interval": "percentile", "probability_of_improvement": "P(X better) + P(tie) / 2 per episode over run "
        "pairs, averaged over episodes (paired by episode)"}}
    for score in scores_of(first):
        mats = {name: score_matrix(runs, score.key) for name, runs in entries.items()}
        pols = {name: {"runs": int(m.shape[0]), "episodes": int(m.shape[1]),
                       **aggregate(m, score.statistics, n_boot=n_boot, confidence=confidence, seed=seed)}
                for name, m in mats.items()}
        pairs = [(g, b) for g in multi for b in baselines] + [(b2, b1) for i, b1 in enumerate(baselines)
                                                              for b2 in baselines[i + 1:]]
        poi: dict[str, dict] = {}
        for cand, base in pairs:
            poi.setdefault(cand, {})[base] = probability_of_improvement(
                mats[cand], mats[base], higher_is_better=score.higher_is_better, n_boot=n_boot, confidence=confidence,
                seed=seed)
        entry = {"label": score.label, "higher_is_better": score.higher_is_better, "policies": pols,
                 "probability_of_improvement": poi}
        if "iqm" in score.statistics:  # a continuous score: its performance profile
            taus = tau_grid(mats, score)
            prof, cis = performance_profiles(mats, taus, higher_is_better=score.higher_is_better, n_boot=n_boot,
                                             confidence=confidence, seed=seed)
            entry["profile"] = {"taus": taus.tolist(), "profiles": {k: v.tolist() for k, v in prof.items()},
                                "cis": {k: v.tolist() for k, v in cis.items()}}
        out["scores"][score.key] = entry
    return out


def profile_panels(agg: dict) -> list[dict]:
    """The performance-profile panels of :func:`evaluation_aggregates`' result, for :func:`plot_profiles`."""
    return [{"score": SCORES[k], "taus": np.asarray(e["profile"]["taus"]),
             "profiles": {n: np.asarray(v) for n, v in e["profile"]["profiles"].items()},
             "cis": {n: np.asarray(v) for n, v in e["profile"]["cis"].items()}}
            for k, e in agg.get("scores", {}).items() if "profile" in e]


def _ci(v: dict, fmt: str) -> str:
    return f"{fmt.format(v['value'])} [{fmt.format(v['ci'][0])}, {fmt.format(v['ci'][1])}]"


def aggregates_table(agg: dict, fmt: str = "{:.3f}") -> str:
    """Markdown: per score, the IQM / mean / median [95 % CI] of every policy (runs x episodes) and the
    probability of improvement of each policy over each baseline."""
    if not agg or "scores" not in agg:
        return ""
    lines = []
    for key, e in agg["scores"].items():
        stats = [s for s in ("iqm", "mean", "median") if s in next(iter(e["policies"].values()))]
        names = {"iqm": "IQM", "mean": "mean", "median": "median"}
        lines += [f"{e['label']} ({'higher' if e['higher_is_better'] else 'lower'} is better):", "",
                  "| policy | runs x episodes | " + " | ".join(f"{names[s]} [95 % CI]" for s in stats) + " |",
                  "|---|---|" + "---|" * len(stats)]
        for n, p in e["policies"].items():
            lines.append(f"| {n} | {p['runs']} x {p['episodes']} | " + " | ".join(_ci(p[s], fmt) for s in stats) + " |")
        lines += ["", "| policy | baseline | probability of improvement [95 % CI] |", "|---|---|---|"]
        for c, per in e["probability_of_improvement"].items():
            for b, v in per.items():
                lines.append(f"| {c} | {b} | {_ci(v, '{:.3f}')} |")
        lines.append("")
    return "\n".join(lines)
