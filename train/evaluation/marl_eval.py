"""Evaluation results in marl-eval's raw-data JSON format (InstaDeep's ``id-marl-eval``, the format
BenchMARL's JSON logger writes), so the multi-agent results load in its tools
(``marl_eval.utils.data_processing_utils.data_process_pipeline`` and ``create_matrices_for_rliable``)::

    {environment: {task: {algorithm: {run: {
        "step_0": {"step_count": <int>, "<metric>": [one value per evaluation episode]},
        "absolute_metrics": {"<metric>": [one value per evaluation episode]}}}}}}

Here: environment ``formation_env``, task = the scenario, algorithm = a seed group (``<name>_seed<k>``
policies: one run ``seed_<k>`` each) or a baseline controller, one logging step whose ``step_count`` is
the policy's training steps (its sidecar JSON's ``num_timesteps``; 0 for a baseline), and the held-out
evaluation episodes as the absolute metrics (marl-eval's "absolute metric" is the final policy's
performance on many evaluation episodes: this evaluation). The metrics are the per-episode values of
the evaluation, team-level (averaged over the learning UAVs), lower case, booleans as 0/1.

marl-eval requires the same number of runs for every algorithm of an environment: a deterministic
baseline controller (one run) is written as that many identical runs (``seed_0`` ..), which leaves any
bootstrap over runs unchanged for it. Groups with different numbers of seeds cannot share one file
(ValueError here; ``formation-env evaluate`` then writes no marl_eval.json and says so in results.json's
``marl_eval``, and evaluates every level as usual). marl-eval itself is not a dependency (its 0.0.4 sdist pins pandas 1.4.4 and does not
build here); the format is tested on fixed inputs (tests/train/test_marl_eval_export.py).
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

__all__ = ["ENVIRONMENT", "marl_eval_data", "write_marl_eval", "training_steps", "METRICS"]

ENVIRONMENT = "formation_env"
#: the per-episode metrics exported when the episodes have them (the evaluation's and wake surfing's)
METRICS = ("return", "rms_slot_error_m", "max_slot_error_m", "time_within_1m_frac", "min_separation_m", "collision",
           "crashed", "reconfig_success", "induced_drag_saving", "saving", "saving_ratio", "box_outside_frac")
_SEED = re.compile(r"_seed(\d+)$")


def training_steps(spec: str | None) -> int:
    """Training steps of a policy zip from its sidecar JSON (``num_timesteps``); 0 when unknown (a baseline)."""
    if not spec:
        return 0
    side = Path(spec).with_suffix(".json")
    try:
        return int(json.loads(side.read_text()).get("num_timesteps") or 0) if side.is_file() else 0
    except (OSError, ValueError, TypeError):
        return 0


def _values(episodes: Sequence[dict], key: str) -> list[float]:
    out = []
    for e in episodes:
        v = float(e[key])
        if not math.isfinite(v):
            raise ValueError(f"metric {key!r} of episode seed {e.get('seed')} is {v}: marl-eval needs finite values")
        out.append(v)
    return out


def _run(episodes: Sequence[dict], metrics: Sequence[str], step_count: int) -> dict:
    vals = {m: _values(episodes, m) for m in metrics}
    return {"step_0": {"step_count": int(step_count), **vals}, "absolute_metrics": {m: list(v) for m, v in vals.items()}}


def marl_eval_data(task: str, episodes: Mapping[str, Sequence[dict]], groups: Mapping[str, Sequence[str]],
                   baselines: Sequence[str], *, step_counts: Mapping[str, int] | None = None,
                   environment: str = ENVIRONMENT) -> dict:
    """The marl-eval dict of one evaluation: ``episodes`` {policy name: per-episode metric dicts, all on the
    same seeds}, ``groups`` {algorithm: [its seeds' policy names]} (each group one algorithm), ``baselines``
    (policy names written as one-run algorithms, repeated to the groups' run count), ``step_counts``
    {policy name: training steps} (default 0). Names are lower-cased (marl-eval does) and may not
    contain commas."""
    step_counts = dict(step_counts or {})
    groups = {g: list(m) for g, m in groups.items() if m}
    if not groups and not baselines:
        raise ValueError("nothing to export: give at least one group or baseline")
    n_runs = {len(m) for m in groups.values()} or {1}
    if len(n_runs) > 1:
        raise ValueError(f"marl-eval needs the same number of runs for every algorithm, the groups have {sorted(n_runs)}")
    n = n_runs.pop()
    names = [*groups, *baselines]
    bad = [a for a in names if "," in a]
    if bad:
        raise ValueError(f"marl-eval algorithm names may not contain commas: {bad}")
    if len({a.lower() for a in names}) != len(names):
        raise ValueError(f"algorithm names must differ in lower case: {names}")
    all_eps = [episodes[p] for m in groups.values() for p in m] + [episodes[b] for b in baselines]
    seeds = [e["seed"] for e in all_eps[0]]
    if any([e["seed"] for e in eps] != seeds for eps in all_eps):
        raise ValueError("every policy must fly the same episodes (seeds) in the same order")
    metrics = [m for m in METRICS if all(m in e for eps in all_eps for e in eps)]
    algos: dict[str, dict] = {}
    for g, members in groups.items():
        runs = {}
        for k, p in enumerate(members):
            m = _SEED.search(p)
            run = f"seed_{m.group(1)}" if m else f"seed_{k}"
            if run in runs:
                run = f"seed_{k}"
            runs[run] = _run(episodes[p], metrics, step_counts.get(p, 0))
        algos[g.lower()] = runs
    for b in baselines:
        one = _run(episodes[b], metrics, step_counts.get(b, 0))
        algos[b.lower()] = {f"seed_{k}": json.loads(json.dumps(one)) for k in range(n)}
    return {environment.lower(): {task.lower(): algos}}


def write_marl_eval(path, data: dict, *, overwrite: bool = False) -> Path:
    """Write :func:`marl_eval_data`'s dict as JSON, atomically, refusing an existing file unless ``overwrite``."""
    from formation_env.io import atomic_write_json

    return atomic_write_json(path, data, overwrite=overwrite)
