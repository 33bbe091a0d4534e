"""``formation-env replay``: fly one episode of a scenario and write its replay: Tacview ACMI 2.1
(``<scenario>.txt.acmi``), the episode log (``.npz``), a 3D trajectory figure, and with ``--gif`` an
animated 3D view (``<scenario>.gif``, with a progress display).

Who flies is ``--policy``: ``pid`` (the thesis FCS on every UAV, the scenario's own deterministic run;
the default), ``pid_formation`` (the classical formation-keeping PID on the followers), ``station_keeper``
(the cross-track station keeper on the followers), an SB3 ``.zip``
(its sidecar JSON / run config.yaml gives the action mode and the default scenario) or an RLlib
checkpoint directory (needs ray). Learned and ``pid_formation`` policies fly the evaluation episode
(:func:`train.evaluation.episodes.eval_env_config`: wake on, frozen Dryden turbulence ``--turbulence``) with
seed ``--seed``, so a replay is reproducible and matches ``formation-env evaluate --seeds SEED``.
"""

from __future__ import annotations

import json
import sys
import time

from ._args import (MAX_DURATION_S, MAX_GIF_FRAMES, bounded_int, check_min_duration, check_policy_scenario, duration,
                    nonneg_int, positive_int, trained_scenario)

DEFAULT_SEED = 20_000_000_000  # formation_env.tasks.TEST_SEED_BASE: the first held-out evaluation episode


def _nonneg_sigma(text: str) -> float:
    from .evaluate import _nonneg_float

    return _nonneg_float(text)


def register(sub) -> None:
    from ..scenarios import scenario_names

    p = sub.add_parser("replay", help="fly one episode (PID, pid_formation, station_keeper, an SB3 zip or an RLlib checkpoint) "
                                      "and export it for Tacview (ACMI), as a 3D figure and an animated GIF")
    p.add_argument("--scenario", default=None,
                   help=f"one of {scenario_names()} (required for pid / pid_formation / station_keeper; a policy zip's default "
                        "is the scenario it was trained on)")
    p.add_argument("--policy", default="pid", metavar="PATH|pid|pid_formation|station_keeper",
                   help="who flies: 'pid' (thesis FCS, default), 'pid_formation' (classical formation-keeping "
                        "PID), 'station_keeper' (cross-track station keeper), an SB3 .zip or an RLlib checkpoint directory")
    p.add_argument("--action-mode", default=None, choices=("surfaces", "residual", "setpoints"),
                   help="action mode of a zip without sidecar JSON / config.yaml")
    p.add_argument("--seed", type=nonneg_int, default=None,
                   help=f"episode seed of a learned / pid_formation replay (default {DEFAULT_SEED}, the first "
                        "held-out evaluation episode); refused with --policy pid, whose replay draws no random numbers")
    p.add_argument("--turbulence", type=_nonneg_sigma, default=None,
                   help="Dryden sigma, m/s, of a learned / pid_formation replay (default 1, as evaluate)")
    p.add_argument("--no-wake", action="store_true", help="fly without the ELL wake interaction")
    p.add_argument("--allow-scenario-mismatch", action="store_true",
                   help="fly a policy on a scenario other than the one it was trained for (equal observation sizes)")
    p.add_argument("--duration", type=duration, default=None,
                   help=f"override the scenario's duration, s (at least one physics step, at most {MAX_DURATION_S:g})")
    p.add_argument("--out", default=None, help="output directory (default results/replay-<scenario>-<timestamp>)")
    p.add_argument("--overwrite", action="store_true", help="allow writing into an existing non-empty directory")
    p.add_argument("--gif", action="store_true", help="also write an animated GIF (3D view with the wake legs)")
    p.add_argument("--stride", type=positive_int, default=1, help="write every N-th sample to the ACMI file (default 1)")
    p.add_argument("--max-frames", type=bounded_int(1, MAX_GIF_FRAMES), default=200,
                   help=f"GIF frames at most, 1..{MAX_GIF_FRAMES} (default 200)")
    bar = p.add_mutually_exclusive_group()
    bar.add_argument("--progress", dest="progress", action="store_true", default=None,
                     help="GIF progress bar (tqdm or rich when installed, else plain lines; default: on when stderr "
                          "is a terminal, else plain lines)")
    bar.add_argument("--no-progress", dest="progress", action="store_false", help="no GIF progress display")
    p.set_defaults(func=run)


def _progress(enabled: bool | None, total: int, desc: str):
    """A callable(i) for each rendered frame i (0-based) and a close(); tqdm, else rich, else plain
    lines on stderr (every 10 %)."""
    if enabled is False:
        return (lambda i: None), (lambda: None)
    if enabled or sys.stderr.isatty():
        try:
            from tqdm import tqdm

            bar = tqdm(total=total, desc=desc, unit="frame", file=sys.stderr)
            return (lambda i: bar.update(1)), bar.close
        except ImportError:
            pass
        try:
            from rich.console import Console
            from rich.progress import Progress

            prog = Progress(console=Console(stderr=True))
            task = prog.add_task(desc, total=total)
            prog.start()
            return (lambda i: prog.update(task, advance=1)), prog.stop
        except ImportError:
            pass
    marks = {max(1, round(total * k / 10)) for k in range(1, 11)}

    def line(i: int) -> None:
        if i + 1 in marks:
            print(f"{desc}: frame {i + 1}/{total} ({100 * (i + 1) // total} %)", file=sys.stderr, flush=True)

    return line, (lambda: None)


