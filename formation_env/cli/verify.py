"""``formation-env verify``: the thesis tables reproduced beside the thesis's values."""

from __future__ import annotations

import json

import numpy as np

# Modules exposing SECTIONS = {key: callable returning a JSON-serialisable dict} (shared with the report).
from ..verification.sections import SECTION_MODULES, available_sections  # noqa: F401


def register(sub) -> None:
    p = sub.add_parser("verify", help="reproduce the thesis tables and print them beside the thesis values")
    p.add_argument("--json", action="store_true", help="print JSON (keys table_5_2, table_5_3, table_5_4, ...)")
    p.add_argument("--section", action="append", metavar="KEY", help="only these sections (repeatable)")
    p.add_argument("--converged-saving", action="store_true",
                   help="instead of the thesis tables, the converged-saving table of docs/model/ell.md: each lattice's "
                        "saving and winds against nseg 80 over the acceptance grid (minutes)")
    p.set_defaults(func=run)


def run(args) -> int:
    if args.converged_saving:
        if args.json or args.section:
            raise ValueError("--converged-saving prints its own table: leave out --json and --section")
        from ..verification.converged_saving import print_table

        print_table(lambda line: print(line, flush=True))
        return 0
    sections = available_sections()
    keys = args.section or list(sections)
    unknown = [k for k in keys if k not in sections]
    if unknown:
        raise ValueError(f"unknown section(s) {unknown}; available: {list(sections)}")
    results = {k: sections[k]() for k in keys}
    if args.json:
        print(json.dumps(results, indent=2))
    else:
        for key, data in results.items():
            print(format_section(key, data))
            print()
    return 0 if all(_ok(d) for d in results.values()) else 1


def _ok(data) -> bool:
    return bool(data.get("ok", True)) if isinstance(data, dict) else True


def _fmt(values) -> str:
    arr = np.atleast_1d(np.asarray(values, dtype=float))
    return "[" + " ".join(f"{v: .4g}" if (abs(v) < 1e-3 and v != 0) else f"{v: .4f}" for v in arr.ravel()) + "]"


def format_section(key: str, data: dict) -> str:
    """Human-readable rendering: every entry with computed/thesis values, one line each."""
    lines = [f"== {key}: {'OK' if _ok(data) else 'MISMATCH'} =="]

    def walk(prefix: str, node) -> None:
        if isinstance(node, dict) and "computed" in node and "thesis" in node:
            mark = "ok " if node.get("ok", True) else "BAD"
            err = node.get("max_abs_error")
            err_s = f"  |err|max {err:.1e}" if err is not None else ""
            lines.append(f"  {mark} {prefix:<28s} computed {_fmt(node['computed'])}")
            lines.append(f"      {'':<28s} thesis   {_fmt(node['thesis'])}{err_s}")
        elif isinstance(node, dict):
            for k, v in node.items():
                if k != "ok":
                    walk(f"{prefix}.{k}" if prefix else k, v)
        elif isinstance(node, list) and node and isinstance(node[0], dict):
            for i, v in enumerate(node):
                walk(f"{prefix}[{i}]", v)

    walk("", data)
    return "\n".join(lines)
