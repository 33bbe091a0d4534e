"""``formation-env results``: docs/results.md and its marl-eval JSON, generated from the committed records.

Every number on the page is computed here from the per-episode columns of the records in ``train/policies/`` (the
held-out test episodes of each task's evaluation protocol, ``formation_env.tasks.Task.evaluation``): per task and
turbulence level, every learned policy (its training seeds pooled, one run each) and every classical baseline with
the task's headline metric as rliable's IQM (or the mean, for a 0/1 success) with its stratified-bootstrap 95 %
interval (runs and episodes resampled together), the mean, the lateral and vertical RMS slot errors in spans, the
collisions, and the probability of improvement over the best classical baseline on the same episodes. The record
each row comes from is named with the sha256 of its bytes, so a changed record changes the page. A test holds the
committed page equal to what this module writes; nothing on it is typed by hand.

The README's task table (between ``<!-- tasks:start -->`` and ``<!-- tasks:end -->``) is written from the same
numbers.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .absolute import absolute_episodes, absolute_markdown
from .record_data import (ALIASES, CEILINGS, CLASSICAL, N_BOOT, POLICIES, RECORDS, REPO, SPAN_M, RecordSource,
                          _columns, _digest, _fmt, _group, _label, _matrix, _metric_key, collect)

__all__ = ["RECORDS", "RecordSource", "collect", "results_markdown", "readme_table", "marl_eval_json",
           "write_results", "PAGE", "MARL_EVAL", "README"]

PAGE = REPO / "docs" / "results.md"
MARL_EVAL = REPO / "docs" / "results_marl_eval.json"
BENCH_JSON = REPO / "docs" / "bench.json"      # `formation-env bench --json > docs/bench.json` on an idle machine
PERFORMANCE = REPO / "docs" / "performance.md"
README = REPO / "README.md"
_ANCHORS = """Physical anchors for the savings: NASA's F/A-18 Autonomous Formation Flight measured about 12 % less
fuel for the trailing aircraft in flight; C-17 formation flight tests 7-10 %; Airbus's fello'fly more than 5 % per
trip. The benefit is sharp: a lateral error of a tenth of a span halves it, which is why the slot errors below are
given in spans."""


def _level_rows(task, level: dict) -> tuple[list[dict], str | None]:
    """Rows of one level's table (one per group) and the best classical baseline's group."""
    from train.evaluation.aggregates import aggregate, probability_of_improvement

    metric = task.evaluation.metric
    higher = task.evaluation.higher_is_better
    stat = "mean" if metric == "reconfig_success" else "iqm"
    rows = []
    for group, runs in level["runs"].items():
        any_cols = next(iter(runs.values()))
        key = _metric_key(any_cols, metric)
        m = None if key is None else _matrix(runs, key)
        if m is None:
            continue
        agg = aggregate(m, statistics=("iqm", "mean"), n_boot=N_BOOT, seed=0)
        lat = _matrix(runs, "rms_lateral_m")
        ver = _matrix(runs, "rms_vertical_m")
        col = _matrix(runs, "collision")
        rows.append({"group": group, "label": _label(group, task.name), "runs": m.shape[0], "episodes": m.shape[1],
                     "matrix": m, "names": [n for n, c in sorted(runs.items()) if key in c], "headline": agg[stat], "mean": agg["mean"]["value"],
                     "lateral_b": None if lat is None else float(np.sqrt(np.mean(lat ** 2)) / SPAN_M),
                     "vertical_b": None if ver is None else float(np.sqrt(np.mean(ver ** 2)) / SPAN_M),
                     "collisions": None if col is None else (int(col.sum()), int(col.size))})
    classical = [r for r in rows if r["group"] in CLASSICAL]
    best = None
    if classical:
        best = (max if higher else min)(classical, key=lambda r: r["headline"]["value"])
        for r in rows:
            if r is best or r["group"] in CLASSICAL or r["matrix"].shape[1] != best["matrix"].shape[1]:
                continue
            r["poi"] = probability_of_improvement(r["matrix"], best["matrix"], higher_is_better=higher, n_boot=N_BOOT,
                                                  seed=0)
    order = {g: i for i, g in enumerate(CLASSICAL)}
    rows.sort(key=lambda r: (r["group"] in CLASSICAL, r["group"] in CEILINGS, order.get(r["group"], 0), r["group"]))
    return rows, (best["group"] if best else None)


def _table(task, level: dict) -> tuple[str, list[dict], str | None]:
    from formation_env.tasks import HEADLINE_METRICS

    rows, best = _level_rows(task, level)
    metric = task.evaluation.metric
    stat = "mean" if metric == "reconfig_success" else "IQM"
    lines = [f"| controller | runs x episodes | {HEADLINE_METRICS[metric][0]}: {stat} [95 % CI] | mean | "
             "lateral RMS, b | vertical RMS, b | collisions | P(better than the best baseline) [95 % CI] |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        coll = "-" if r["collisions"] is None else f"{r['collisions'][0]} / {r['collisions'][1]}"
        poi = r.get("poi")
        name = r["label"] + (" (best baseline)" if r["group"] == best else "")
        lines.append(f"| {name} | {r['runs']} x {r['episodes']} | {_fmt(r['headline']['value'], r['headline']['ci'])} | "
                     f"{_fmt(r['mean'])} | {_fmt(r['lateral_b'])} | {_fmt(r['vertical_b'])} | {coll} | "
                     f"{_fmt(poi['value'], poi['ci'], 2) if poi else '-'} |")
    return "\n".join(lines), rows, best


def results_markdown(data: dict | None = None) -> tuple[str, dict]:
    """The page's markdown and, per task, the headline rows (for the README table and the marl-eval JSON)."""
    from formation_env.tasks import HEADLINE_METRICS, get_task

    data = collect() if data is None else data
    parts = ["# Results", "",
             "<!-- generated by `formation-env results` from the records in train/policies/; do not edit -->", "",
             "Every number on this page is computed from the per-episode records committed in `train/policies/`: the "
             "held-out test episodes of each task's evaluation protocol (seeds from 20,000,000,000 up, never used in "
             "training or model selection; 100 episodes per level). A learned policy's three training seeds are "
             "pooled as three runs; a classical baseline is one run. Intervals are stratified bootstrap 95 % "
             "intervals (runs and episodes resampled together; rliable). The probability of improvement compares "
             "each controller with the best classical baseline on the same episodes. Slot errors are in spans "
             f"(b = {SPAN_M} m). The raw data are the records themselves; `results_marl_eval.json` beside this page "
             "holds the headline metric in marl-eval's format.", "", _ANCHORS, ""]
    summary = {}
    for name, levels in data.items():
        task = get_task(name)
        ev = task.evaluation
        parts += [f"## {name}", "",
                  f"`{task.gym_id}` (task version {task.version}): {task.description}. Headline: "
                  f"{HEADLINE_METRICS[ev.metric][0]} at sigma {ev.headline_level:g} m/s "
                  f"({'higher' if ev.higher_is_better else 'lower'} is better).", ""]
        for sigma in sorted(levels, key=lambda s: (s != ev.headline_level, s)):
            level = levels[sigma]
            table, rows, best = _table(task, level)
            files = ", ".join(f"`{f}` (sha256 {d})" for f, d in sorted(level["files"].items()))
            parts += [f"### sigma {sigma:g} m/s", "", f"Records: {files}.", "", table, ""]
            if sigma == ev.headline_level:
                summary[name] = {"task": task, "rows": rows, "best": best, "sigma": sigma}
                parts += absolute_markdown(task, data)
        parts += versus_markdown(task)
    return "\n".join(parts).rstrip() + "\n", summary


