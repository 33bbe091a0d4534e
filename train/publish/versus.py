"""Two training recipes flown on the same held-out episodes, compared paired by episode on the task's headline metric:
e.g. SAC against PPO on close_formation, from one levels record (:mod:`train.publish.levels_record`) whose evaluation
flew both seed groups.

    formation-env publish versus RECORD.json CANDIDATE REFERENCE OUT.json [--overwrite]

``CANDIDATE`` and ``REFERENCE`` are seed groups of the record (its policies ``<group>_seed<k>``, e.g.
``close_formation_sac_setpoints`` and ``close_formation_ppo_setpoints``). Per turbulence level: the headline metric
(:attr:`formation_env.tasks.Task.evaluation`'s ``metric``) averaged over each group's training seeds episode by
episode, then paired by episode: ``difference`` = candidate - reference (positive: the candidate is higher) with its 95 % bootstrap interval (:func:`train.evaluation.stats.paired_comparison`, or
:func:`train.evaluation.stats.paired_rate_difference` for a 0/1 success); and rliable's probability that a candidate
run beats a reference run on an episode, with its stratified-bootstrap interval (runs and episodes resampled;
:func:`train.evaluation.aggregates.probability_of_improvement`).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

__all__ = ["versus", "main"]

N_BOOT = 10_000  # as the evaluation's paired comparisons


def _runs(episodes: dict, group: str, key: str) -> tuple[list[str], np.ndarray]:
    names = sorted(n for n in episodes if re.fullmatch(rf"{re.escape(group)}_seed\d+", n))
    if not names:
        raise ValueError(f"no policy {group}_seed<k> in the record (its policies: {sorted(episodes)})")
    missing = [n for n in names if key not in episodes[n]]
    if missing:
        raise ValueError(f"policies {missing} have no per-episode {key!r} in the record")
    return names, np.asarray([episodes[n][key] for n in names], dtype=float)


def versus(record: dict, candidate: str, reference: str, *, n_boot: int = N_BOOT) -> dict:
    """The comparison (module docstring) of every level of ``record`` (a one-task levels record)."""
    from formation_env.tasks import task_for_scenario

    from ..evaluation.aggregates import probability_of_improvement
    from ..evaluation.stats import paired_comparison, paired_rate_difference

    task = task_for_scenario(record.get("scenario"))
    if task is None:
        raise ValueError(f"the record's scenario {record.get('scenario')!r} is no task's: no headline metric")
    key, higher = task.evaluation.metric, task.evaluation.higher_is_better
    out = {"task": task.name, "metric": key, "higher_is_better": higher, "candidate": candidate,
           "reference": reference, "levels": {}}
    for level, data in record["by_level"].items():
        eps = data["episodes"]
        cand_names, cand = _runs(eps, candidate, key)
        ref_names, ref = _runs(eps, reference, key)
        if cand.shape[1] != ref.shape[1] or eps[cand_names[0]]["seed"] != eps[ref_names[0]]["seed"]:
            raise ValueError(f"{level}: the two groups did not fly the same episodes")
        a, b = cand.mean(axis=0), ref.mean(axis=0)  # seed-averaged, episode by episode
        if key == "reconfig_success":
            pc = paired_rate_difference(b, a, n_boot=n_boot)
            diff, ci = pc["difference"], pc["difference_ci"]
        else:
            pc = paired_comparison(b, a, n_boot=n_boot, lower_is_better=not higher)
            lo, hi = pc["mean_reduction_ci"]  # of reference - candidate
            diff, ci = -pc["mean_reduction"], [-hi, -lo]
        poi = probability_of_improvement(cand, ref, higher_is_better=higher, n_boot=n_boot)
        out["levels"][level] = {
            "turbulence_sigma_mps": data.get("turbulence_sigma_mps"), "n_episodes": int(cand.shape[1]),
            "candidate_runs": cand_names, "reference_runs": ref_names,
            "candidate_mean": float(a.mean()), "reference_mean": float(b.mean()),
            "difference": float(diff), "difference_ci": [float(ci[0]), float(ci[1])],
            "better": bool(ci[0] > 0 if higher else ci[1] < 0),  # the interval clear of zero on the better side
            "paired": pc, "probability_of_improvement": poi}
    return out


def write_versus(record_path, candidate: str, reference: str, out, *, overwrite: bool = False) -> dict:
    """:func:`versus` of the two groups of the one-task levels record at ``record_path``, written to ``out``
    (``formation-env publish versus``); the comparison."""
    from formation_env.io import atomic_write_json

    record = json.loads(Path(record_path).read_text())
    if "by_level" not in record:
        raise ValueError(f"{record_path} is not a one-task levels record (no 'by_level')")
    result = versus(record, candidate, reference)
    atomic_write_json(Path(out), result, overwrite=overwrite)
    return result
