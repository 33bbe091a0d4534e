"""Copy a run's best model into ``train/policies/`` with its metadata and learning curve.

    formation-env publish run RUN_DIR NAME [--eval RESULTS_JSON] [--wall-s S] [--stopped-at STEPS]

Writes ``NAME.zip`` (the SB3 model), ``NAME.json`` (env/action mode, exact command, seed, steps, wall
time, validation and test numbers) and ``NAME_curve.csv`` (every training episode's return) and
``NAME_evaluations.json`` (validation at every evaluation). Never overwrites.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import yaml

from formation_env.io import atomic_write, atomic_write_json
from formation_env.sim.layout import OPTIONS as OBSERVATION_OPTIONS

POLICIES = Path(__file__).resolve().parents[1] / "policies"


def publish(run_dir: str | Path, name: str, *, eval_json: str | Path | None = None, wall_s: float | None = None,
            stopped_at: int | None = None, note: str | None = None, model: str = "best", guard: dict | None = None) -> Path:
    """``model`` "best" (the validation's choice) or "final" (the last model, with the last validation: for a run
    none of whose validations was free of collisions, where the selection rule has no best; say so in ``note``).
    ``guard``: the separation guard's gains the published policy flies with (its sidecar's ``env.action_guard``, e.g.
    ``{"clip_ramp": 0.25}``) instead of the run's own guard (a run trained with the guard in the loop only)."""
    if model not in ("best", "final"):
        raise ValueError(f"publish: model must be 'best' or 'final', got {model!r}")
    if guard is not None:
        from ..sb3.guard import guard_gains

        guard_gains(guard)  # unknown gains or bad values fail before anything is written
    run = Path(run_dir)
    cfg = yaml.safe_load((run / "config.yaml").read_text())
    best = json.loads((run / f"{model}_model.json").read_text())
    if model == "final":
        best["validation"] = json.loads((run / "evaluations.json").read_text())[-1]
    c = cfg["config"]
    if guard is not None:
        if not best.get("action_guard"):
            raise ValueError(f"publish: {run} was trained without the separation guard; a guard for its policy is a new "
                             "policy, train it with action_guard instead")
        best["action_guard"] = guard
    meta = {
        "env": {**{k: best[k] for k in ("algo", "scenario", "action_mode", "control_hz")},
                **({"action_guard": best["action_guard"]} if best.get("action_guard") else {}),
                **({"residual_on": best["residual_on"]} if best.get("residual_on") else {}),
                **{k: best[k] for k in ("observation", *OBSERVATION_OPTIONS) if best.get(k)},
                # the task and version it was trained on, and how the run departed from its benchmark configuration
                **{k: best[k] for k in ("task", "task_version", "departures") if k in best}},
        "command": cfg.get("command"),
        "seed": c["seed"],
        "num_timesteps": best["num_timesteps"],
        "run_steps": stopped_at,
        "wall_s": wall_s,
        "config": c,
        "validation": best["validation"],
        "note": note,
    }
    if eval_json is not None:
        rep = json.loads(Path(eval_json).read_text())
        meta["evaluation"] = {"seeds": rep["seeds"], "turbulence_sigma_mps": rep["turbulence_sigma_mps"], "wake": rep["wake"],
                              "summaries": {n: r["summary"] for n, r in rep["policies"].items()}}
    else:
        meta["evaluation"] = None
    atomic_write(POLICIES / f"{name}.zip", lambda p: shutil.copyfile(run / f"{model}_model.zip", p))
    atomic_write_json(POLICIES / f"{name}.json", meta)
    atomic_write(POLICIES / f"{name}_curve.csv", lambda p: shutil.copyfile(run / "curve.csv", p))
    atomic_write(POLICIES / f"{name}_evaluations.json", lambda p: shutil.copyfile(run / "evaluations.json", p))
    return POLICIES / f"{name}.zip"


def slim_evaluation(report: dict) -> dict:
    """An evaluation report without the per-decision series (``series``, ``saving_series``: 10 MB for five
    policies' 100 episodes; the per-episode scalar metrics, summaries, paired comparisons and seed groups are
    kept: enough to recompute every interval)."""
    out = {k: v for k, v in report.items() if k not in ("policies", "plots", "out_dir")}
    out["policies"] = {}
    for name, r in report["policies"].items():
        eps = [{k: v for k, v in e.items() if not k.endswith("series")} for e in r["episodes"]]
        out["policies"][name] = {**{k: v for k, v in r.items() if k != "episodes"}, "episodes": eps}
    return out


