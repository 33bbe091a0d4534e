"""The evaluation report: markdown tables (per-policy metrics, paired comparisons, seed groups) and
the comparison plots."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .summary import PER_UAV_PREFIX, per_uav_keys

__all__ = ["markdown_table", "comparison_table", "groups_table"]

_TABLE = (("rms_slot_error_m", "RMS slot error (m)", "{:.3f}"),
          ("rms_along_track_m", "RMS along-track error (m)", "{:.3f}"),
          ("rms_lateral_m", "RMS lateral error (m)", "{:.3f}"), ("rms_vertical_m", "RMS vertical error (m)", "{:.3f}"),
          ("max_slot_error_m", "max slot error (m, mean)", "{:.2f}"),
          ("max_slot_error_m_worst", "max slot error (m, worst)", "{:.2f}"),
          ("time_within_1m_frac", "time within 1 m (fraction)", "{:.3f}"),
          ("min_separation_m", "min separation (m)", "{:.2f}"),
          ("min_separation_m_p05", "min separation (m, 5th percentile of episodes)", "{:.2f}"),
          ("collisions", "collisions", "{:d}"),
          ("crashes", "crashes", "{:d}"), ("reconfig_success_rate", "reconfiguration success", "{:.2f}"),
          ("reconfig_time_s", "reconfiguration time (s)", "{:.1f}"),
          ("control_effort_rad", "control effort (rad RMS)", "{:.4f}"), ("throttle_mean", "mean throttle", "{:.3f}"),
          ("fuel_saving_pct", "follower fuel saving vs leader (%)", "{:.2f}"),
          ("induced_drag_saving", "induced-drag saving (ELL)", "{:.4f}"),
          ("harvest_ratio", "harvest ratio (saving / calm-air optimum)", "{:.3f}"),
          ("drag_saving_pct_ell", "drag saving, ELL (%)", "{:.2f}"), ("drag_saving_pct_6dof", "drag saving, 6-DOF (%)", "{:.2f}"),
          ("return", "episode return", "{:.1f}"))
_PLOT_KEYS = ("rms_slot_error_m", "max_slot_error_m", "max_slot_error_m_worst", "time_within_1m_frac", "min_separation_m",
              "control_effort_rad", "fuel_saving_pct")


def _fmt(v, fmt: str = "{:.3f}") -> str:
    if v is None:
        return "-"
    if isinstance(v, float) and math.isnan(v):
        return "nan"
    return fmt.format(v)


def _cell(s: dict, key: str, fmt: str) -> str:
    v = s.get(key)
    if v is None:
        return "-"
    if f"{key}_ci" in s and (key in ("rms_slot_error_m", "rms_lateral_m", "rms_vertical_m", "harvest_ratio",
                                      "formation_saving") or key.startswith(PER_UAV_PREFIX)):
        lo, hi = s[f"{key}_ci"]
        return f"{_fmt(v, fmt)} [{_fmt(lo, fmt)}, {_fmt(hi, fmt)}]"
    if key in ("collisions", "crashes") and "episodes" in s:
        return f"{v}/{s['episodes']}"
    if key == "reconfig_success_rate" and "reconfig_success_rate_ci" in s:
        lo, hi = s["reconfig_success_rate_ci"]
        return f"{_fmt(v, fmt)} [{_fmt(lo, fmt)}, {_fmt(hi, fmt)}]"
    return _fmt(v, fmt)


def markdown_table(summaries: dict[str, dict]) -> str:
    """Per-policy metrics; the RMS error as mean [95 % bootstrap CI], collisions (and crashes) as k/n,
    the reconfiguration success as rate [95 % Wilson CI]."""
    names = list(summaries)
    lines = ["| metric (mean over episodes [95 % CI]) | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
    per_uav = per_uav_keys({k for s in summaries.values() for k in s})
    rows = list(_TABLE)
    at = [k for k, _, _ in rows].index("harvest_ratio") + 1  # an N-UAV task: the formation's and each follower's
    rows[at:at] = [("formation_saving", "formation induced-drag saving (every UAV, ELL)", "{:.4f}")] + [
        (k, f"induced-drag saving, uav_{k[len(PER_UAV_PREFIX):]}", "{:.4f}") for k in per_uav]
    for key, label, fmt in rows:
        if not any(key in s for s in summaries.values()):
            continue
        lines.append(f"| {label} | " + " | ".join(_cell(summaries[n], key, fmt) for n in names) + " |")
    if "pid" in summaries:
        base = summaries["pid"]["rms_slot_error_m"]
        cells = [f"{100.0 * (1.0 - summaries[n]['rms_slot_error_m'] / base):+.1f} %" for n in names]
        lines.append("| RMS error reduction vs PID | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _ci(pair, fmt: str) -> str:
    return f"[{_fmt(pair[0], fmt)}, {_fmt(pair[1], fmt)}]"


def comparison_table(comps: dict[str, dict], groups: dict[str, dict] | None = None) -> str:
    """The paired comparisons (per-episode RMS slot error, reduction = baseline - policy, m): one row per
    policy (or seed group) and baseline."""
    rows = [(p, b, c) for p, per in comps.items() for b, c in per.items()]
    rows += [(f"{g} (mean of {r['n_seeds']} seeds)", b, c) for g, r in (groups or {}).items()
             for b, c in r["comparisons"].items()]
    if not rows:
        return ""
    success = any("reconfig_success" in c for _, _, c in rows)
    head = ("| policy | baseline | reduction of the mean (m) | 95 % CI | reduction of the median (m) | 95 % CI | "
            "relative (%) [95 % CI] | better | sign-test p |" + (" success difference [95 % CI] |" if success else ""))
    lines = [head, "|---" * (9 + success) + "|"]
    for p, b, c in rows:
        r = c["rms_slot_error_m"]
        cells = [p, b, _fmt(r["mean_reduction"]), _ci(r["mean_reduction_ci"], "{:.3f}"), _fmt(r["median_reduction"]),
                 _ci(r["median_reduction_ci"], "{:.3f}"),
                 f"{_fmt(r['relative_reduction_pct'], '{:+.1f}')} {_ci(r['relative_reduction_pct_ci'], '{:+.1f}')}",
                 f"{r['n_better']}/{r['n']} ({100 * r['fraction_better']:.0f} %)", f"{r['sign_test_p']:.3g}"]
        if success:
            s = c.get("reconfig_success")
            cells.append("-" if s is None else f"{s['difference']:+.2f} {_ci(s['difference_ci'], '{:+.2f}')}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def groups_table(groups: dict[str, dict]) -> str:
    """Seed groups: mean +- std (min .. max) across the training seeds of a few summary metrics."""
    if not groups:
        return ""
    keys = [("rms_slot_error_m", "RMS slot error (m)", "{:.3f}"), ("collision_rate", "collision rate", "{:.3f}"),
            ("reconfig_success_rate", "reconfiguration success", "{:.2f}"),
            ("min_separation_m", "min separation (m)", "{:.2f}")]
    keys = [k for k in keys if any(k[0] in g["summary"] for g in groups.values())]
    lines = ["| group | seeds | " + " | ".join(lbl + ", mean ± std (min .. max)" for _, lbl, _ in keys) + " |",
             "|---|---|" + "---|" * len(keys)]
    for name, g in groups.items():
        cells = []
        for k, _, fmt in keys:
            s = g["summary"].get(k)
            cells.append("-" if s is None else
                         f"{_fmt(s['mean'], fmt)} ± {_fmt(s['std'], fmt)} ({_fmt(s['min'], fmt)} .. {_fmt(s['max'], fmt)})")
        lines.append(f"| {name} | {g['n_seeds']} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def write_plots(out_dir: Path, results: dict[str, dict], scenario: str, *, overwrite: bool) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from formation_env.io import atomic_write

    names = list(results)
    written = []
    labels = {k: lbl for k, lbl, _ in _TABLE}
    keys = [(k, labels[k]) for k in _PLOT_KEYS if all(k in results[n]["summary"] for n in names)]
    # a compact grid of small panels (up to 3 columns), not one long strip of bars
    ncols = max(1, min(3, len(keys)))
    nrows = max(1, -(-len(keys) // ncols))
    fig, axes = plt.subplots(nrows, ncols, figsize=(2.9 * ncols, 2.4 * nrows), squeeze=False)
    for ax in axes.flat[len(keys):]:
        ax.set_visible(False)
    for ax, (k, lbl) in zip(axes.flat, keys):
        summ = [results[n]["summary"] for n in names]
        vals = [s[k] for s in summ]
        yerr = None
        if all(f"{k}_ci" in s for s in summ):
            yerr = np.array([[v - s[f"{k}_ci"][0], s[f"{k}_ci"][1] - v] for v, s in zip(vals, summ)]).T
            lbl += " (95 % CI)"
        ax.bar(range(len(names)), vals, yerr=yerr, capsize=3, color=[f"C{i}" for i in range(len(names))])
        ax.set_xticks(range(len(names)), names, rotation=30, ha="right", fontsize=8)
        ax.set_title(lbl, fontsize=8)
        ax.tick_params(axis="y", labelsize=7)
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.grid(True, axis="y", alpha=0.3)
    fig.suptitle(f"{scenario}: held-out episodes, wake + Dryden turbulence", fontsize=10)
    fig.tight_layout()
    written.append(str(atomic_write(out_dir / "metrics.png", lambda p: fig.savefig(p, dpi=110, format="png"), overwrite=overwrite)))
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(8, 4))
    for i, n in enumerate(names):
        eps = results[n]["episodes"]
        # episodes that ended early (collision, crash) leave the statistics from then on (NaN padding),
        # so one early end does not cut every curve
        longest = max(eps, key=lambda ep: len(ep["series"]["t"]))
        t = np.asarray(longest["series"]["t"])
        e = np.full((len(eps), len(t)), np.nan)
        for k, ep in enumerate(eps):
            e[k, :len(ep["series"]["slot_error_m"])] = ep["series"]["slot_error_m"]
        mean, lo, hi = np.nanmean(e, 0), np.nanpercentile(e, 10, axis=0), np.nanpercentile(e, 90, axis=0)
        ended = int(np.sum(np.isnan(e[:, -1])))
        ax.plot(t, mean, color=f"C{i}", label=f"{n} (mean, 10-90 %)" + (f", {ended} ended early" if ended else ""))
        ax.fill_between(t, lo, hi, color=f"C{i}", alpha=0.2)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("slot error (m)")
    ax.set_yscale("log")
    ax.grid(True, alpha=0.3)
    ax.legend()
    ax.set_title(f"{scenario}: follower slot error")
    fig.tight_layout()
    written.append(str(atomic_write(out_dir / "slot_error.png", lambda p: fig.savefig(p, dpi=110, format="png"), overwrite=overwrite)))
    plt.close(fig)
    return written