def versus_markdown(task, policies: Path | None = None) -> list[str]:
    """The task's recipes paired against PPO (``formation-env publish versus`` records,
    ``<task>_<algo>_setpoints_versus_ppo.json``): per level the difference in the headline metric (seed-averaged,
    paired by episode) with its 95 % interval, and the probability that a run of the one beats a run of the other on
    an episode. No section where the task has none."""
    from formation_env.tasks import HEADLINE_METRICS, versus_records

    records = versus_records(POLICIES if policies is None else policies, task.name)
    if not records:
        return []
    metric = HEADLINE_METRICS[task.evaluation.metric][0]
    lines = ["### Against PPO", "",
             f"Each recipe's three training seeds against PPO's on the same held-out episodes: the {metric} averaged "
             "over the seeds episode by episode, the difference (recipe minus PPO) with its paired bootstrap 95 % "
             "interval, and the probability that a run of the recipe does better than a run of PPO on an episode "
             "(stratified bootstrap interval). Records: " + ", ".join(
                 f"`{f.name}` (sha256 {_digest(f)})" for f, _ in records) + ".", "",
             "| recipe | level | recipe | PPO | difference [95 % CI] | P(recipe better) [95 % CI] |",
             "|---|---|---|---|---|---|"]
    for f, r in records:
        label = _label(r["candidate"], task.name)
        for level, v in sorted(r["levels"].items(), key=lambda kv: kv[1]["turbulence_sigma_mps"]):
            poi = v["probability_of_improvement"]
            lines.append(f"| {label} | sigma {v['turbulence_sigma_mps']:g} | {v['candidate_mean']:.3f} | "
                         f"{v['reference_mean']:.3f} | {v['difference']:+.3f} [{v['difference_ci'][0]:+.3f}, "
                         f"{v['difference_ci'][1]:+.3f}] | {poi['value']:.2f} [{poi['ci'][0]:.2f}, {poi['ci'][1]:.2f}] |")
    return lines + [""]


