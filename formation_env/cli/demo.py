"""``formation-env demo``: the main job of ``make demo``.

Reproduces the thesis tables (``verify``), the chapter 5.4 validation sweeps and the wake-field
figures into a fresh output directory (never overwriting an existing one).
"""

from __future__ import annotations

import datetime as _dt
import json

from ..io import atomic_write_json, atomic_write_text, prepare_output_dir
from . import verify


def register(sub) -> None:
    p = sub.add_parser("demo", help="run the main demonstration (tables, sweeps, figures) into --out")
    p.add_argument("--out", default=None, help="output directory (default results/demo-<timestamp>)")
    p.add_argument("--overwrite", action="store_true", help="allow writing into an existing non-empty directory")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..plotting import save_figure
    from ..plotting.wake_figures import sweeps_figure, trefftz_planes_figure
    from ..verification.sweeps import lateral_sweep, longitudinal_sweep, vertical_sweep

    out_dir = args.out or f"results/demo-{_dt.datetime.now().strftime('%Y%m%d-%H%M%S')}"
    out = prepare_output_dir(out_dir, overwrite=args.overwrite)
    ow = args.overwrite

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

    ok = all(verify._ok(d) for d in results.values())
    summary = {"verify_ok": ok, "files": sorted(p.name for p in out.iterdir())}
    print(f"\nwrote {out}/: {', '.join(summary['files'])}")
    print(json.dumps({"verify_ok": ok}))
    return 0 if ok else 1
