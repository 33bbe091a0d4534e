"""``formation-env replay --scenario NAME``: fly a scenario with the PID agents and write its
replay: Tacview ACMI 2.1 (``<scenario>.txt.acmi``), the episode log (``.npz``), a 3D trajectory
figure, and with ``--gif`` an animated 3D view (``<scenario>.gif``)."""

from __future__ import annotations

import json
import time


def register(sub) -> None:
    from ..scenarios import scenario_names

    p = sub.add_parser("replay", help="export a scenario episode for Tacview (ACMI) and as an animated GIF")
    p.add_argument("--scenario", required=True, help=f"one of {scenario_names()}")
    p.add_argument("--policy", default="pid", choices=("pid",), help="who flies (the thesis FCS)")
    p.add_argument("--no-wake", action="store_true", help="fly without the ELL wake interaction")
    p.add_argument("--duration", type=float, default=None, help="override the scenario's duration, s")
    p.add_argument("--out", default=None, help="output directory (default results/replay-<scenario>-<timestamp>)")
    p.add_argument("--overwrite", action="store_true", help="allow writing into an existing non-empty directory")
    p.add_argument("--gif", action="store_true", help="also write an animated GIF (3D view with the wake legs)")
    p.add_argument("--stride", type=int, default=1, help="write every N-th sample to the ACMI file (default 1)")
    p.add_argument("--max-frames", type=int, default=200, help="GIF frames at most (default 200)")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..io import prepare_output_dir
    from ..plotting import save_figure
    from ..plotting.trajectory3d import trajectory_3d_figure
    from ..replay import EpisodeLog, write_acmi, write_animation
    from ..scenarios import get_scenario
    from ..runs.runner import run_scenario

    sc = get_scenario(args.scenario)
    out = prepare_output_dir(args.out or f"results/replay-{sc.name}-{time.strftime('%Y%m%d-%H%M%S')}", overwrite=args.overwrite)
    run_ = run_scenario(sc, False if args.no_wake else None, args.duration)
    log = EpisodeLog.from_scenario_run(run_)
    ow = args.overwrite
    files = [write_acmi(log, out / f"{sc.name}.txt.acmi", overwrite=ow, stride=args.stride),
             log.save_npz(out / f"{sc.name}_log.npz", overwrite=ow),
             save_figure(trajectory_3d_figure(log), out / f"{sc.name}_trajectory_3d.png", overwrite=ow)]
    if args.gif:
        files.append(write_animation(log, out / f"{sc.name}.gif", overwrite=ow, max_frames=args.max_frames))
    print(json.dumps({"scenario": sc.name, "status": run_.status_message, "samples": log.n_samples,
                      "files": [str(f) for f in files]}, indent=2))
    return 0


__all__ = ["register", "run"]