def readme_table(summary: dict) -> str:
    """The README's task table: every registered id, its agents, what it poses, the best learned and classical
    headline numbers at the headline level (linked to the results page)."""
    from formation_env.tasks import HEADLINE_METRICS, TASKS

    lines = ["| id | agents | what it poses | best learned | best classical |", "|---|---|---|---|---|"]
    for t in TASKS.values():
        if not t.gym_id:
            continue
        sc = t.get_scenario()
        n = sc.n_vehicles
        agents = {"followers": f"{n - 1} follower(s) of {n}", "all": f"all {n}"}[t.learning] if n > 1 else "1"
        learned = classical = "-"
        s = summary.get(t.name)
        if s is not None:
            def cell(r):
                anchor = t.name
                return f"[{r['label']} {r['headline']['value']:.3f}](docs/results.md#{anchor})"

            learned_rows = [r for r in s["rows"] if r["group"] not in CLASSICAL and r["group"] not in CEILINGS
                            and "transfer" not in r["label"]]
            if learned_rows:
                key = (max if t.evaluation.higher_is_better else min)
                learned = cell(key(learned_rows, key=lambda r: r["headline"]["value"]))
            if s["best"] is not None:
                classical = cell(next(r for r in s["rows"] if r["group"] == s["best"]))
            metric = HEADLINE_METRICS[t.evaluation.metric][0].split(" (")[0]
            learned = f"{learned} ({metric}, sigma {s['sigma']:g})" if learned != "-" else learned
        lines.append(f"| `{t.gym_id}` | {agents} | {t.description} | {learned} | {classical} |")
    return "\n".join(lines)


def marl_eval_json(summary: dict) -> dict:
    """The headline metric of every controller in marl-eval's raw-data layout: env -> task -> algorithm -> run ->
    step -> {metric: [episode values]} (one evaluation step: the final policy)."""
    out: dict = {"formation_env": {}}
    for name, s in summary.items():
        metric = s["task"].evaluation.metric
        task_entry = out["formation_env"].setdefault(s["task"].gym_id, {})
        absolute = absolute_episodes(name)
        for r in s["rows"]:
            algo = task_entry.setdefault(r["label"], {})
            for i, row in enumerate(r["matrix"]):
                # the best seed's absolute metric is its flight on ten times the episodes, where recorded
                best = absolute.get((r["group"], r["names"][i]))
                best = row if best is None else best
                algo[f"{i}"] = {"step_0": {"step_count": 0, metric: [round(float(v), 6) for v in row]},
                                "absolute_metrics": {metric: [round(float(v), 6) for v in best]}}
    return out


def _replace_readme_table(text: str, table: str) -> str:
    start, end = "<!-- tasks:start -->", "<!-- tasks:end -->"
    if start not in text or end not in text:
        raise ValueError(f"README.md has no {start} ... {end} markers for the task table")
    head, rest = text.split(start, 1)
    _, tail = rest.split(end, 1)
    return f"{head}{start}\n{table}\n{end}{tail}"


def performance_markdown(bench: dict) -> str:
    """docs/performance.md from a ``formation-env bench --json`` file: the machine it ran on and every figure of
    the benchmark's own report (speed is a measurement of one machine on one day; ratios between codes measured in
    the same run are what transfers)."""
    import contextlib
    import io

    from formation_env.cli.bench import print_human

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        print_human(bench)
    m = bench.get("machine", {})
    envs = bench.get("envs") or {}
    against = []
    if envs.get("baseline"):
        commit = envs.get("baseline_commit")
        older = f"commit {commit}" if commit else "an older checkout"
        against = [f"A figure's ratio in brackets is this code over the code of {older} (`--baseline`), measured in "
                   "the same run on the same machine.", ""]
    return "\n".join([
        "# Performance", "",
        "<!-- generated by `formation-env results` from docs/bench.json; do not edit -->", "",
        "Measured by `make bench-peers OUT=docs/bench.json` (`formation-env bench --json --peers`, the peers VMAS and "
        "PyFlyt timed in the same run from a virtual environment of their own) on the machine below, nothing else "
        "running (speed on a shared or loaded machine swings by +-20 %; compare codes as ratios measured in the same "
        "run, `formation-env bench --baseline PATH`).", "",
        f"Machine: {m.get('cpus')} CPUs, Python {m.get('python')}, {m.get('platform')}.", "", *against,
        "```text", buf.getvalue().rstrip(), "```", ""])


def render() -> dict[Path, str]:
    """Every file the command writes and its content."""
    page, summary = results_markdown()
    files = {PAGE: page, MARL_EVAL: json.dumps(marl_eval_json(summary), indent=1, sort_keys=True) + "\n"}
    if BENCH_JSON.is_file():
        files[PERFORMANCE] = performance_markdown(json.loads(BENCH_JSON.read_text(encoding="utf-8")))
    text = README.read_text(encoding="utf-8") if README.is_file() else ""
    if "<!-- tasks:start -->" in text:
        files[README] = _replace_readme_table(text, readme_table(summary))
    return files


def write_results(check: bool = False) -> list[Path]:
    """Write (or with ``check``, compare) the generated files; returns those that differ (were rewritten)."""
    changed = []
    for path, text in render().items():
        old = path.read_text(encoding="utf-8") if path.is_file() else None
        if old == text:
            continue
        changed.append(path)
        if not check:
            tmp = path.with_suffix(path.suffix + ".tmp")
            tmp.write_text(text, encoding="utf-8")
            tmp.replace(path)
    return changed
