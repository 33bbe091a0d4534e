"""``formation-env bench``: ELL (and, when present, dynamics) speed figures. Progress (which benchmark,
which case, k/N) goes to stderr; the figures (and ``--json``) to stdout."""

from __future__ import annotations

import json
import os
import platform
import sys
import time

from ._args import nonneg_int, positive_int
from ._optional import import_available

BENCH_MODULES = ("formation_env.wake.bench", "formation_env.aircraft.bench", "formation_env.envs.bench")


def register(sub) -> None:
    p = sub.add_parser("bench", help="measure ELL and dynamics speed (medians of repeated runs)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument("--quick", action="store_true", help="fewer repeats (for smoke tests)")
    p.add_argument("--baseline", default=None, metavar="PATH",
                   help="an older checkout (its repository root) to measure in the same session: ratios new/old")
    p.add_argument("--no-busy", dest="busy", action="store_false",
                   help="skip the runs with a competing busy process")
    p.add_argument("--peers", action="store_true",
                   help="also time the peers' environments (VMAS flocking, PyFlyt dogfight) where installed")
    p.add_argument("--peer-python", default=None, metavar="PATH",
                   help="the interpreter the peers are installed in, e.g. a virtual environment of their own "
                        "(default: this one; `make bench-peers` makes one)")
    p.add_argument("--rllib", action="store_true",
                   help="instead: RLlib env steps/s sampled with 1 and 2 env runners (needs the 'distributed' extra)")
    p.add_argument("--runners", type=nonneg_int, nargs="+", default=None, help="env runner counts for --rllib (default 1 2)")
    p.add_argument("--action-mode", default=None, choices=("surfaces", "residual", "setpoints"),
                   help="action mode for --rllib (default setpoints)")
    p.add_argument("--envs-per-runner", type=positive_int, default=None, help="envs per env runner for --rllib (default 1)")
    p.add_argument("--address", default=None, help="Ray cluster for --rllib (default: a local instance)")
    p.set_defaults(func=run)


def run(args) -> int:
    if args.rllib:
        return _run_rllib(args)
    given = [f for f, v in (("--runners", args.runners), ("--action-mode", args.action_mode),
                            ("--envs-per-runner", args.envs_per_runner), ("--address", args.address)) if v is not None]
    if given:
        raise ValueError(f"{', '.join(given)}: only with --rllib")
    if args.peer_python is not None and not args.peers:
        raise ValueError("--peer-python: only with --peers")
    if args.peer_python is not None and not (os.path.isfile(args.peer_python) and os.access(args.peer_python, os.X_OK)):
        raise ValueError(f"--peer-python {args.peer_python!r}: not an executable file (a Python interpreter)")
    if args.baseline is not None and not os.path.isdir(os.path.join(args.baseline, "formation_env")):
        raise ValueError(f"--baseline {args.baseline!r}: not a checkout (no formation_env/ inside)")
    results = {"machine": {"cpus": os.cpu_count(), "python": platform.python_version(), "platform": platform.platform()}}
    modules = import_available(BENCH_MODULES)
    t0 = time.perf_counter()

    def log(line: str) -> None:
        print(f"bench [{time.perf_counter() - t0:5.0f} s] {line}", file=sys.stderr, flush=True)

    for k, (name, module) in enumerate(modules.items(), 1):
        key = name.split(".")[1]
        log(f"{k}/{len(modules)} {key} ({name}) ...")
        if name == "formation_env.envs.bench":
            results["envs"] = module.run_benchmarks(quick=args.quick, baseline=args.baseline, busy=args.busy,
                                                    log=lambda line: log(f"{k}/{len(modules)} {line}"))
        else:
            results[key] = module.run_benchmarks(quick=args.quick)
    if args.peers:
        from ..envs.bench import run_peers

        log("peers ...")
        results["peers"] = run_peers(args.peer_python, quick=args.quick)
    log("done")
    if args.json:
        print(json.dumps(results, indent=2))
    else:
        print_human(results)
    return 0


def print_human(results: dict) -> None:
    """The benchmark's report as text (``formation-env bench`` without ``--json``; docs/performance.md)."""
    m = results["machine"]
    print(f"machine: {m['cpus']} CPUs, Python {m['python']}")
    w = results.get("wake")
    if w:
        print(f"ELL ({w['case']}):")
        print(f"  single evaluation      {w['single_evaluation_us']:9.1f} us   (thesis: {w['thesis_s'] * 1e3:.0f} ms;"
              f" {w['speedup_vs_thesis']:.0f}x faster)")
        print(f"  single incl. meshing   {w['single_with_meshing_us']:9.1f} us")
        if any("kernel" in r for rows in w["batched"].values() for r in rows.values()):
            print("  (per formation: WakeModel.evaluate's kernel; across lanes: the decision step's, 16 formations "
                  "a vector, formation_env.wake.across)")
        for b, rows in w["batched"].items():
            for r in rows.values():
                print(f"  batch {int(b):5d}, {r['kernel'].replace('_', ' '):13s}, {r['threads']} thread"
                      f"{'s' if r['threads'] > 1 else ' '} {r['formation_evaluations_per_s']:9.0f} formation-evaluations/s"
                      f"  ({r['us_per_formation']:.2f} us each), {r['gflops']:.2f} GFLOP/s"
                      f" ({r['gflops_per_core']:.2f} a core)")
        peak = w.get("peak_per_core")
        if peak and peak.get("gflops"):
            print(f"  nominal peak           {peak['gflops']:9.1f} GFLOP/s a core ({peak['derivation']})")
        if "flops_per_evaluation" in w:
            fl = w["flops_per_evaluation"]
            print(f"  ELL GFLOP/s            {w['gflops_single']:9.2f} (single evaluation), counting {fl['total']:,} flops "
                  f"per evaluation (AIC {fl['aic']:,}, LU {fl['lu']:,}, field {fl['field']:,}; "
                  "formation_env.wake.bench.FLOPS)")
    envs = results.get("envs")
    if envs:
        from ..envs.bench import format_table

        print(f"environments ({envs['case']}):")
        print(format_table(envs))
    peers = results.get("peers")
    if peers:
        from ..envs.bench import format_peers

        print(format_peers(peers))
    for key, value in results.items():
        if key not in ("machine", "wake", "envs", "peers"):
            print(f"{key}:")
            print("  " + json.dumps(value, indent=2).replace("\n", "\n  "))


def _run_rllib(args) -> int:
    from train.rllib.backend import benchmark_sampling

    runners = args.runners or [1, 2]
    envs = 1 if args.envs_per_runner is None else args.envs_per_runner
    if any(n < 0 for n in runners):
        raise ValueError(f"--runners must be integers >= 0, got {runners}")
    if envs < 1:
        raise ValueError(f"--envs-per-runner must be >= 1, got {envs}")
    res = benchmark_sampling(tuple(runners), action_mode=args.action_mode or "residual", address=args.address,
                             num_envs_per_env_runner=envs,
                             rounds=2 if args.quick else 5, batch=1000 if args.quick else 2000,
                             log=(lambda m: None) if args.json else print)
    if args.json:
        print(json.dumps(res, indent=2))
    return 0
