"""The committed evaluation records as data: where each task's per-episode columns are in ``train/policies/``
(:data:`RECORDS`, from each task's ``evaluation.records``), how a record's controllers are grouped and named, and
:func:`collect`, which reads them. The results page (:mod:`train.publish.results_page`) and the absolute metric
(:mod:`train.publish.absolute`) compute every number they show from what this module reads."""

from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from formation_env.constants import AEROSONDE_SPAN_M
from formation_env.tasks import TASKS
from formation_env.tasks.base import ALGORITHM_LABELS

__all__ = ["REPO", "POLICIES", "N_BOOT", "SPAN_M", "CLASSICAL", "CEILINGS", "ALIASES", "RecordSource", "RECORDS",
           "collect"]

REPO = Path(__file__).resolve().parents[2]
POLICIES = REPO / "train" / "policies"
N_BOOT = 2000  # bootstrap resamples per interval: the intervals' own Monte Carlo error is below their last digit
SPAN_M = AEROSONDE_SPAN_M  # the unit of the slot errors on the page

#: the classical controllers (agents/): the baselines a learned policy is compared with
CLASSICAL = {"pid": "thesis PID", "pid_formation": "PID formation keeper", "station_keeper": "station keeper",
             "extremum_seeking": "extremum seeker"}
#: controllers told the optimum's position (ceilings, not baselines)
CEILINGS = {"oracle_keeper_margin0": "station keeper told the optimum (ceiling)",
            "oracle_keeper_margin0.05": "station keeper told the optimum, 0.05 b margin (ceiling)"}
#: record columns of a headline metric where a record names it otherwise
ALIASES = {"harvest_ratio": ("harvest_ratio", "saving_ratio"), "reconfig_success": ("reconfig_success",),
           "formation_saving": ("formation_saving",), "rms_slot_error_m": ("rms_slot_error_m",)}


@dataclass(frozen=True)
class RecordSource:
    """Where a task's episodes at one turbulence level are: ``file`` in train/policies, the ``path`` of keys to a
    mapping policy -> episodes (a list of episode dicts or a dict of columns)."""

    task: str
    sigma: float
    file: str
    path: tuple


#: every registered task's committed records (its EvaluationProtocol.records), one source per level
RECORDS: tuple[RecordSource, ...] = tuple(
    RecordSource(task.name, sigma, rec.file, rec.keys_at(sigma))
    for task in TASKS.values() for rec in task.evaluation.records for sigma in rec.levels)


def _columns(episodes) -> dict[str, np.ndarray]:
    if isinstance(episodes, dict) and "episodes" in episodes:
        episodes = episodes["episodes"]
    if isinstance(episodes, list):
        keys = episodes[0].keys() if episodes else ()
        return {k: np.asarray([e.get(k) for e in episodes], dtype=float) for k in keys
                if all(isinstance(e.get(k), (int, float, bool)) and e.get(k) is not None for e in episodes)}
    return {k: np.asarray(v, dtype=float) for k, v in episodes.items()
            if isinstance(v, list) and all(isinstance(x, (int, float, bool)) for x in v)}


def _group(name: str) -> str:
    return re.sub(r"_seed\d+$", "", name)


def _label(group: str, task: str) -> str:
    if group in CLASSICAL:
        return CLASSICAL[group]
    if group in CEILINGS:
        return CEILINGS[group]
    # the shortest task prefix: "vee5_recurrent_ppo_setpoints" is recurrent PPO on vee5, not PPO on "vee5_recurrent"
    m = re.match(r"(.+?)_(ppo|mappo|sac|td3|recurrent_ppo)_(setpoints|residual|surfaces)$", group)
    if m is None:
        return group
    trained_on, algo = m.group(1), m.group(2)
    label = ALGORITHM_LABELS[algo]
    return label if trained_on == task else f"{label} trained on {trained_on} (transfer)"


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()[:12]


def collect(sources=RECORDS, policies: Path | None = None) -> dict:
    """task -> sigma -> {"file", "digest", "runs": {group: {run name: columns}}}."""
    out: dict = {}
    for src in sources:
        path = (POLICIES if policies is None else policies) / src.file
        data = json.loads(path.read_text())
        for key in src.path:
            data = data[key]
        level = out.setdefault(src.task, {}).setdefault(src.sigma, {"files": {}, "runs": {}})
        level["files"][src.file] = _digest(path)
        for name, eps in data.items():
            cols = _columns(eps)
            if cols:
                level["runs"].setdefault(_group(name), {})[name] = cols
    return out


def _metric_key(cols: dict, metric: str) -> str | None:
    return next((k for k in ALIASES[metric] if k in cols), None)


def _matrix(runs: dict, key: str) -> np.ndarray | None:
    rows = [c[key] for _, c in sorted(runs.items()) if key in c]
    if not rows or len({len(r) for r in rows}) != 1:
        return None
    return np.vstack(rows)


def _fmt(v, ci=None, digits=3) -> str:
    if v is None or not np.isfinite(v):
        return "-"
    s = f"{v:.{digits}f}"
    return s if ci is None else f"{s} [{ci[0]:.{digits}f}, {ci[1]:.{digits}f}]"
