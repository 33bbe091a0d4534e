"""One evaluation at several turbulence levels (issue 24: close formation is judged in calm air and at 0.5, 1
and 1.5 m/s): :func:`train.evaluation.evaluate.evaluate` once per level, on the same held-out seeds, into
``<out>/sigma_<level>/``, and a headline table over the levels (``levels.md``, ``levels.json``) of the
quantities close formation exists for: the harvest ratio and the induced-drag saving, the slot-frame RMS errors
(lateral and vertical, where the saving lives; along-track), collisions and the smallest separation."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path

__all__ = ["DEFAULT_LEVELS", "HEADLINE", "evaluate_levels", "levels_table"]

DEFAULT_LEVELS = (0.0, 0.5, 1.0, 1.5)  # m/s: calm air and the three turbulence levels of the issue
# (summary key, column label, format): the headline quantities, per level
HEADLINE = (("harvest_ratio", "harvest", "{:.3f}"), ("induced_drag_saving", "saving", "{:.3f}"),
            ("rms_lateral_m", "lat. RMS m", "{:.3f}"), ("rms_vertical_m", "vert. RMS m", "{:.3f}"),
            ("rms_along_track_m", "along RMS m", "{:.2f}"), ("collisions", "collisions", "{:d}"),
            ("min_separation_m", "min sep. m", "{:.2f}"))


def _level_name(sigma: float) -> str:
    return f"sigma_{sigma:g}"


def evaluate_levels(policies: Sequence[str], *, scenario: str, levels: Sequence[float] = DEFAULT_LEVELS,
                    out_dir: str | Path | None = None, overwrite: bool = False, log: Callable[[str], None] | None = None,
                    **kwargs) -> dict:
    """:func:`~train.evaluation.evaluate.evaluate` of ``policies`` at every turbulence sigma of ``levels`` (m/s,
    distinct, finite, >= 0), the same seeds at each. Returns ``{"levels": [...], "reports": {level name: report},
    "table_markdown": ...}``; with ``out_dir`` each level's files go to ``out_dir/sigma_<level>/`` and the table to
    ``levels.md`` / ``levels.json``."""
    from formation_env.io import atomic_write_json, atomic_write_text, prepare_output_dir

    from .evaluate import evaluate

    vals = []
    for v in levels:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
            raise ValueError(f"turbulence levels must be finite numbers >= 0, got {v!r}")
        vals.append(float(v))
    if not vals or len(set(vals)) != len(vals):
        raise ValueError(f"turbulence levels must be distinct and at least one, got {list(levels)!r}")
    out = prepare_output_dir(out_dir, overwrite=overwrite) if out_dir is not None else None
    reports = {}
    for sigma in vals:
        if log:
            log(f"== turbulence sigma {sigma:g} m/s")
        reports[_level_name(sigma)] = evaluate(policies, scenario=scenario, turbulence_sigma_mps=sigma,
                                               out_dir=None if out is None else out / _level_name(sigma),
                                               overwrite=overwrite, log=log, **kwargs)
    summaries = {name: {p: r["summary"] for p, r in rep["policies"].items()} for name, rep in reports.items()}
    table = levels_table(summaries)
    res = {"scenario": scenario, "levels": vals, "reports": reports, "table_markdown": table}
    if out is not None:
        atomic_write_json(out / "levels.json", {"scenario": scenario, "levels": vals, "summaries": summaries},
                          overwrite=overwrite)
        atomic_write_text(out / "levels.md", f"# {scenario} at every turbulence level\n\n{table}", overwrite=overwrite)
        res["out_dir"] = str(out)
    return res


def levels_table(summaries: dict[str, dict[str, dict]]) -> str:
    """Markdown: one row per policy and level, the :data:`HEADLINE` columns (``-`` where a summary lacks one;
    the harvest ratio with its 95 % interval when the summary has it)."""
    head = "| policy | level | " + " | ".join(label for _, label, _ in HEADLINE) + " |"
    lines = [head, "|" + "---|" * (len(HEADLINE) + 2)]
    for level, by_policy in summaries.items():
        for policy, s in by_policy.items():
            cells = []
            for key, _, fmt in HEADLINE:
                v = s.get(key)
                if v is None:
                    cells.append("-")
                    continue
                cell = fmt.format(v)
                if f"{key}_ci" in s and key in ("harvest_ratio", "rms_lateral_m", "rms_vertical_m"):
                    lo, hi = s[f"{key}_ci"]
                    cell += f" [{fmt.format(lo)}, {fmt.format(hi)}]"
                cells.append(cell)
            lines.append(f"| {policy} | {level.replace('sigma_', 'sigma ')} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
