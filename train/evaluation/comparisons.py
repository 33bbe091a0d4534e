"""Paired comparisons of policies with the baselines on the same episodes, and seed groups (one
recipe trained with several seeds), on :mod:`train.evaluation.stats` (SciPy). The seed groups' rliable
aggregates (runs and episodes resampled together) are :mod:`train.evaluation.aggregates`'."""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np

from .stats import N_BOOT, paired_comparison, paired_rate_difference, seed_spread

__all__ = ["compare_episodes", "comparisons", "seed_groups", "group_report", "BASELINES"]

# the classical controllers every other policy is compared with, in order: each is also compared with the ones
# before it (pid_formation with the thesis PID; station_keeper, issue 24, with both)
BASELINES = ("pid", "pid_formation", "station_keeper")
_SEED_NAME = re.compile(r"^(?P<group>.+)_seed(?P<seed>\d+)$")
# the close-formation metrics compared when the episodes have them (issue 24): metric -> lower is better
_PRECISION_KEYS = {"rms_lateral_m": True, "rms_vertical_m": True, "harvest_ratio": False}
_PAIRED_KEYS = ("rms_slot_error_m", "reconfig_success", *_PRECISION_KEYS)


def _column(episodes: list[dict], key: str) -> np.ndarray:
    return np.array([float(e[key]) for e in episodes])


def _check_paired(a: list[dict], b: list[dict]) -> None:
    sa, sb = [e["seed"] for e in a], [e["seed"] for e in b]
    if sa != sb:
        raise ValueError("paired comparison needs the same episodes (seeds) in the same order")


def compare_episodes(baseline: list[dict], candidate: list[dict] | None = None, *,
                     candidate_values: dict[str, np.ndarray] | None = None, n_boot: int = N_BOOT, seed: int = 0) -> dict:
    """Paired comparison of a candidate with a baseline on the same episodes: ``rms_slot_error_m``
    (:func:`train.evaluation.stats.paired_comparison`, reduction = baseline - candidate in m) and, when the
    episodes have them, ``reconfig_success`` (:func:`train.evaluation.stats.paired_rate_difference`, candidate -
    baseline), ``rms_lateral_m`` / ``rms_vertical_m`` (reductions, m) and ``harvest_ratio`` (higher is better:
    its "reduction" baseline - candidate is negative where the candidate harvests more). The candidate is its episode list or, for a seed group, ``candidate_values``: the
    per-episode values (seed-averaged) keyed by metric."""
    if candidate is not None:
        _check_paired(baseline, candidate)
        candidate_values = {k: _column(candidate, k) for k in _PAIRED_KEYS if k in candidate[0]}
    assert candidate_values is not None
    out = {"rms_slot_error_m": paired_comparison(_column(baseline, "rms_slot_error_m"),
                                                 candidate_values["rms_slot_error_m"], n_boot=n_boot, seed=seed)}
    if "reconfig_success" in baseline[0] and "reconfig_success" in candidate_values:
        out["reconfig_success"] = paired_rate_difference(_column(baseline, "reconfig_success"),
                                                         candidate_values["reconfig_success"], n_boot=n_boot, seed=seed)
    for key, lower in _PRECISION_KEYS.items():
        if key in baseline[0] and key in candidate_values:
            out[key] = paired_comparison(_column(baseline, key), candidate_values[key], n_boot=n_boot, seed=seed,
                                         lower_is_better=lower)
    return out


def comparisons(episodes: dict[str, list[dict]], baselines: dict[str, str] | None = None, *,
                candidates: Sequence[str] | None = None, n_boot: int = N_BOOT, seed: int = 0) -> dict:
    """``{policy: {baseline: compare_episodes(...)}}`` for every candidate policy against every
    baseline present, and every baseline against the kinds before it in :data:`BASELINES` (pid_formation against
    pid; station_keeper against both). ``baselines`` maps the baseline kind ("pid", "pid_formation",
    "station_keeper") to its policy name (default: the names themselves, when evaluated);
    ``candidates`` defaults to every other policy except a baseline given twice ("pid-2"). Every
    bootstrap draws from ``default_rng(seed)``."""
    if baselines is None:
        baselines = {b: b for b in BASELINES if b in episodes}
    base_names = set(baselines.values())
    if candidates is None:
        candidates = [n for n in episodes if n not in base_names and not _is_duplicate_baseline(n, base_names)]
    out: dict[str, dict] = {}
    for name in candidates if baselines else ():
        out[name] = {b: compare_episodes(episodes[b], episodes[name], n_boot=n_boot, seed=seed) for b in baselines.values()}
    kinds = [k for k in BASELINES if k in baselines]
    for i, later in enumerate(kinds[1:], 1):
        cand = baselines[later]
        out[cand] = {baselines[k]: compare_episodes(episodes[baselines[k]], episodes[cand], n_boot=n_boot, seed=seed)
                     for k in kinds[:i]}
    return out


def _is_duplicate_baseline(name: str, base_names: set[str]) -> bool:
    """"pid-2" etc.: a baseline given twice (renamed by :func:`evaluate`) is not a candidate."""
    head, _, tail = name.rpartition("-")
    return head in base_names and tail.isdigit()


def seed_groups(names: Sequence[str]) -> dict[str, list[str]]:
    """Groups of policy names ``<group>_seed<k>`` with two or more members (in the given order)."""
    found: dict[str, list[str]] = {}
    for n in names:
        m = _SEED_NAME.match(n)
        if m:
            found.setdefault(m.group("group"), []).append(n)
    return {g: members for g, members in found.items() if len(members) >= 2}


def _scalar_metrics(summary: dict) -> list[str]:
    return [k for k, v in summary.items()
            if k not in ("episodes", "wall_s") and isinstance(v, (int, float)) and not isinstance(v, bool)]


def group_report(members: dict[str, dict], baselines: dict[str, list[dict]], *, n_boot: int = N_BOOT,
                 seed: int = 0) -> dict:
    """One policy trained with several seeds: ``members`` maps each seed's policy name to its
    ``{"summary", "episodes"}``. Returns ``policies``, ``n_seeds``, ``summary`` (for every scalar
    summary metric, :func:`train.evaluation.stats.seed_spread` of the seeds' values: mean, std, min, max, n),
    ``per_episode`` (the seed-averaged per-episode RMS error, and success when present) and
    ``comparisons`` ({baseline: compare_episodes} of the seed-averaged per-episode metrics)."""
    names = list(members)
    if not names:
        raise ValueError("a seed group needs at least one policy")
    first = members[names[0]]["episodes"]
    for n in names[1:]:
        _check_paired(first, members[n]["episodes"])
    keys = [k for k in _scalar_metrics(members[names[0]]["summary"]) if all(k in members[n]["summary"] for n in names)]
    summary = {k: seed_spread([members[n]["summary"][k] for n in names]) for k in keys}
    per_episode = {k: np.mean([_column(members[n]["episodes"], k) for n in names], axis=0)
                   for k in _PAIRED_KEYS if k in first[0]}
    comps = {b: compare_episodes(eps, candidate_values=per_episode, n_boot=n_boot, seed=seed) for b, eps in baselines.items()}
    return {"policies": names, "n_seeds": len(names), "summary": summary,
            "per_episode": {k: v.tolist() for k, v in per_episode.items()}, "comparisons": comps}
