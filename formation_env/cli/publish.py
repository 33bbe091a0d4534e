"""``formation-env publish``: the project's published results. ``run`` copies a training run into
train/policies/; ``levels`` writes the record of a multi-level evaluation; ``committed`` re-evaluates the committed
policies and draws the README figures; ``recompute`` recomputes the committed statistics from their episodes;
``ceilings`` measures what limits close-formation station keeping; ``records`` flies and writes the records of a
task with its own evaluation; ``versus`` pairs two recipes of one record by episode on the task's headline metric
(train/publish/, train/evaluation/ceilings.py)."""

from __future__ import annotations

import argparse
import json
import math

from ._args import MAX_EPISODES, OneLineArgumentParser, bounded_int, nonneg_int

_EPISODES = bounded_int(1, MAX_EPISODES)


def _wall_s(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"must be a number of seconds >= 0, got {text!r}")
    return value


def _sigma(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and 0.0 <= value <= 3.0):
        raise argparse.ArgumentTypeError(f"must be a number of m/s in [0, 3], got {text!r}")
    return value


def register(sub) -> None:
    p = sub.add_parser("publish", help="publish results: a run into train/policies/, evaluation records, the "
                                       "committed evaluation, its statistics, the ceilings table")
    actions = p.add_subparsers(dest="action", required=True, metavar="ACTION", parser_class=OneLineArgumentParser)

    r = actions.add_parser("run", help="copy a run's model into train/policies/NAME.* with its metadata, curve and "
                                       "validation history (an existing NAME is never overwritten: remove it first)")
    r.add_argument("run_dir", metavar="RUN_DIR", help="the run directory of `formation-env train`")
    r.add_argument("name", metavar="NAME", help="the published name (train/policies/NAME.zip, NAME.json, ...)")
    r.add_argument("--eval", default=None, metavar="RESULTS_JSON", help="an evaluation's results.json to attach")
    r.add_argument("--wall-s", type=_wall_s, default=None, help="the run's wall time, s (>= 0)")
    r.add_argument("--stopped-at", type=nonneg_int, default=None, metavar="STEPS", help="where the run was stopped")
    r.add_argument("--note", default=None, help="a note stored in NAME.json")
    r.add_argument("--model", choices=("best", "final"), default="best",
                   help="the validation's best model (default) or the final one")
    r.add_argument("--guard", default=None, metavar="JSON",
                   help="the separation guard's gains the published policy flies with, e.g. '{\"clip_ramp\": 0.25}' "
                        "(a run trained with the guard in the loop only)")
    r.set_defaults(func=run_publish)

    lv = actions.add_parser("levels", help="the record of a multi-level evaluation (`formation-env evaluate "
                                           "--turbulence 0 0.5 1 1.5 --out RESULTS_DIR`)")
    lv.add_argument("results_dir", metavar="RESULTS_DIR", help="the evaluation's --out (levels.json or results.json)")
    lv.add_argument("out_json", metavar="OUT.json", help="the record to write")
    lv.add_argument("--command", dest="eval_command", help="the evaluate command that made the results (stored in the record)")
    lv.add_argument("--overwrite", action="store_true",
                    help="replace OUT.json (with --task: replace its '_about' by --about; its records are kept)")
    lv.add_argument("--task", help="add the record to OUT.json's records[TASK] (a multi-task record, e.g. the N-UAV "
                                   "ones) instead of writing a one-record file")
    lv.add_argument("--about", help="with --task: what the multi-task record holds (required for a new file)")
    lv.set_defaults(func=run_levels)

    c = actions.add_parser("committed", help="evaluate the committed policies beside the PID baselines on the "
                                             "held-out episodes, attach the results and draw the README figures")
    c.add_argument("--out", default=None, help="output directory (default results/committed-eval): the evaluations, "
                                               "and without --overwrite also the records, metadata (policies/) and "
                                               "figures (figures/)")
    c.add_argument("--overwrite", action="store_true",
                   help="write the records, metadata and figures into train/policies/ and docs/figures/ (tracked)")
    c.add_argument("--episodes", type=_EPISODES, default=100,
                   help=f"held-out test episodes per policy, 1..{MAX_EPISODES} (default 100)")
    c.add_argument("--validation-episodes", type=_EPISODES, default=32,
                   help="validation episodes of the baselines' lines in training_curves.png (default 32)")
    c.add_argument("--tasks", nargs="+", default=None, metavar="TASK", help="the tasks (default every committed one)")
    c.set_defaults(func=run_committed)

    rc = actions.add_parser("recompute", help="recompute the committed evaluations' statistics from their stored "
                                              "episodes and compare every interval with the committed one")
    rc.add_argument("--out", required=True, help="a new (or empty) directory for the outputs")
    rc.add_argument("--n-boot", type=bounded_int(100, 10 ** 6), default=None,
                    help="bootstrap resamples, 100..1000000 (default the evaluation's)")
    rc.add_argument("--noise-seeds", type=bounded_int(2, 1000), default=8,
                    help="recomputations that measure the Monte-Carlo noise, 2..1000 (default 8)")
    rc.add_argument("--tasks", nargs="+", default=None, metavar="TASK", help="the tasks (default every committed one)")
    rc.set_defaults(func=run_recompute)

    ce = actions.add_parser("ceilings", help="the close-formation ceilings table: the station keeper flown with "
                                             "what a real controller does not have (more thrust, faster decisions, "
                                             "a preview of the disturbance)")
    ce.add_argument("--episodes", type=bounded_int(1, 1000), default=100, help="episodes, 1..1000 (default 100)")
    ce.add_argument("--seed", type=nonneg_int, default=None,
                    help="the first of --episodes consecutive seeds (default the held-out test seeds)")
    ce.add_argument("--sigma", type=_sigma, default=1.0, help="turbulence sigma, m/s, 0..3 (default 1)")
    ce.set_defaults(func=run_ceilings)

    rs = actions.add_parser("records", help="fly committed zips in every setting of a task with its own evaluation "
                                            "(e.g. wake_surfing) and write their records into train/policies/")
    rs.add_argument("task", metavar="TASK", help="a task with its own evaluation (Task.evaluator)")
    rs.add_argument("episodes_dir", metavar="EPISODES_DIR", help="where the flown episodes are kept")
    rs.add_argument("zips", metavar="ZIP", nargs="+", help="the policies, named <group>_seed<k>.zip")
    rs.add_argument("--episodes", type=_EPISODES, default=100,
                    help=f"held-out episodes per setting, 1..{MAX_EPISODES} (default 100)")
    rs.add_argument("--out-dir", default="train/policies", help="where the records go (default train/policies)")
    rs.add_argument("--overwrite", action="store_true", help="replace existing records")
    rs.set_defaults(func=run_records)

    vs = actions.add_parser("versus", help="two recipes of one levels record paired by episode on the task's "
                                           "headline metric: the difference with its 95 %% interval and the "
                                           "probability of improvement")
    vs.add_argument("record", metavar="RECORD.json", help="a one-task levels record (publish levels) holding both")
    vs.add_argument("candidate", metavar="CANDIDATE", help="a seed group, e.g. close_formation_sac_setpoints")
    vs.add_argument("reference", metavar="REFERENCE", help="a seed group, e.g. close_formation_ppo_setpoints")
    vs.add_argument("out_json", metavar="OUT.json", help="the comparison's JSON")
    vs.add_argument("--overwrite", action="store_true", help="replace OUT.json")
    vs.set_defaults(func=run_versus)


