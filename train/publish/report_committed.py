"""Evaluate the committed policies (3 training seeds per task) beside the thesis PID and ``pid_formation``
on 100 held-out test episodes, attach the results to their metadata and draw the README figures.

    python -m train.publish.report_committed [--out results/committed-eval] [--episodes 100]

For each task: ``formation-env evaluate`` with the three seeds, ``pid`` and ``pid_formation`` (frozen
Dryden turbulence sigma 1 m/s, wake on, seeds 20000000000..), written to ``OUT/<task>/``; the slim record
(per-episode metrics, summaries, paired comparisons, seed groups) to
``train/policies/<task>_ppo_setpoints_evaluation.json``; each policy's ``NAME.json`` gets its summary and
comparisons. Figures: ``docs/figures/eval_<task>_slot_error.png`` and ``docs/figures/training_curves.png``
(validation curves with the baselines' RMS on the same 32 validation episodes).
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

from ..config import VALIDATION_SEED_BASE
from ..evaluate import evaluate
from .publish import POLICIES, attach_evaluation, plot_validation_curves

TASKS = ("formation_keeping", "close_formation", "reconfiguration")
FIGURES = Path(__file__).resolve().parents[2] / "docs" / "figures"


def policy_names(task: str) -> list[str]:
    return [f"{task}_ppo_setpoints_seed{k}" for k in range(3)]


def main() -> None:
    ap = argparse.ArgumentParser(prog="python -m train.publish.report_committed", description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/committed-eval")
    ap.add_argument("--episodes", type=int, default=100)
    ap.add_argument("--tasks", nargs="+", default=list(TASKS), choices=TASKS)
    a = ap.parse_args()
    out = Path(a.out)
    baselines = {}
    for task in a.tasks:
        names = policy_names(task)
        rep = evaluate([str(POLICIES / f"{n}.zip") for n in names] + ["pid", "pid_formation"], scenario=task,
                       episodes=a.episodes, out_dir=out / task, log=print)
        print(rep["table_markdown"])
        print(rep.get("comparison_markdown", ""))
        print(rep.get("groups_markdown", ""))
        record = POLICIES / f"{task}_ppo_setpoints_evaluation.json"
        attach_evaluation(names, out / task / "results.json", record)
        shutil.copyfile(out / task / "slot_error.png", FIGURES / f"eval_{task}_slot_error.png")
        val = evaluate(["pid", "pid_formation"], scenario=task, episodes=32, seeds=[VALIDATION_SEED_BASE],
                       plots=False)
        baselines[task] = {f"{n} (validation)": val["policies"][n]["summary"]["rms_slot_error_m"]
                           for n in ("pid", "pid_formation")}
    (out / "validation_baselines.json").write_text(json.dumps(baselines, indent=2))
    plot_validation_curves({t: policy_names(t) for t in a.tasks}, FIGURES / "training_curves.png", baselines=baselines)


if __name__ == "__main__":
    main()
