"""``formation-env run --scenario NAME``: fly a thesis scenario with the PID agents and write
``metrics.json`` and thesis-style figures into a fresh output directory."""

from __future__ import annotations

import json
import time

from ._args import MAX_DURATION_S, duration


def register(sub) -> None:
    from ..scenarios import scenario_names

    p = sub.add_parser("run", help="run a thesis scenario (tracking, gust, formation_keeping, reconfiguration)")
    p.add_argument("--scenario", required=True, help=f"one of {scenario_names()}")
    p.add_argument("--no-wake", action="store_true", help="fly without the ELL wake interaction")
    p.add_argument("--out", default=None, help="output directory (default results/run-<scenario>-<timestamp>)")
    p.add_argument("--overwrite", action="store_true", help="allow writing into an existing non-empty directory")
    p.add_argument("--duration", type=duration, default=None,
                   help=f"override the scenario's duration, s (at most {MAX_DURATION_S:g})")
    p.add_argument("--no-figures", action="store_true", help="write only metrics.json")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..scenarios import get_scenario
    from ..runs.runner import run_scenario_to_dir

    sc = get_scenario(args.scenario)  # unknown names fail before anything is created
    if args.duration is not None and args.duration < sc.dt:
        raise ValueError(f"--duration {args.duration:g}: shorter than one step of {sc.name!r} ({sc.dt:g} s)")
    out = args.out or f"results/run-{args.scenario}-{time.strftime('%Y%m%d-%H%M%S')}"
    metrics = run_scenario_to_dir(args.scenario, out, wake=not args.no_wake, overwrite=args.overwrite,
                                  duration_s=args.duration, figures=not args.no_figures)
    scalars = {k: v for k, v in metrics.items() if isinstance(v, (int, float, str, bool)) or v is None}
    print(json.dumps(scalars, indent=2))
    print(f"wrote {out}/metrics.json and {len(metrics['figures'])} figures")
    return 0


__all__ = ["register", "run"]
