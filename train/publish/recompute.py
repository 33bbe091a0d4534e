"""Recompute the committed evaluations' statistics from their stored per-episode data with the library
estimators (SciPy for the per-policy and paired intervals, rliable for the aggregates over training
seeds x episodes), compare every interval with the one committed, and write the aggregates, the
performance profiles and marl-eval JSON. Nothing is simulated again and nothing tracked is written.

    formation-env publish recompute --out DIR [--n-boot 10000] [--noise-seeds 8]

The Monte-Carlo noise of an interval end is the standard deviation of that end over ``--noise-seeds``
recomputations with other bootstrap seeds (same estimator, same data); the committed end and the
recomputed one (seed 0) are two independent draws, so their difference is scored as
z = (new - old) / (sqrt(2) sd). Exact quantities (Wilson intervals, sign-test p-values, point values)
are compared as absolute differences. Outputs in DIR: ``recompute.json`` (every interval old / new / sd /
z, the aggregates of each task, the cross-task aggregates), ``recompute.md`` (the tables),
``<task>_performance_profile.png`` and ``<task>_marl_eval.json``.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np

from ..evaluation.aggregates import (SCORES, aggregate, aggregates_table, evaluation_aggregates, normalised_score,
                                     plot_profiles, probability_of_improvement, profile_panels)
from ..evaluation.comparisons import comparisons, group_report
from ..evaluation.marl_eval import marl_eval_data, training_steps, write_marl_eval
from ..evaluation.stats import N_BOOT
from ..evaluation.summary import summarise
from ..evaluation import stats as _stats
from ..evaluation.task_eval import task_groups
from formation_env.tasks import TASKS as _TASKS

from . import publish

#: each task with a committed PPO evaluation record, and its score in the cross-task table (normalised by
#: :func:`normalised_score`): what the tasks declare (``EvaluationProtocol.ppo_record_score``), in the registry's order
HEADLINE = {name: task.evaluation.ppo_record_score for name, task in _TASKS.items()
            if task.evaluation.ppo_record_score is not None}
TASKS = tuple(HEADLINE)


def _evaluator(task: str):
    """The task's own evaluation hooks (None: the generic evaluation's record)."""
    from formation_env.tasks import get_task

    return get_task(task).evaluator


def _own_policies(rec: dict, eps: dict) -> list[str]:
    """The policies of a task-evaluation record (its ``policy_specs``: neither a baseline nor a ceiling)."""
    return [n for n in eps if n in rec["policy_specs"]]


def record_path(task: str) -> Path:
    return publish.POLICIES / f"{task}_ppo_setpoints_evaluation.json"


def _episodes(rec: dict) -> dict[str, list[dict]]:
    pols = rec.get("policies") or rec["controllers"]
    return {n: r["episodes"] for n, r in pols.items()}


def recompute_statistics(task: str, rec: dict, *, n_boot: int = N_BOOT, seed: int = 0) -> dict:
    """The record's summaries and paired comparisons (and seed groups) recomputed from its episodes."""
    eps = _episodes(rec)
    ev = _evaluator(task)
    if ev is not None:  # a task with its own evaluation: its hooks' statistics
        names = _own_policies(rec, eps)
        return {"controllers": {n: {"summary": ev.summarise(e, _stats, n_boot=n_boot, seed=seed)} for n, e in eps.items()},
                "comparisons": ev.comparisons(eps, names, _stats, n_boot=n_boot, seed=seed)}
    baselines = rec["baselines"]
    cands = [n for n in eps if n not in baselines.values()]
    base_eps = {b: eps[b] for b in baselines.values()}
    members = {n: {"summary": summarise(e, n_boot=n_boot, seed=seed), "episodes": e} for n, e in eps.items()}
    return {"policies": {n: {"summary": m["summary"]} for n, m in members.items()},
            "comparisons": comparisons(eps, baselines, candidates=cands, n_boot=n_boot, seed=seed),
            "groups": {g: group_report({m: members[m] for m in r["policies"]}, base_eps, n_boot=n_boot, seed=seed)
                       for g, r in rec.get("groups", {}).items()}}


_SKIP = ("episodes", "per_episode", "profile", "seed_spread")
#: the exact (not resampled) values compared: point estimates and p-values
_EXACT = ("sign_test_p", "mean_reduction", "median_reduction", "relative_reduction_pct", "difference", "mean_gain",
          "median_gain", "rms_slot_error_m", "saving_ratio", "collision_rate", "reconfig_success_rate")


def _leaves(obj, path: tuple = ()) -> dict[tuple, object]:
    """Every interval (``*_ci`` pair) and exact value (:data:`_EXACT`) of a nested report, by path."""
    out = {}
    if isinstance(obj, dict):
        for k, v in obj.items():
            if k not in _SKIP:
                out.update(_leaves(v, (*path, k)))
    elif isinstance(obj, (list, tuple)) and path and str(path[-1]).endswith("_ci") and len(obj) == 2:
        out[path] = (float(obj[0]), float(obj[1]))
    elif isinstance(obj, (int, float)) and not isinstance(obj, bool) and path and str(path[-1]) in _EXACT:
        out[path] = float(obj)
    return out


