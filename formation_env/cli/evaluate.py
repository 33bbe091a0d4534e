"""``formation-env evaluate``: compare policies (SB3 zips, RLlib checkpoints, the thesis PID and the
classical formation-keeping PID) on held-out seeds with the wake and Dryden turbulence on; writes
results.json (summaries with 95 % intervals, paired comparisons against the baselines, seed groups and,
for policies trained with several seeds, rliable's IQM / mean / median over seeds x episodes with
stratified bootstrap intervals and the probability of improvement over each baseline), results.md,
comparison plots, the performance profiles (performance_profile.png) and marl_eval.json. With ``--task-report``, the
task's own evaluation instead (its baselines, ceilings, metrics and statistics: ``train.evaluation.task_eval``, for a
task that has one, e.g. wake_surfing)."""

from __future__ import annotations

import time

from ._args import (MAX_DURATION_S, MAX_EPISODES, bounded_int, check_min_duration, check_policy_scenario,
                    duration)


def _nonneg_float(text: str) -> float:
    import argparse
    import math

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number >= 0, got {text!r}") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {text!r}")
    return value


def register(sub) -> None:
    from train.config import ACTION_MODES, TEST_SEED_BASE
    from train.evaluation.evaluate import TEST_EPISODES

    from ..scenarios import scenario_names
    from ..sim.config import LEADER_REFERENCES, TURBULENCE_FIELD_ALIASES, TURBULENCE_FIELDS
    from ..wake.coupling import WAKE_FIDELITIES

    p = sub.add_parser("evaluate", help="evaluate policies against the PID baselines on held-out seeds (wake + turbulence)")
    p.add_argument("--policy", action="append", default=None,
                   help="an SB3 .zip, an RLlib checkpoint, 'pid' (thesis FCS), 'pid_formation' (classical "
                        "formation-keeping PID) or 'station_keeper' (cross-track station keeper); repeat to compare several side by side (policies named "
                        "<name>_seed<k> are also reported as a seed group)")
    p.add_argument("--scenario", required=True, help=f"one of {scenario_names()}")
    p.add_argument("--episodes", type=bounded_int(1, MAX_EPISODES), default=None,
                   help=f"episodes per policy, 1..{MAX_EPISODES} (default {TEST_EPISODES}, or the number of --seeds "
                        "when several are given; with several --seeds it must equal their number)")
    p.add_argument("--seeds", type=bounded_int(0, 2 ** 63 - 1), nargs="+", default=None,
                   help=f"one seed: the first of --episodes consecutive seeds; several: exactly one distinct seed "
                        f"per episode (then --episodes, if given, must match their count) "
                        f"(default {TEST_SEED_BASE}.., never used in training)")
    p.add_argument("--turbulence", type=_nonneg_float, nargs="+", default=None,
                   help="turbulence sigma, m/s, every axis (default 1; a task preset's own level, wake_surfing 0.25); "
                        "several levels (e.g. 0 0.5 1 1.5) evaluate each on the same seeds into OUT/sigma_<level>/ "
                        "and write the table over the levels (levels.md)")
    p.add_argument("--turbulence-field", default=None, choices=TURBULENCE_FIELDS + tuple(TURBULENCE_FIELD_ALIASES),
                   help="von_karman (default) or dryden: one frozen spatial field per formation; lanes (old name "
                        "frozen): the earlier Cholesky-mixed Dryden lanes; independent: one Dryden stream per UAV")
    p.add_argument("--no-wake", action="store_true", help="switch the ELL wake off (default on)")
    p.add_argument("--wake-fidelity", default=None, choices=WAKE_FIDELITIES,
                   help="how finely the ELL resolves the wake (default: the scenario's; converged in close_formation "
                        "and the N-UAV close formations, lattice elsewhere): lattice (the thesis's discrete legs), "
                        "sheet (the sheet law), converged (sheet law, span correction, residual table of pairs)")
    p.add_argument("--throttle-max", type=float, default=1.0,
                   help="the flight control's throttle ceiling for every UAV, 0.8..2 (default 1, the Aerosonde's full "
                        "throttle); above 1 a counterfactual engine, for measuring what thrust authority limits a "
                        "controller (a ceiling, not an aircraft)")
    p.add_argument("--leader-reference", default=None, choices=LEADER_REFERENCES,
                   help="how the leader's (vehicle 0's) reference moves (default: the scenario's; air in vee_rotation, "
                        "ground elsewhere): ground (the thesis's: the trim speed over the ground, a fixed altitude) or "
                        "air (carried along the track and vertically by the air the leader flies in)")
    p.add_argument("--benefit", action="store_true", help="also compute the ELL induced-drag saving (slow)")
    p.add_argument("--action-mode", default=None, choices=ACTION_MODES,
                   help="action mode of the zips when no sidecar JSON / config.yaml says it")
    p.add_argument("--duration", type=duration, default=None,
                   help=f"override the episode length, s (at least one physics step, at most {MAX_DURATION_S:g})")
    p.add_argument("--allow-scenario-mismatch", action="store_true",
                   help="evaluate a policy on a scenario other than the one it was trained for (its metadata's); "
                        "the observation sizes must still agree")
    p.add_argument("--ablate", action="append", default=None, metavar="GROUPS",
                   help="also fly every learned policy with these observation groups zeroed (comma-separated, from "
                        "air_data, attitude, rates, altitude, slot_position_error, slot_velocity_error, induced_wind, "
                        "induced_rotation, ambient_wind, engine, previous_action, slot_schedule, controller_state, "
                        "neighbours); repeat for several ablations")
    p.add_argument("--out", default=None, help="output directory (default runs/eval-<scenario>-<timestamp>)")
    p.add_argument("--overwrite", action="store_true", help="allow an existing non-empty output directory")
    p.add_argument("--no-plots", action="store_true", help="write no figures (results.json, results.md, marl_eval.json)")
    own = p.add_argument_group("a task's own evaluation (a task with evaluation hooks: wake_surfing and its variant)")
    own.add_argument("--task-report", action="store_true",
                     help="fly the task's own evaluation: its baselines and ceilings, each episode measured by the "
                          "task's metrics, the task's statistics (SB3 zips as --policy)")
    own.add_argument("--ceiling", action="append", default=None, metavar="SPEC",
                     help="a ceiling to fly beside the controllers (the task's specs, e.g. oracle_keeper:0.05; "
                          "default: the task's own); repeat for several, 'none' for none")
    own.add_argument("--figure", default=None, help="write the task's figure with the first policy here")
    own.add_argument("--tune", action="store_true", help="run the task's tuning sweep of a baseline instead")
    p.add_argument("--bootstrap-resamples", type=bounded_int(100, 1_000_000), default=None,
                   help="resamples of every bootstrap interval, 100..1000000 (default 10000)")
    p.set_defaults(func=run)