def _fly_policy(policy, scenario: str, *, seed: int, wake: bool, turbulence: float, duration_s):
    """One evaluation episode of ``policy`` (the rollout's Policy protocol) recorded at the decision rate."""
    from train.evaluation.episodes import eval_env_config

    from ..replay import EpisodeRecorder
    from ..rollout import Recorder, rollout
    from ..tasks.compose import task_simulation

    class _Replay(Recorder):
        def start(self, sim, out) -> None:
            self.log = EpisodeRecorder(sim)
            self.log.record()

        def after_step(self, sim, out, actions, alive, k) -> None:
            self.log.record()

    cfg = eval_env_config(scenario, policy.action_mode, turbulence_sigma_mps=turbulence, wake=wake,
                          control_hz=policy.control_hz, duration_s=duration_s,
                          observation=getattr(policy, "observation", None))  # the policy's optional groups
    sim = task_simulation(cfg, batch_size=1)  # a task's Python terms too (its policy observes them)
    rec = _Replay()
    res = rollout(sim, policy, [seed], recorders=[rec])
    status = "completed"
    if res.terminated[0]:
        what = "collision" if bool(res.collided[0]) else "a UAV left the envelope"
        status = f"terminated at t = {float(sim.time_s[0]):.2f} s ({what})"
    log = rec.log.log()
    log.meta.update({"wake": wake, "status": status, "policy": policy.name, "seed": seed,
                     "turbulence_sigma_mps": turbulence})
    return log, status


def run(args) -> int:
    from ..scenarios import get_scenario

    policy_spec = args.policy
    learned = policy_spec != "pid"
    if not learned:
        given = [f"{o} {v}" for o, v in (("--seed", args.seed), ("--turbulence", args.turbulence),
                                         ("--action-mode", args.action_mode)) if v is not None]
        if given:
            raise ValueError(f"{', '.join(given)}: only with a learned policy or pid_formation (the pid replay is the "
                             "scenario's deterministic run and draws no random numbers)")
        if args.allow_scenario_mismatch:
            raise ValueError("--allow-scenario-mismatch: only with a learned policy")
    pol = None
    if learned:
        try:
            from train.evaluation.policy_loader import load_policy
        except ModuleNotFoundError as exc:
            raise ValueError(f"--policy {policy_spec!r} needs the RL extra ({exc}); pip install -e '.[rl]'") from None
        scenario = args.scenario
        if scenario is None and policy_spec not in ("pid_formation", "station_keeper"):
            scenario = trained_scenario(policy_spec)
        if scenario is None:
            raise ValueError(f"--scenario is required with --policy {policy_spec!r}" +
                             ("" if policy_spec in ("pid_formation", "station_keeper") else " (no scenario in the policy's metadata)"))
        sc = get_scenario(scenario)
        if sc.n_vehicles < 2:
            raise ValueError(f"--scenario {sc.name!r} has one UAV; --policy {policy_spec!r} flies followers "
                             "(use --policy pid)")
        check_policy_scenario(policy_spec, sc.name, allow=args.allow_scenario_mismatch)
        pol = load_policy(policy_spec, action_mode=args.action_mode)  # unknown files fail before any output
    else:
        if args.scenario is None:
            raise ValueError("--scenario is required with --policy pid")
        sc = get_scenario(args.scenario)
    check_min_duration(args.duration, sc)

    from ..io import prepare_output_dir
    from ..plotting import save_figure
    from ..plotting.trajectory3d import trajectory_3d_figure
    from ..replay import EpisodeLog, write_acmi, write_animation

    out = prepare_output_dir(args.out or f"results/replay-{sc.name}-{time.strftime('%Y%m%d-%H%M%S')}",
                             overwrite=args.overwrite)
    if pol is None:
        from ..runs.runner import run_scenario

        run_ = run_scenario(sc, False if args.no_wake else None, args.duration)
        log, status = EpisodeLog.from_scenario_run(run_), run_.status_message
        summary = {"scenario": sc.name, "policy": "pid", "seed": None}
    else:
        seed = DEFAULT_SEED if args.seed is None else args.seed
        turb = 1.0 if args.turbulence is None else args.turbulence
        print(f"flying {sc.name} with {pol.name} ({pol.action_mode} actions), seed {seed} ...", file=sys.stderr,
              flush=True)
        log, status = _fly_policy(pol, sc.name, seed=seed, wake=not args.no_wake, turbulence=turb,
                                  duration_s=args.duration)
        summary = {"scenario": sc.name, "policy": pol.name, "action_mode": pol.action_mode, "seed": seed,
                   "turbulence_sigma_mps": turb}
    ow = args.overwrite
    files = [write_acmi(log, out / f"{sc.name}.txt.acmi", overwrite=ow, stride=args.stride),
             log.save_npz(out / f"{sc.name}_log.npz", overwrite=ow),
             save_figure(trajectory_3d_figure(log), out / f"{sc.name}_trajectory_3d.png", overwrite=ow)]
    if args.gif:
        from ..replay.animation import frame_indices

        total = len(frame_indices(log, 10.0, 4.0, args.max_frames))
        step, close = _progress(args.progress, total, f"{sc.name}.gif")
        try:
            files.append(write_animation(log, out / f"{sc.name}.gif", overwrite=ow, max_frames=args.max_frames,
                                         progress=step))
        finally:
            close()
    print(json.dumps({**summary, "status": status, "samples": log.n_samples, "files": [str(f) for f in files]},
                     indent=2))
    return 0


__all__ = ["register", "run", "DEFAULT_SEED", "MAX_GIF_FRAMES"]