def _exact(path: tuple) -> bool:
    """Wilson intervals (rates) are exact: no resampling."""
    return str(path[-1]) in ("collision_rate_ci", "reconfig_success_rate_ci")


def compare_intervals(task: str, rec: dict, *, n_boot: int, noise_seeds: int) -> dict:
    """Old vs new for every interval end and exact value of one record (module docstring)."""
    new = [_leaves(recompute_statistics(task, rec, n_boot=n_boot, seed=s)) for s in range(noise_seeds)]
    old = _leaves({k: rec[k] for k in ("policies", "controllers", "comparisons", "groups") if k in rec})
    rows = []
    for path, o in old.items():
        if path not in new[0]:
            continue
        draws = np.stack([np.atleast_1d(np.asarray(n[path], float)) for n in new])  # (seeds, ends)
        o = np.atleast_1d(np.asarray(o, float))
        row = {"path": "/".join(map(str, path)), "old": o.tolist(), "new": draws[0].tolist(),
               "diff": (draws[0] - o).tolist(), "kind": "exact"}
        if str(path[-1]).endswith("_ci") and not _exact(path):
            row.update(kind="interval", new_min=draws.min(axis=0).tolist(), new_max=draws.max(axis=0).tolist(),
                       noise=np.abs(draws[1:] - draws[0]).tolist())
        rows.append(row)
    return {"rows": rows, "summary": _noise_summary(rows, noise_seeds)}


def _noise_summary(rows: list[dict], k: int) -> dict:
    """|new - old| / width over every interval end, beside the same for two recomputations (new seed s vs
    seed 0: the Monte-Carlo noise itself), and how often the committed end lies outside the k recomputed
    ends (2 / (k + 1) expected for exchangeable draws, fewer with the ties of discrete ends)."""
    iv = [r for r in rows if r["kind"] == "interval" and all(math.isfinite(x) for x in r["old"])
          and r["old"][1] > r["old"][0]]
    d_old = np.array([abs(r["diff"][i]) / (r["old"][1] - r["old"][0]) for r in iv for i in range(2)])
    d_mc = np.array([abs(x) / (r["old"][1] - r["old"][0]) for r in iv for n in r["noise"] for x in n])
    outside = sum(int(r["old"][i] < r["new_min"][i] - 1e-12 or r["old"][i] > r["new_max"][i] + 1e-12)
                  for r in iv for i in range(2))
    ex = [r for r in rows if r["kind"] == "exact" and all(math.isfinite(x) for x in r["old"])]
    q = lambda a, p: float(np.percentile(a, p)) if a.size else 0.0  # noqa: E731
    return {"intervals": len(iv), "ends": int(d_old.size),
            "old_vs_new_over_width": {"median": q(d_old, 50), "p95": q(d_old, 95), "max": q(d_old, 100)},
            "new_vs_new_over_width": {"median": q(d_mc, 50), "p95": q(d_mc, 95), "max": q(d_mc, 100)},
            "ends_outside_recomputed_range": outside, "expected_outside": 2.0 * d_old.size / (k + 1),
            "exact": len(ex), "exact_max_abs_diff": float(max((abs(d) for r in ex for d in r["diff"]), default=0.0))}


def _step_counts(names) -> dict[str, int]:
    return {n: training_steps(str(publish.POLICIES / f"{n}.zip")) for n in names}


def task_aggregates(task: str, rec: dict, *, n_boot: int, seed: int = 0) -> tuple[dict, dict, dict]:
    """(aggregates, groups, marl-eval dict) of one record."""
    eps = _episodes(rec)
    ev = _evaluator(task)
    if ev is not None:
        groups, baselines = task_groups(_own_policies(rec, eps)), list(ev.baseline_names)
    else:
        groups = {g: r["policies"] for g, r in rec.get("groups", {}).items()}
        baselines = list(rec["baselines"].values())
    agg = evaluation_aggregates(eps, groups, baselines, n_boot=n_boot, seed=seed)
    data = marl_eval_data(task, eps, groups, baselines, step_counts=_step_counts([m for g in groups.values() for m in g]))
    return agg, groups, data


def cross_task(records: dict[str, dict], groups: dict[str, dict], *, n_boot: int, seed: int = 0) -> dict:
    """The committed recipe and the two PIDs across the tasks, on :func:`normalised_score` of each task's
    headline score: (runs, tasks) matrices of each run's mean normalised score, rliable's IQM / mean /
    median with the runs resampled within each task (rliable's default for a fixed suite), and the
    probability of improvement of PPO over each PID."""
    mats: dict[str, list[list[float]]] = {"ppo": [], "pid": [], "pid_formation": []}
    for task, rec in records.items():
        eps = _episodes(rec)
        score = SCORES[HEADLINE[task]]
        ref = float(np.mean([e[score.key] for e in eps["pid"]]))
        members = next(iter(groups[task].values()))
        col = {"ppo": [float(np.mean(normalised_score(score, [e[score.key] for e in eps[m]], ref))) for m in members],
               "pid": [float(np.mean(normalised_score(score, [e[score.key] for e in eps["pid"]], ref)))],
               "pid_formation": [float(np.mean(normalised_score(score, [e[score.key] for e in eps["pid_formation"]], ref)))]}
        for k, v in col.items():
            mats[k].append(v)
    m = {k: np.array(v).T for k, v in mats.items()}  # (runs, tasks)
    return {"tasks": list(records), "headline": {t: HEADLINE[t] for t in records},
            "scores": {k: v.tolist() for k, v in m.items()},
            "aggregates": {k: aggregate(v, n_boot=n_boot, seed=seed, task_bootstrap=False) for k, v in m.items()},
            "probability_of_improvement": {b: probability_of_improvement(m["ppo"], m[b], n_boot=n_boot, seed=seed)
                                           for b in ("pid", "pid_formation")}}


