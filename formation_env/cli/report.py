"""``formation-env report``: the validation report (markdown + PNG figures) putting the project's
numbers beside the thesis's, with a replay of the reconfiguration (ACMI + GIF).

Exit status 0 once the report is written, whatever it found (rows outside the tolerance, such as the
tail-plane rows the README lists as known mismatches, are counted in the report and named on stderr);
``--strict`` exits 1 when any row is out (for CI). ``formation-env verify`` always exits 1 on a mismatch."""

from __future__ import annotations

import json
import sys


def register(sub) -> None:
    from ..report import SECTIONS

    p = sub.add_parser("report", help="validation report: the thesis's tables, sweeps, scenarios and figures beside ours")
    p.add_argument("--out", default=None, help="output directory (default results/report-<timestamp>)")
    p.add_argument("--overwrite", action="store_true", help="allow writing into an existing non-empty directory")
    p.add_argument("--quick", action="store_true", help="short scenarios, coarse sweeps, short GIF (a smoke run)")
    p.add_argument("--section", action="append", metavar="KEY", help=f"only these sections (repeatable): {list(SECTIONS)}")
    p.add_argument("--strict", action="store_true",
                   help="exit 1 when any row is outside its tolerance (default: exit 0 once the report is written)")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..report import build_report

    s = build_report(args.out, quick=args.quick, overwrite=args.overwrite, sections=args.section)
    print(json.dumps({"out": s["out"], "counts": s["counts"], "figures": len(s["figures"])}, indent=2))
    print(f"wrote {s['out']}/report.md")
    n_out = s["counts"]["out"]
    if n_out:
        print(f"formation-env report: {n_out} row(s) outside the tolerance (see {s['out']}/report.md; the README "
              "lists the known mismatches)" + ("" if args.strict else "; --strict makes this exit status 1"),
              file=sys.stderr)
    return 1 if (args.strict and n_out) else 0


__all__ = ["register", "run"]