def attach_evaluation(names: list[str], eval_json: str | Path, record: str | Path, *, overwrite: bool = False,
                      meta_dir: str | Path | None = None) -> None:
    """Write the slim held-out evaluation to ``record`` (a new file unless ``overwrite``) and put each
    policy's summary and its paired comparisons into ``NAME.json``: read from ``train/policies/`` and
    written atomically to ``meta_dir`` (default: in place)."""
    rep = json.loads(Path(eval_json).read_text())
    slim = slim_evaluation(rep)
    atomic_write_json(record, slim, overwrite=overwrite)
    for name in names:
        meta = json.loads((POLICIES / f"{name}.json").read_text())
        meta_path = (POLICIES if meta_dir is None else Path(meta_dir)) / f"{name}.json"
        meta["evaluation"] = {"record": Path(record).name, "seeds": [rep["seeds"][0], rep["seeds"][-1]],
                              "episodes": len(rep["seeds"]), "turbulence_sigma_mps": rep["turbulence_sigma_mps"],
                              "wake": rep["wake"], "summary": rep["policies"][name]["summary"],
                              "comparisons": rep.get("comparisons", {}).get(name)}
        atomic_write_json(meta_path, meta, overwrite=True)


def plot_curves(names: list[str], out: str | Path, *, pid_validation: dict | None = None, bin_steps: int = 20_000) -> Path:
    """Learning curves of committed policies: training-episode return (binned mean) and validation
    RMS slot error against steps (``pid_validation``: {scenario: the PID's RMS on the validation seeds})."""
    import csv

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
    for i, name in enumerate(names):
        with (POLICIES / f"{name}_curve.csv").open() as fh:
            rows = np.array([[float(x) for x in r] for r in list(csv.reader(fh))[1:]])
        bins = (rows[:, 0] // bin_steps).astype(int)
        xs = [(b + 0.5) * bin_steps for b in np.unique(bins)]
        ys = [rows[bins == b, 1].mean() for b in np.unique(bins)]
        a1.plot(xs, ys, color=f"C{i}", label=name)
        ev = json.loads((POLICIES / f"{name}_evaluations.json").read_text())
        a2.plot([e["num_timesteps"] for e in ev], [e["rms_slot_error_m"] for e in ev], "o-", color=f"C{i}", label=name)
        scen = json.loads((POLICIES / f"{name}.json").read_text())["env"]["scenario"]
        if pid_validation and scen in pid_validation:
            a2.axhline(pid_validation[scen], color=f"C{i}", ls="--", label=f"PID ({scen})")
    a1.set_xlabel("environment steps")
    a1.set_ylabel(f"training episode return (mean per {bin_steps // 1000}k steps)")
    a2.set_xlabel("environment steps")
    a2.set_ylabel("validation RMS slot error (m), 32 held-out episodes")
    for a in (a1, a2):
        a.grid(True, alpha=0.3)
        a.legend(fontsize=8)
    fig.tight_layout()
    path = atomic_write(out, lambda p: fig.savefig(p, dpi=100, format="png"))
    plt.close(fig)
    return path


def plot_validation_curves(groups: dict[str, list[str]], out: str | Path, *, baselines: dict | None = None) -> Path:
    """One panel per task: the validation RMS slot error (32 held-out episodes, model selection) of
    each training seed against steps, with the baselines' RMS on the same episodes as lines
    (``baselines``: {task: {baseline name: RMS m}})."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(groups), figsize=(4.2 * len(groups), 3.6), squeeze=False)
    for ax, (task, names) in zip(axes[0], groups.items()):
        for i, name in enumerate(names):
            ev = json.loads((POLICIES / f"{name}_evaluations.json").read_text())
            steps = [e["num_timesteps"] / 1e6 for e in ev]
            ax.plot(steps, [e["rms_slot_error_m"] for e in ev], "o-", ms=3, color=f"C{i}",
                    label=f"PPO seed {name.rsplit('seed', 1)[-1]}")
        for j, (bname, value) in enumerate((baselines or {}).get(task, {}).items()):
            ax.axhline(value, color=("k", "0.5")[j % 2], ls=("--", ":")[j % 2], label=bname)
        ax.set_yscale("log")
        ax.set_title(task, fontsize=10)
        ax.set_xlabel("environment steps (millions)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    axes[0][0].set_ylabel("validation RMS slot error (m)")
    fig.tight_layout()
    path = atomic_write(out, lambda p: fig.savefig(p, dpi=100, format="png"), overwrite=True)
    plt.close(fig)
    return path
