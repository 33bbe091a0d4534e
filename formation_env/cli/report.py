"""``formation-env report``: the validation report (markdown + PNG figures) putting the project's
numbers beside the thesis's, with a replay of the reconfiguration (ACMI + GIF)."""

from __future__ import annotations

import json


def register(sub) -> None:
    from ..report import SECTIONS

    p = sub.add_parser("report", help="validation report: the thesis's tables, sweeps, scenarios and figures beside ours")
    p.add_argument("--out", default=None, help="output directory (default results/report-<timestamp>)")
    p.add_argument("--overwrite", action="store_true", help="allow writing into an existing non-empty directory")
    p.add_argument("--quick", action="store_true", help="short scenarios, coarse sweeps, short GIF (a smoke run)")
    p.add_argument("--section", action="append", metavar="KEY", help=f"only these sections (repeatable): {list(SECTIONS)}")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..report import build_report

    s = build_report(args.out, quick=args.quick, overwrite=args.overwrite, sections=args.section)
    print(json.dumps({"out": s["out"], "counts": s["counts"], "figures": len(s["figures"])}, indent=2))
    print(f"wrote {s['out']}/report.md")
    return 0 if s["counts"]["out"] == 0 else 1


__all__ = ["register", "run"]