def _run_task_report(args) -> int:
    from train.evaluation.task_eval import run as run_task

    seeds = args.seeds if args.seeds and len(args.seeds) > 1 else (
        None if not args.seeds else [args.seeds[0] + i for i in range(args.episodes)])
    levels = args.turbulence or [None]
    if len(levels) > 1:
        raise ValueError("--task-report takes one --turbulence level")
    ceilings = None if args.ceiling is None else [c for c in args.ceiling if c != "none"]
    return run_task(args.policy or [], scenario=args.scenario, episodes=args.episodes, seeds=seeds,
                    turbulence_sigma_mps=levels[0], ceilings=ceilings, out=args.out, overwrite=args.overwrite,
                    figure=args.figure, tune=args.tune)


def run(args) -> int:
    from train.evaluation.evaluate import TEST_EPISODES, evaluate

    if not args.task_report and (args.ceiling or args.figure or args.tune):
        raise ValueError("--ceiling, --figure and --tune go with --task-report")
    if not args.policy and not args.task_report:
        raise ValueError("give at least one --policy")
    if args.episodes is not None and args.episodes < 1:
        raise ValueError(f"--episodes must be >= 1, got {args.episodes}")
    if args.seeds and len(set(args.seeds)) != len(args.seeds):
        dup = sorted({s for s in args.seeds if args.seeds.count(s) > 1})
        raise ValueError(f"--seeds: duplicate seed(s) {dup} (each seed is one episode)")
    if args.seeds and len(args.seeds) > 1:
        if args.episodes is not None and args.episodes != len(args.seeds):
            raise ValueError(f"--episodes {args.episodes} disagrees with the {len(args.seeds)} seeds given by --seeds "
                             "(give one --seeds value to start --episodes consecutive seeds, or leave out --episodes)")
        args.episodes = len(args.seeds)
    elif args.episodes is None:
        args.episodes = TEST_EPISODES
    from ..scenarios import get_scenario

    sc = get_scenario(args.scenario)  # unknown names fail before a policy loads
    if args.task_report:
        from pathlib import Path

        missing = [p for p in args.policy or [] if not Path(p).is_file()]
        if missing:
            raise ValueError(f"policy file {missing[0]!r} does not exist")
        return _run_task_report(args)
    if args.ablate:
        from train.evaluation.ablation import parse_ablation

        for a in args.ablate:
            parse_ablation(a)
    check_min_duration(args.duration, sc)
    for spec in args.policy:
        check_policy_scenario(spec, sc.name, allow=args.allow_scenario_mismatch)
    out = args.out or f"runs/eval-{args.scenario}-{time.strftime('%Y%m%d-%H%M%S')}"
    levels = args.turbulence or [None]
    if len(levels) > 1:
        if len(set(levels)) != len(levels):
            raise ValueError(f"--turbulence: duplicate level(s) in {levels}")
        from train.evaluation.levels import evaluate_levels

        res = evaluate_levels(args.policy, scenario=args.scenario, levels=levels, episodes=args.episodes,
                              seeds=args.seeds, wake=not args.no_wake, compute_benefit=args.benefit,
                              action_mode=args.action_mode, out_dir=out, overwrite=args.overwrite,
                              plots=not args.no_plots, duration_s=args.duration, turbulence_field=args.turbulence_field,
                              wake_fidelity=args.wake_fidelity, throttle_max=args.throttle_max,
                              leader_reference=args.leader_reference, ablations=args.ablate or (), log=print, **({} if args.bootstrap_resamples is None else {"n_boot": args.bootstrap_resamples}))
        print(res["table_markdown"])
        print(f"wrote {out}/levels.md, levels.json and " + ", ".join(f"sigma_{v:g}/" for v in levels))
        return 0
    rep = evaluate(args.policy, scenario=args.scenario, episodes=args.episodes, seeds=args.seeds,
                   turbulence_sigma_mps=levels[0], wake=not args.no_wake, compute_benefit=args.benefit,
                   action_mode=args.action_mode, out_dir=out, overwrite=args.overwrite, plots=not args.no_plots,
                   duration_s=args.duration, turbulence_field=args.turbulence_field, ablations=args.ablate or (),
                   wake_fidelity=args.wake_fidelity, throttle_max=args.throttle_max,
                   leader_reference=args.leader_reference, log=print,
                   **({} if args.bootstrap_resamples is None else {"n_boot": args.bootstrap_resamples}))
    print(rep["table_markdown"])
    if rep["comparison_markdown"]:
        print("paired comparisons (per-episode RMS slot error, reduction = baseline - policy):\n"
              + rep["comparison_markdown"])
    if rep["groups_markdown"]:
        print("training seeds:\n" + rep["groups_markdown"])
    agg = rep.get("aggregates") or {}
    if agg.get("scores"):
        print("aggregates over training seeds x episodes (rliable, 95 % stratified bootstrap):\n"
              + rep.get("aggregates_markdown", ""))
    files = ["results.json", "results.md"] + (["marl_eval.json"] if agg and "marl_eval" not in rep else [])
    if not args.no_plots:
        files += ["metrics.png", "slot_error.png"] + (["performance_profile.png"] if agg.get("scores") else [])
    print(f"wrote {out}/" + ", ".join(files))
    return 0


__all__ = ["register", "run"]
