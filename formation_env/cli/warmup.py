"""``formation-env warmup``: compile the simulation kernels ahead of time, with progress (``make install`` runs
it, so the first run after an install is warm; :mod:`formation_env.sim.warmup`)."""

from __future__ import annotations

import sys


def register(sub) -> None:
    p = sub.add_parser("warmup", help="compile the simulation kernels now (make install does; cached afterwards)")
    p.add_argument("--force", action="store_true", help="run the warm-up even when the cache is already warm")
    p.add_argument("--processes", type=int, choices=(1, 2), default=None,
                   help="2: the two decision steps compile in two processes at once (the default with two cores or "
                        "more); 1: one stage after the other in this process")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..sim import Simulation
    from ..sim.warmup import is_warm, warm_up

    if is_warm() and not args.force:
        print("formation-env: the kernel cache is warm (use --force to run the warm-up anyway)", file=sys.stderr)
        return 0
    print("formation-env: compiling the simulation kernels (about 90 s on 2 idle cores, about 2 minutes with one "
          "of them busy, longer under heavier load; cached afterwards):",
          file=sys.stderr, flush=True)
    total = warm_up(Simulation, sys.stderr, processes=args.processes)
    print(f"formation-env: kernels ready in {total:.0f} s", file=sys.stderr)
    return 0


__all__ = ["register", "run"]