def run_publish(args) -> int:
    from train.publish.publish import publish

    guard = None
    if args.guard is not None:
        try:
            guard = json.loads(args.guard)
        except json.JSONDecodeError as exc:
            raise ValueError(f"--guard must be a JSON object of GuardGains fields, got {args.guard!r} ({exc})") from None
    try:
        print(publish(args.run_dir, args.name, eval_json=args.eval, wall_s=args.wall_s, stopped_at=args.stopped_at,
                      note=args.note, model=args.model, guard=guard))
    except FileExistsError as exc:
        raise ValueError(f"{args.name} is already published ({exc.filename or exc}); remove its files first") from None
    return 0


def run_levels(args) -> int:
    from train.publish.levels_record import write_levels_record

    print(write_levels_record(args.results_dir, args.out_json, command=args.eval_command, overwrite=args.overwrite,
                              task=args.task, about=args.about))
    return 0


def run_committed(args) -> int:
    from train.publish.report_committed import DEFAULT_OUT, TASKS, report_committed

    return report_committed(args.out or DEFAULT_OUT, overwrite=args.overwrite, episodes=args.episodes,
                            validation_episodes=args.validation_episodes, tasks=args.tasks or TASKS)


def run_recompute(args) -> int:
    from train.evaluation.stats import N_BOOT
    from train.publish.recompute import TASKS, recompute

    return recompute(args.out, n_boot=args.n_boot or N_BOOT, noise_seeds=args.noise_seeds, tasks=args.tasks or TASKS)


def run_records(args) -> int:
    from train.publish.records import write_records

    for path in write_records(args.task, args.episodes_dir, args.zips, episodes=args.episodes, out_dir=args.out_dir,
                              overwrite=args.overwrite):
        print(f"wrote {path}")
    return 0


def run_versus(args) -> int:
    from train.publish.versus import write_versus

    result = write_versus(args.record, args.candidate, args.reference, args.out_json, overwrite=args.overwrite)
    for level, r in result["levels"].items():
        print(f"{level}: {result['metric']} {args.candidate} - {args.reference} = {r['difference']:+.4f} "
              f"[{r['difference_ci'][0]:+.4f}, {r['difference_ci'][1]:+.4f}], P(improvement) "
              f"{r['probability_of_improvement']['value']:.3f}")
    return 0


def run_ceilings(args) -> int:
    from train.evaluation.ceilings import ceilings_report

    print(ceilings_report(args.episodes, args.seed, args.sigma))
    return 0
