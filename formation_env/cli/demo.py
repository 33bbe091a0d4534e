"""``formation-env demo``: the main job of ``make demo``.

Flies the thesis scenarios with the thesis PID baseline (tracking, gust, formation keeping with
and without the wake, reconfiguration) and writes their metrics and thesis-style figures; then
reproduces the thesis tables (``verify``), the chapter 5.4 validation sweeps and the wake-field
figures; finally flies the committed ``close_formation`` RL policy beside the thesis PID and
``pid_formation`` on a few held-out episodes under frozen turbulence (comparison table and figures).
Everything goes into a fresh output directory (never overwriting an existing one).
"""

from __future__ import annotations

import datetime as _dt
import json

from ..io import atomic_write_json, atomic_write_text, prepare_output_dir
from . import verify

DEMO_SCENARIOS = ("tracking", "gust", "formation_keeping", "reconfiguration")
DEMO_POLICY_SCENARIO = "close_formation"
DEMO_POLICY_EPISODES = 8


def register(sub) -> None:
    p = sub.add_parser("demo", help="run the main demonstration (tables, sweeps, figures) into --out")
    p.add_argument("--out", default=None, help="output directory (default results/demo-<timestamp>)")
    p.add_argument("--overwrite", action="store_true", help="allow writing into an existing non-empty directory")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..plotting import save_figure
    from ..plotting.wake_figures import sweeps_figure, trefftz_planes_figure
    from ..runs.runner import run_scenario_to_dir
    from ..verification.sweeps import lateral_sweep, longitudinal_sweep, vertical_sweep

    out_dir = args.out or f"results/demo-{_dt.datetime.now().strftime('%Y%m%d-%H%M%S')}"
    out = prepare_output_dir(out_dir, overwrite=args.overwrite)
    ow = args.overwrite

    scenario_summary = {}
    for name in DEMO_SCENARIOS:
        print(f"flying {name} with the PID baseline ...", flush=True)
        metrics = run_scenario_to_dir(name, out / "scenarios" / name, wake=True, overwrite=ow)
        scenario_summary[name] = metrics
    atomic_write_json(out / "scenario_metrics.json", scenario_summary, overwrite=ow)
    print(_scenario_lines(scenario_summary))

    sections = verify.available_sections()
    results = {k: fn() for k, fn in sections.items()}
    atomic_write_json(out / "verify.json", results, overwrite=ow)
    report = "\n\n".join(verify.format_section(k, d) for k, d in results.items())
    atomic_write_text(out / "verify.txt", report + "\n", overwrite=ow)
    print(report)

    sweeps = [lateral_sweep(), longitudinal_sweep(), vertical_sweep(y_b=1.0), vertical_sweep(y_b=0.75)]
    atomic_write_json(out / "validation_sweeps.json", {s.name: s.as_dict() for s in sweeps}, overwrite=ow)
    save_figure(sweeps_figure(sweeps), out / "validation_sweeps.png", overwrite=ow)
    save_figure(trefftz_planes_figure(), out / "wake_trefftz_planes.png", overwrite=ow)

    policy_ok = _policy_comparison(out, ow)

    ok = (all(verify._ok(d) for d in results.values()) and all(_completed(m) for m in scenario_summary.values())
          and policy_ok)
    summary = {"verify_ok": ok, "files": sorted(p.name for p in out.iterdir())}
    print(f"\nwrote {out}/: {', '.join(summary['files'])}")
    print(json.dumps({"verify_ok": ok}))
    return 0 if ok else 1


def _policy_comparison(out, overwrite: bool) -> bool:
    """The committed close_formation policy (training seed 0) against the thesis PID and pid_formation
    on the first held-out test episodes (frozen Dryden turbulence sigma 1 m/s, wake on)."""
    from pathlib import Path

    policies = sorted((Path(__file__).resolve().parents[2] / "train" / "policies").glob(f"{DEMO_POLICY_SCENARIO}_*seed0.zip"))
    if not policies:
        print(f"no committed {DEMO_POLICY_SCENARIO} policy: skipping the policy comparison")
        return True
    try:
        from train.evaluation.evaluate import evaluate
    except ModuleNotFoundError as exc:  # the RL extra is not installed
        print(f"policy comparison skipped ({exc}); install with pip install -e '.[rl]'")
        return True
    print(f"\nflying {DEMO_POLICY_SCENARIO}: {policies[0].name} vs the thesis PID vs pid_formation "
          f"({DEMO_POLICY_EPISODES} held-out episodes, frozen turbulence sigma 1 m/s, wake on) ...", flush=True)
    rep = evaluate([str(policies[0]), "pid", "pid_formation"], scenario=DEMO_POLICY_SCENARIO,
                   episodes=DEMO_POLICY_EPISODES, out_dir=out / "policy_comparison", overwrite=overwrite, n_boot=2000)
    print(rep["table_markdown"])
    if rep.get("comparison_markdown"):
        print(rep["comparison_markdown"])
    return all(p["summary"]["episodes"] == DEMO_POLICY_EPISODES for p in rep["policies"].values())


def _completed(metrics: dict) -> bool:
    if "wake_on" in metrics:
        return bool(metrics["wake_on"]["completed"] and metrics["wake_off"]["completed"])
    return bool(metrics.get("completed", False))


def _scenario_lines(summary: dict) -> str:
    """A few headline numbers per scenario (full metrics in scenario_metrics.json)."""
    lines = ["", "== PID baseline on the thesis scenarios =="]
    for name, m in summary.items():
        if name == "formation_keeping":
            on, off = m["wake_on"]["follower"], m["wake_off"]["follower"]
            lines.append(f"  formation_keeping: follower rms along-track / altitude error "
                         f"{on['along_track_error_m']['rms']:.4f} / {on['altitude_error_m']['rms']:.4f} m with wake, "
                         f"{off['along_track_error_m']['rms']:.4f} / {off['altitude_error_m']['rms']:.4f} m without; "
                         f"mean induced wind NED {[round(x, 4) for x in on['induced_wind_ned_mps']['mean']]} m/s")
        else:
            keys = [k for k in ("final_error_m", "min_separation_m", "completed") if k in m]
            extra = ", ".join(f"{k} {m[k]:.3f}" if isinstance(m[k], float) else f"{k} {m[k]}" for k in keys)
            if name == "gust":
                extra += "; recovery " + ", ".join(f"{g}: {v['recovery_time_s']} s" for g, v in m["gusts"].items())
            lines.append(f"  {name}: {extra}")
    return "\n".join(lines)
