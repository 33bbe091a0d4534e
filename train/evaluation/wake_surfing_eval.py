"""Wake-surfing evaluation (issue 16): the committed policies against the thesis PID and
``pid_formation`` at the nominal slot and the extremum seeker, on 100 held-out episodes, each measured
against its reference optimum (:mod:`train.evaluation.wake_surfing_rollout`).

Statistics (95 %, ``scipy.stats.bootstrap`` percentile intervals over episodes, 10,000 resamples from seed 0;
Wilson for rates, :mod:`train.evaluation.stats`):
per controller the mean saving and the mean of the per-episode ratio to the reference optimum with
intervals; time to reach 80 % of the optimum (episodes that never do count as the episode's length in
the mean and are reported separately); collisions, episodes outside the safe box for more than 1 s,
the smallest separation. Paired by episode: each policy (and the three training seeds averaged per
episode) against each baseline, the gain in saving ratio (policy - baseline) and, against extremum
seeking, the time saved to 80 % (extremum seeking - policy). Over the training seeds and episodes
(``aggregates``, :mod:`train.evaluation.aggregates`, rliable): IQM, mean and median of the harvest ratio with
stratified bootstrap intervals and the probability of improvement of the policies over each baseline.

``python -m train.evaluation.wake_surfing_eval POLICY.zip [...] --out DIR`` (a new directory) writes
``results.json``, ``results.md``, ``marl_eval.json`` and ``performance_profile.png`` (with several seeds) and,
with ``--figure PATH``, the saving map with the trajectories.
``--tune-es`` runs the extremum seeker's gain sweep on training seeds instead (docs/wake_surfing.md).
``--scenario wake_surfing_random_leader`` evaluates on the randomised-leader variant (the leader's weight and speed
drawn per episode; each episode's reference follows them).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from ..config import TEST_SEED_BASE
from .aggregates import aggregates_table, evaluation_aggregates, plot_profiles, profile_panels
from .comparisons import seed_groups
from .marl_eval import marl_eval_data, training_steps, write_marl_eval
from .stats import N_BOOT, bootstrap_ci, paired_comparison, wilson_interval
from .wake_surfing_rollout import (es_surfer, fly, oracle_keeper, oracle_surfer, pid_formation_surfer, pid_surfer,
                                  sb3_surfer)

__all__ = ["evaluate_wake_surfing", "surfing_report", "summarise_surfer", "paired_gain", "tune_es", "plot_surfing_figure",
           "main"]

BASELINE_NAMES = ("pid", "pid_formation", "extremum_seeking")
SCENARIOS = ("wake_surfing", "wake_surfing_random_leader")  # the task and its randomised-leader variant
TUNING_SEEDS = tuple(range(1000, 1016))  # training-range seeds (never the held-out ones) for the ES sweep
# the last round of the issue-23 sweep (the station keeper flying the set-point; docs/wake_surfing.md has all five)
ES_GRID = {"inner": ["station_keeper"], "gain_y": [0.5, 1.0], "gain_z": [0.5, 1.0], "amplitude_y_m": [0.35],
           "amplitude_z_m": [0.4, 0.6], "phase_lag_y_s": [2.3], "phase_lag_z_s": [0.5], "highpass_rad_s": [0.6],
           "lowpass_rad_s": [1.0, 2.0]}


def _censored_times(eps: list[dict]) -> np.ndarray:
    """Time to 80 % per episode, an episode that never reaches it counted as its length."""
    return np.array([e["time_to_80_s"] if math.isfinite(e["time_to_80_s"]) else e["duration_s"] for e in eps])


def _mean_of(eps: list[dict], key: str) -> float:
    """Mean of ``key`` over the episodes (NaN where an episode record has none, e.g. one made before it existed)."""
    return float(np.mean([float(e.get(key, float("nan"))) for e in eps]))


def summarise_surfer(eps: list[dict], *, n_boot: int = N_BOOT, seed: int = 0) -> dict:
    n = len(eps)
    col = lambda k: np.array([float(e[k]) for e in eps])  # noqa: E731
    ratio, saving = col("saving_ratio"), col("saving")
    times = _censored_times(eps)
    reached = np.isfinite(col("time_to_80_s"))
    longest = col("box_outside_longest_s")
    collisions = int(sum(e["collision"] for e in eps))
    return {
        "episodes": n,
        "saving": float(saving.mean()), "saving_ci": list(bootstrap_ci(saving, "mean", n_boot=n_boot, seed=seed)),
        "reference_saving": float(col("reference_saving").mean()),
        "saving_ratio": float(ratio.mean()), "saving_ratio_ci": list(bootstrap_ci(ratio, "mean", n_boot=n_boot, seed=seed)),
        "reached_80_frac": float(reached.mean()),
        "time_to_80_s_mean_censored": float(times.mean()),
        "time_to_80_s_mean_censored_ci": list(bootstrap_ci(times, "mean", n_boot=n_boot, seed=seed)),
        "time_to_80_s_median_censored": float(np.median(times)),
        "collisions": collisions, "collision_rate_ci": list(wilson_interval(collisions, n)),
        "crashes": int(sum(e["crashed"] for e in eps)),
        "box_outside_over_1s": int(np.sum(longest > 1.0)),
        "box_outside_longest_s_worst": float(longest.max()),
        "box_outside_frac": float(col("box_outside_frac").mean()),
        "min_separation_m": float(col("min_separation_m").min()),
        # the energy account (formation_env.sim.energy): the follower's total-drag saving, % of its drag alone
        "drag_saving_pct_ell": _mean_of(eps, "drag_saving_pct_ell"),
        "drag_saving_pct_6dof": _mean_of(eps, "drag_saving_pct_6dof"),
    }


def paired_gain(baseline, candidate, *, higher_is_better: bool = True, n_boot: int = N_BOOT, seed: int = 0) -> dict:
    """Per-episode gain of the candidate over the baseline (candidate - baseline when higher is better,
    baseline - candidate otherwise) with bootstrap intervals, episodes better / worse and the sign test
    (:func:`train.evaluation.stats.paired_comparison`, resamples from ``default_rng(seed)``)."""
    if higher_is_better:
        r = paired_comparison(candidate, baseline, n_boot=n_boot, lower_is_better=True, seed=seed)
    else:
        r = paired_comparison(baseline, candidate, n_boot=n_boot, lower_is_better=True, seed=seed)
    return {"n": r["n"], "baseline_mean": r["candidate_mean"] if higher_is_better else r["baseline_mean"],
            "candidate_mean": r["baseline_mean"] if higher_is_better else r["candidate_mean"],
            "mean_gain": r["mean_reduction"], "mean_gain_ci": list(r["mean_reduction_ci"]),
            "median_gain": r["median_reduction"], "median_gain_ci": list(r["median_reduction_ci"]),
            "n_better": r["n_better"], "n_worse": r["n_worse"], "sign_test_p": r["sign_test_p"]}


def _per_episode(eps: list[dict]) -> dict:
    return {"saving_ratio": np.array([e["saving_ratio"] for e in eps]), "time_to_80_s": _censored_times(eps)}


def _compare(cand: dict, base: dict, base_name: str, n_boot: int, seed: int = 0) -> dict:
    out = {"saving_ratio": paired_gain(base["saving_ratio"], cand["saving_ratio"], n_boot=n_boot, seed=seed)}
    if base_name == "extremum_seeking":
        out["time_to_80_s"] = paired_gain(base["time_to_80_s"], cand["time_to_80_s"], higher_is_better=False,
                                          n_boot=n_boot, seed=seed)
    return out


def surfing_comparisons(episodes_by: dict[str, list[dict]], names: list[str], *, n_boot: int = N_BOOT,
                        seed: int = 0) -> dict:
    """Paired by episode: each policy in ``names`` against the three baselines, extremum seeking against
    the two PIDs, and (two or more policies) their per-episode mean ``policy_seed_mean`` against the
    baselines (the oracle ceilings are summarised, not compared: they know the wind)."""
    per = {n: _per_episode(episodes_by[n]) for n in [*BASELINE_NAMES, *names]}
    comps = {n: {b: _compare(per[n], per[b], b, n_boot, seed) for b in BASELINE_NAMES} for n in names}
    comps["extremum_seeking"] = {b: _compare(per["extremum_seeking"], per[b], b, n_boot, seed)
                                 for b in ("pid", "pid_formation")}
    if len(names) >= 2:
        group = {k: np.mean([per[n][k] for n in names], axis=0) for k in ("saving_ratio", "time_to_80_s")}
        comps["policy_seed_mean"] = {b: _compare(group, per[b], b, n_boot, seed) for b in BASELINE_NAMES}
    return comps


def evaluate_wake_surfing(policies, *, episodes: int = 100, seeds=None, es_gains=None, n_boot: int = N_BOOT,
                          turbulence_sigma_mps: float | None = None, oracle_margins_b=(), log=print,
                          scenario: str = "wake_surfing", oracle_keeper_margins_b=()) -> dict:
    """Every policy (SB3 zips) and the three baselines on the same held-out episodes; the report.
    ``turbulence_sigma_mps`` replaces the task's turbulence level (None: the task's); ``oracle_margins_b``
    adds the oracle set-point ceilings (:func:`train.evaluation.wake_surfing_rollout.oracle_surfer`) and
    ``oracle_keeper_margins_b`` the oracle station-keeper ceilings (:func:`~.wake_surfing_rollout.oracle_keeper`),
    reported beside the controllers but compared with none. ``scenario``: one of :data:`SCENARIOS` (the task's preset)."""
    from .episodes import eval_env_config

    if scenario not in SCENARIOS:
        raise ValueError(f"scenario must be one of {SCENARIOS}, got {scenario!r}")
    config = eval_env_config(scenario, "setpoints", turbulence_sigma_mps=turbulence_sigma_mps)
    seeds = list(seeds) if seeds is not None else [TEST_SEED_BASE + i for i in range(episodes)]
    surfers = [pid_surfer(), pid_formation_surfer(), es_surfer(es_gains)]
    names = []
    for p in policies:
        s = sb3_surfer(str(p))
        if s.name in names or s.name in BASELINE_NAMES:
            raise ValueError(f"two policies named {s.name!r}")
        names.append(s.name)
        surfers.append(s)
    surfers += [oracle_surfer(float(m)) for m in oracle_margins_b]
    surfers += [oracle_keeper(float(m)) for m in oracle_keeper_margins_b]
    episodes_by = {}
    for s in surfers:
        t0 = time.perf_counter()
        episodes_by[s.name] = fly(s, seeds, config=config, keep_series=False)
        summ = summarise_surfer(episodes_by[s.name], n_boot=n_boot)
        log(f"{s.name}: saving {summ['saving']:.4f}, ratio to optimum {summ['saving_ratio']:.3f} "
            f"[{summ['saving_ratio_ci'][0]:.3f}, {summ['saving_ratio_ci'][1]:.3f}], reached 80 % in "
            f"{summ['reached_80_frac']:.2f} of episodes, >1 s outside the box {summ['box_outside_over_1s']}, "
            f"collisions {summ['collisions']} ({time.perf_counter() - t0:.0f} s)")
    specs = {s.name: str(p) for s, p in zip(surfers[3:], policies)}
    return surfing_report(episodes_by, names, scenario=scenario, seeds=seeds, randomisation=config.randomisation,
                          policy_specs=specs, n_boot=n_boot)


def surfing_report(episodes_by: dict, names, *, scenario: str, seeds, randomisation, policy_specs=None,
                   n_boot: int = N_BOOT) -> dict:
    """The report of :func:`evaluate_wake_surfing` from the episodes every controller flew on ``seeds``
    (``episodes_by``: name -> :func:`~.wake_surfing_rollout.fly`'s list; the baselines under their names, the
    policies under ``names``, any other entry an oracle ceiling, summarised but compared with none)."""
    seeds = [int(x) for x in seeds]
    for n, e in episodes_by.items():
        if [int(x["seed"]) for x in e] != seeds:
            raise ValueError(f"surfing_report: {n!r} flew other episodes than the seeds given")
    report = {"scenario": scenario, "seeds": seeds, "turbulence_sigma_mps": randomisation.turbulence_sigma_mps,
              "randomisation": dataclasses.asdict(randomisation), "controllers": {n: {"summary": summarise_surfer(e, n_boot=n_boot), "episodes": e}
                                              for n, e in episodes_by.items()}}
    comps = surfing_comparisons(episodes_by, names, n_boot=n_boot)
    if len(names) >= 2:
        report["seed_spread"] = {k: {"mean": float(np.mean(v)), "std": float(np.std(v, ddof=1)), "min": float(np.min(v)),
                                     "max": float(np.max(v))}
                                 for k, v in {m: [report["controllers"][n]["summary"][m] for n in names]
                                              for m in ("saving", "saving_ratio", "time_to_80_s_mean_censored")}.items()}
    report["comparisons"] = comps
    report["policy_specs"] = dict(policy_specs or {})
    report["groups"] = surfing_groups(names)
    report["aggregates"] = evaluation_aggregates(episodes_by, report["groups"], list(BASELINE_NAMES), n_boot=n_boot)
    report["markdown"] = markdown(report)
    return report


def surfing_groups(names: list[str]) -> dict[str, list[str]]:
    """The policies as seed groups: ``<name>_seed<k>`` groups, else all of them as ``policy_seeds`` (two or more)."""
    groups = seed_groups(names)
    grouped = {n for m in groups.values() for n in m}
    rest = [n for n in names if n not in grouped]
    if len(rest) >= 2:
        groups["policy_seeds"] = rest
    return groups


def markdown(report: dict) -> str:
    rows = ["| controller | saving | ratio to optimum [95 % CI] | reached 80 % | time to 80 % (s, censored mean [CI]; median) "
            "| >1 s outside box | collisions | min separation (m) |", "|---|---|---|---|---|---|---|---|"]
    for n, r in report["controllers"].items():
        s = r["summary"]
        rows.append(f"| {n} | {s['saving']:.4f} | {s['saving_ratio']:.3f} [{s['saving_ratio_ci'][0]:.3f}, "
                    f"{s['saving_ratio_ci'][1]:.3f}] | {100 * s['reached_80_frac']:.0f} % | "
                    f"{s['time_to_80_s_mean_censored']:.1f} [{s['time_to_80_s_mean_censored_ci'][0]:.1f}, "
                    f"{s['time_to_80_s_mean_censored_ci'][1]:.1f}]; {s['time_to_80_s_median_censored']:.1f} | "
                    f"{s['box_outside_over_1s']} (worst {s['box_outside_longest_s_worst']:.1f} s) | {s['collisions']} | "
                    f"{s['min_separation_m']:.2f} |")
    rows += ["", "| candidate | baseline | ratio gain [95 % CI] | better / worse | time saved to 80 % (s) [95 % CI] |",
             "|---|---|---|---|---|"]
    for n, comps in report["comparisons"].items():
        for b, c in comps.items():
            g = c["saving_ratio"]
            t = c.get("time_to_80_s")
            rows.append(f"| {n} | {b} | {g['mean_gain']:+.3f} [{g['mean_gain_ci'][0]:+.3f}, {g['mean_gain_ci'][1]:+.3f}] | "
                        f"{g['n_better']} / {g['n_worse']} | "
                        + (f"{t['mean_gain']:+.1f} [{t['mean_gain_ci'][0]:+.1f}, {t['mean_gain_ci'][1]:+.1f}]" if t else "") + " |")
    agg = aggregates_table(report.get("aggregates") or {})
    if agg:
        rows += ["", "Over training seeds x episodes (rliable, stratified bootstrap 95 %):", "", agg]
    return "\n".join(rows) + "\n"


def tune_es(grid: dict[str, list[float]], *, seeds=TUNING_SEEDS, log=print) -> list[dict]:
    """The extremum seeker's sweep: every combination of ``grid`` (ExtremumSeekingGains fields) on the
    training-range ``seeds``; the mean saving ratio of each, best first."""
    import itertools

    from agents.extremum_seeking import ExtremumSeekingGains

    keys = list(grid)
    out = []
    for values in itertools.product(*(grid[k] for k in keys)):
        combo = dict(zip(keys, values))
        inner = combo.pop("inner", None)  # what flies the set-point (agents.extremum_seeking.INNER_LOOPS)
        gains = ExtremumSeekingGains(**combo)
        eps = fly(es_surfer(gains, inner=inner), seeds)
        s = summarise_surfer(eps, n_boot=200)
        row = {**dict(zip(keys, values)), "saving_ratio": s["saving_ratio"], "reached_80_frac": s["reached_80_frac"],
               "time_to_80_s_mean_censored": s["time_to_80_s_mean_censored"], "box_outside_over_1s": s["box_outside_over_1s"]}
        log(json.dumps(row))
        out.append(row)
    return sorted(out, key=lambda r: -r["saving_ratio"])


def plot_surfing_figure(path, policy_zip: str, *, es_gains=None, crosswind_mps: float = 4.0, seed: int = TEST_SEED_BASE,
                        overwrite: bool = False) -> Path:
    """Two panels: the follower's saving over the safe box (x = -2 spans) in calm air and in a steady
    crosswind, with the reference optimum and the paths of the policy and the extremum seeker flying
    a demonstration episode (no turbulence, no manoeuvre) from the nominal slot."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from formation_env.sim.config import Randomisation
    from formation_env.io import save_figure
    from formation_env.scenarios import get_scenario
    from formation_env.tasks.wake_surfing.optimum import reference_optimum, saving_in_crosswind

    from .episodes import eval_env_config

    box = np.asarray(get_scenario("wake_surfing").safe_box_b)
    cfg = eval_env_config("wake_surfing", "setpoints")
    import dataclasses

    cfg = dataclasses.replace(cfg, randomisation=Randomisation())
    y = np.linspace(box[1, 0], box[1, 1], 61)
    z = np.linspace(box[2, 0], box[2, 1], 36)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True, constrained_layout=True)
    for ax, wind in zip(axes, (0.0, crosswind_mps)):
        crab = math.asin(wind / 25.0)
        yy, zz = np.meshgrid(y, z, indexing="ij")
        grid = np.stack([np.full_like(yy, -2.0), yy, zz], axis=-1)
        sav = saving_in_crosswind(grid, crab)
        cs = ax.contourf(yy, zz, sav, levels=np.linspace(-0.1, 0.6, 29), cmap="viridis", extend="both")  # the optimum: 0.56
        oy, oz, osav = reference_optimum(crab)
        ax.plot(float(oy), float(oz), marker="*", ms=16, color="white", mec="k", label=f"reference optimum ({float(osav):.3f})")
        ax.plot(1.0, 0.3, marker="s", ms=8, color="tab:red", mec="k", label="nominal slot (thesis PID)")
        for surfer, colour, lw in ((es_surfer(es_gains), "magenta", 1.0), (sb3_surfer(policy_zip, "policy"), "tab:orange", 2.2)):
            ep = fly(surfer, [seed], config=cfg, keep_series=True, crosswind_mps=wind)[0]
            ax.plot(ep["series"]["lateral_b"], ep["series"]["vertical_b"], color=colour, lw=lw,
                    label=f"{'PPO policy' if surfer.name == 'policy' else 'extremum seeking'} (mean saving {ep['saving']:.3f})")
        ax.add_patch(plt.Rectangle((box[1, 0], box[2, 0]), box[1, 1] - box[1, 0], box[2, 1] - box[2, 0], fill=False,
                                   ec="k", lw=1.5, ls="--"))
        ax.set_xlim(box[1, 0] - 0.05, box[1, 1] + 0.05)
        ax.set_ylim(box[2, 1] + 0.05, box[2, 0] - 0.05)  # z down: the leader's wake plane at the top
        ax.set_xlabel("follower starboard of the leader (spans)")
        ax.set_title(f"crosswind {wind:g} m/s (crab {math.degrees(crab):.1f} deg), 2 spans behind")
        ax.legend(loc="lower right", fontsize=7)
    axes[0].set_ylabel("follower below the leader (spans)")
    fig.colorbar(cs, ax=axes, label="follower induced-drag saving")
    out = save_figure(fig, path, overwrite=overwrite, dpi=110)
    plt.close(fig)
    return out


def write_outputs(out: Path, report: dict, *, overwrite: bool = False) -> list[Path]:
    """With several policy seeds: ``marl_eval.json`` (every controller's episodes in marl-eval's format, the
    oracle ceilings left out) and ``performance_profile.png`` (the rliable profiles of the harvest ratio)."""
    if not report.get("aggregates"):
        return []
    eps = {n: r["episodes"] for n, r in report["controllers"].items()}
    specs = report.get("policy_specs", {})
    data = marl_eval_data("wake_surfing", eps, report["groups"], list(BASELINE_NAMES),
                          step_counts={n: training_steps(p) for n, p in specs.items()})
    return [write_marl_eval(out / "marl_eval.json", data, overwrite=overwrite),
            plot_profiles(out / "performance_profile.png", profile_panels(report["aggregates"]), overwrite=overwrite,
                          title=f"wake surfing: {len(report['seeds'])} held-out episodes")]


def _rounded(x, digits: int = 5):
    """Floats rounded to ``digits`` decimals throughout (the committed JSON stays small)."""
    if isinstance(x, float):
        return round(x, digits)
    if isinstance(x, dict):
        return {k: _rounded(v, digits) for k, v in x.items()}
    if isinstance(x, list):
        return [_rounded(v, digits) for v in x]
    return x


def main(argv=None) -> int:
    """The command line; a bad argument or unreadable policy exits 2 with one line naming it."""
    import zipfile

    try:
        return _main(argv)
    except (ValueError, OSError, zipfile.BadZipFile) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


def _main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m train.evaluation.wake_surfing_eval", description=__doc__.split("\n\n")[0])
    p.add_argument("policies", nargs="*", help="SB3 zips (name them <group>_seed<k>.zip)")
    p.add_argument("--episodes", type=int, default=100)
    p.add_argument("--out", help="a new directory for results.json / results.md")
    p.add_argument("--figure", help="write the saving-map figure here (needs a policy)")
    p.add_argument("--overwrite", action="store_true")
    p.add_argument("--tune-es", action="store_true", help="run the extremum seeker's gain sweep on training seeds")
    p.add_argument("--turbulence", type=float, default=None, help="turbulence sigma, m/s (default: the task's 0.25)")
    p.add_argument("--scenario", default="wake_surfing", choices=SCENARIOS,
                   help="the task (default) or its randomised-leader variant (leader weight and speed drawn per episode)")
    p.add_argument("--oracle-margins", type=float, nargs="*", default=[0.05, 0.1],
                   help="oracle set-point ceilings to add, spans below the reference optimum")
    p.add_argument("--oracle-keeper-margins", type=float, nargs="*", default=[],
                   help="oracle station-keeper ceilings to add (station_keeper flown to the true-wind optimum), spans "
                        "below the reference optimum, each in [0, 0.7]")
    a = p.parse_args(argv)
    if a.tune_es:
        rows = tune_es(ES_GRID)
        print(json.dumps(rows[:5], indent=1))
        return 0
    if a.episodes < 1:
        print(f"error: --episodes must be >= 1, got {a.episodes}", file=sys.stderr)
        return 2
    if a.turbulence is not None and not (math.isfinite(a.turbulence) and a.turbulence >= 0):
        print(f"error: --turbulence must be a finite number >= 0, got {a.turbulence}", file=sys.stderr)
        return 2
    missing = [p for p in a.policies if not Path(p).is_file()]
    if missing:
        print(f"error: policy file {missing[0]!r} does not exist", file=sys.stderr)
        return 2
    out = None
    if a.out:
        from formation_env.io import prepare_output_dir

        out = prepare_output_dir(a.out, overwrite=a.overwrite)
    for m in list(a.oracle_margins) + list(a.oracle_keeper_margins):
        if not (math.isfinite(m) and 0.0 <= m <= 0.7):
            print(f"error: an oracle margin must be in [0, 0.7] spans (the box's depth), got {m}", file=sys.stderr)
            return 2
    report = evaluate_wake_surfing(a.policies, episodes=a.episodes, turbulence_sigma_mps=a.turbulence,
                                   oracle_margins_b=a.oracle_margins, scenario=a.scenario,
                                   oracle_keeper_margins_b=a.oracle_keeper_margins)
    if out is not None:
        from formation_env.io import atomic_write_json, atomic_write_text

        atomic_write_json(out / "results.json", _rounded(json.loads(json.dumps(report, default=float))), overwrite=a.overwrite)
        r = report["randomisation"]
        head = (f"# Wake surfing: held-out evaluation\n\n{len(report['seeds'])} episodes (seeds {report['seeds'][0]}.."
                f"{report['seeds'][-1]}, never used in training or model selection): crosswind +-{r['crosswind_mps']:g} m/s, "
                f"leader turn +-{r['leader_turn_deg']:g} deg and speed change +-{r['leader_speed_mps']:g} m/s"
                + (f", leader speed 25 {r['leader_speed_offset_min_mps']:+g}..{r['leader_speed_offset_max_mps']:+g} m/s and "
                   f"fuel 2 {r['leader_fuel_offset_min_kg']:+g}..{r['leader_fuel_offset_max_kg']:+g} kg drawn per episode"
                   if any(r.get(k) for k in ("leader_fuel_offset_min_kg", "leader_fuel_offset_max_kg",
                                             "leader_speed_offset_min_mps", "leader_speed_offset_max_mps"))
                   else "")
                + f", frozen turbulence field sigma {r['turbulence_sigma_mps']:g} m/s, wake on. Saving counted as 0 outside the safe box; ratio = per-episode "
                "saving / reference optimum's; intervals 95 % percentile bootstrap over episodes (10,000 resamples, "
                "seed 0), Wilson for rates. Oracle rows know the wind (a ceiling, not a controller).\n\n")
        atomic_write_text(out / "results.md", head + report["markdown"], overwrite=a.overwrite)
        write_outputs(out, report, overwrite=a.overwrite)
    print(report["markdown"])
    if a.figure and a.policies:
        print(plot_surfing_figure(a.figure, a.policies[0], overwrite=a.overwrite))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