def markdown(result: dict) -> str:
    lines = ["# Committed evaluations recomputed with SciPy / rliable", "",
             "| task | intervals (ends) | committed vs recomputed end, % of width: median / 95th pct / max | "
             "recomputed vs recomputed (the Monte-Carlo noise): median / 95th pct / max | committed end outside the "
             "recomputed range (expected) | exact values (Wilson, p, points): max abs diff |", "|---|---|---|---|---|---|"]
    for task, r in result["tasks"].items():
        s = r["comparison"]["summary"]
        o, n = s["old_vs_new_over_width"], s["new_vs_new_over_width"]
        lines.append(f"| {task} | {s['intervals']} ({s['ends']}) | {100 * o['median']:.2f} / {100 * o['p95']:.2f} / "
                     f"{100 * o['max']:.2f} | {100 * n['median']:.2f} / {100 * n['p95']:.2f} / {100 * n['max']:.2f} | "
                     f"{s['ends_outside_recomputed_range']} ({s['expected_outside']:.1f}) | {s['exact_max_abs_diff']:.2g} |")
    for task, r in result["tasks"].items():
        lines += ["", f"## {task}", "", aggregates_table(r["aggregates"])]
    ct = result.get("cross_task")
    if ct:
        lines += ["", "## Across the tasks (normalised: 1 - RMS / PID mean RMS; success and harvest ratio as they are)",
                  "", "(runs x tasks of each run's mean normalised score; the runs resampled within each task, so a "
                  "one-run baseline has no interval here: its per-episode intervals are in the task tables)", "",
                  "| policy | runs x tasks | IQM [95 % CI] | mean [95 % CI] | median [95 % CI] |", "|---|---|---|---|---|"]
        for k, a in ct["aggregates"].items():
            runs = len(ct["scores"][k])
            lines.append(f"| {k} | {runs} x {len(ct['tasks'])} | " + " | ".join(
                f"{a[s]['value']:.3f}" + (f" [{a[s]['ci'][0]:.3f}, {a[s]['ci'][1]:.3f}]" if runs > 1 else "")
                for s in ("iqm", "mean", "median")) + " |")
        for b, v in ct["probability_of_improvement"].items():
            lines.append(f"\nP(PPO better than {b}) = {v['value']:.3f} [{v['ci'][0]:.3f}, {v['ci'][1]:.3f}]")
    return "\n".join(lines) + "\n"


def recompute(out: str | Path, *, n_boot: int = N_BOOT, noise_seeds: int = 8, tasks=TASKS) -> int:
    """``formation-env publish recompute``: the recomputation of the module docstring for ``tasks``, written to
    ``out`` (a new or empty directory); ``n_boot`` >= 100 bootstrap resamples, ``noise_seeds`` >= 2 recomputations
    that measure the Monte-Carlo noise. A bad value is a ValueError naming it, before anything is computed."""
    unknown = [t for t in tasks if t not in TASKS]
    if unknown:
        raise ValueError(f"--tasks: unknown task(s) {unknown}; the committed records are {list(TASKS)}")
    if n_boot < 100 or noise_seeds < 2:
        raise ValueError(f"need --n-boot >= 100 and --noise-seeds >= 2, got {n_boot} and {noise_seeds}")
    from formation_env.io import atomic_write_json, atomic_write_text, prepare_output_dir

    out = prepare_output_dir(out)
    records = {t: json.loads(record_path(t).read_text()) for t in tasks}
    result: dict = {"n_boot": n_boot, "noise_seeds": noise_seeds, "tasks": {}}
    groups = {}
    for task, rec in records.items():
        print(f"{task}: recomputing ...", file=sys.stderr)
        agg, groups[task], data = task_aggregates(task, rec, n_boot=n_boot)
        result["tasks"][task] = {"comparison": compare_intervals(task, rec, n_boot=n_boot, noise_seeds=noise_seeds),
                                 "aggregates": agg, "groups": groups[task]}
        write_marl_eval(out / f"{task}_marl_eval.json", data)
        plot_profiles(out / f"{task}_performance_profile.png", profile_panels(agg),
                      title=f"{task}: {len(rec['seeds'])} held-out episodes")
    if set(TASKS) <= set(records):
        result["cross_task"] = cross_task(records, groups, n_boot=n_boot)
    atomic_write_json(out / "recompute.json", result)
    text = markdown(result)
    atomic_write_text(out / "recompute.md", text)
    print(text)
    return 0

