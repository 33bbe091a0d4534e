"""Rows of the validation report: one number (or vector) of the project beside the thesis's, its
tolerance and whether it is within it. ``ok`` is True, False, or None (not applicable: e.g. a
scenario cut too short by ``--quick`` to reach the event the thesis describes)."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["Row", "rows_from_verify_section", "markdown_table", "count"]


@dataclass
class Row:
    name: str
    computed: object
    thesis: object
    tolerance: str
    ok: bool | None
    error: float | None = None
    note: str = ""

    def as_dict(self) -> dict:
        d = asdict(self)
        for k in ("computed", "thesis"):
            v = d[k]
            if isinstance(v, np.ndarray):
                d[k] = v.tolist()
            elif isinstance(v, (np.floating, np.integer, np.bool_)):
                d[k] = v.item()
        return d


def _tol_text(tol) -> str:
    if tol is None:
        return ""
    if isinstance(tol, str):
        return tol
    arr = np.atleast_1d(np.asarray(tol, dtype=float))
    if arr.size == 1:
        return f"abs {arr[0]:.3g}"
    return f"abs {arr.min():.2g}..{arr.max():.2g} (per entry)"


def _label(item: dict, i: int) -> str:
    """A readable label for a table row: its pose or separation where the section gives one."""
    def v(x):
        return "(" + ", ".join(f"{float(a):g}" for a in x) + ")"
    if "pos" in item and "euler_deg" in item:
        return f"pos {v(item['pos'])}, euler {v(item['euler_deg'])} deg"
    if "w2_pos" in item:
        return f"wing 2 at {v(item['w2_pos'])}"
    if "R0_euler_deg" in item:
        return f"R0 euler {v(item['R0_euler_deg'])} deg"
    return str(i)


def rows_from_verify_section(data: dict) -> list[Row]:
    """Every ``{computed, thesis, ok}`` entry of a ``formation-env verify`` section, in order."""
    rows: list[Row] = []

    def walk(prefix: str, node) -> None:
        if isinstance(node, dict) and "computed" in node and "thesis" in node:
            err = node.get("max_abs_error")
            note = node.get("note", "")
            if "relative_error" in node:
                note = (note + "; " if note else "") + f"rel. error {node['relative_error']:.2%}"
            rows.append(Row(prefix, node["computed"], node["thesis"], _tol_text(node.get("tolerance")),
                            bool(node.get("ok", True)), None if err is None else float(err), note))
        elif isinstance(node, dict):
            for k, v in node.items():
                if k not in ("ok", "details", "with_alpha_dot"):
                    walk(f"{prefix}.{k}" if prefix else k, v)
        elif isinstance(node, list) and node and isinstance(node[0], dict):
            for i, v in enumerate(node):
                walk(f"{prefix}[{_label(v, i)}]", v)

    walk("", data)
    return rows


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, str):
        return v
    arr = np.atleast_1d(np.asarray(v, dtype=float)).ravel()
    if arr.size > 4:
        return f"{arr.size} values, max abs {np.max(np.abs(arr)):.4g}"

    def one(x: float) -> str:
        return f"{x:.4g}" if (x == 0 or 1e-3 <= abs(x) < 1e5) else f"{x:.3e}"

    return one(arr[0]) if arr.size == 1 else "(" + ", ".join(one(x) for x in arr) + ")"


def _mark(ok, tolerance: str = "") -> str:
    if ok is None:
        return "info" if tolerance == "info" else "n/a"
    return "ok" if ok else "**OUT**"


def markdown_table(rows: list[Row]) -> str:
    lines = ["| quantity | computed | thesis | error | tolerance | within |", "|---|---|---|---|---|---|"]
    for r in rows:
        err = "-" if r.error is None else f"{r.error:.2e}"
        name = r.name + (f" ({r.note})" if r.note else "")
        lines.append(f"| {name} | {_fmt(r.computed)} | {_fmt(r.thesis)} | {err} | {r.tolerance} | {_mark(r.ok, r.tolerance)} |")
    return "\n".join(lines)


def count(rows: list[Row]) -> dict:
    return {"total": len(rows), "ok": sum(r.ok is True for r in rows), "out": sum(r.ok is False for r in rows),
            "n/a": sum(r.ok is None for r in rows)}
