"""Evaluation of policies (SB3 zips, RLlib checkpoints or the thesis PID) on held-out seeds, wake and Dryden turbulence on.

Every policy flies the same episodes: formation ``f`` of the batch is the episode with seed
``seeds[f]`` (exactly what a single env reset with that seed gives), the followers are the agents,
the leader flies the PID on its path. The PID baseline is the residual action mode with zero action
(bit for bit the thesis FCS).

Metrics (per episode, over the learning UAVs, sampled at every decision, 10 Hz):

=============================  ======================================================================
rms_slot_error_m               RMS distance of the CG from its slot over the episode
max_slot_error_m               largest distance from the slot
time_within_1m_s / _frac       time (and fraction of the episode) within 1 m of the slot
min_separation_m               smallest CG distance to another UAV at the decision instants
collision / crashed            the episode ended by a collision (CG separation < collision_separation_b
                               spans, checked at every physics step) / an envelope exit
control_effort_rad             RMS of (elevator, aileron, rudder) minus trim, rad
throttle_mean                  mean throttle command
throttle_saturated_frac        fraction of the decisions with the throttle command at either limit
action_rms                     RMS of the agent's normalised action (0 for the PID)
fuel_used_kg, leader_fuel_kg   fuel burnt by the followers (mean) and by the leader
fuel_saving_pct                100 (1 - follower fuel / leader fuel)
induced_drag_saving            mean ELL induced-drag saving of the followers (with ``compute_benefit``)
harvest_ratio                  (a task with a reference optimum) mean over the decisions of the saving
                               capped at the optimum of the task's allowed region, over that optimum (the
                               time not flown: no saving); ``harvest_ratio_uncapped`` without the cap; in
                               an N-UAV task each follower's saving capped at its own saving at the joint
                               optimum, over the followers' mean optimum
induced_drag_saving_uav<k>     (several learning followers) follower k's own mean saving
formation_saving               (with the wake) the formation's induced-drag saving, every UAV's (the leader's
                               included) against every UAV alone: 1 - sum D_i(formation) / sum D_i(alone)
                               (the ELL's newtons), mean over the decisions (the time not flown: none)
reconfig_success               (scenarios with a moving slot) no collision or crash and every follower
                               within 1 span (2.9 m) of its final slot for the last 5 s
reconfig_time_s                time from the start of the slot schedule until the follower is within
                               1 span of its final slot for good (NaN when it never is)
=============================  ======================================================================

Statistics (95 %; :mod:`train.evaluation.stats` on SciPy, :mod:`train.evaluation.aggregates` on rliable;
every bootstrap 10,000 resamples from a fixed seed, so the same episodes always give the same numbers):

* per policy (``summary``): the means above, ``rms_slot_error_m_ci`` (``scipy.stats.bootstrap``
  percentile interval of the mean), ``collisions`` / ``collision_rate`` / ``collision_rate_ci`` (Wilson,
  ``scipy.stats.binomtest``), ``reconfig_success_rate`` / ``reconfig_success_rate_ci`` (Wilson),
  ``min_separation_m`` (smallest over all episodes) and ``min_separation_m_p05`` (5th percentile of the
  per-episode minima);
* ``comparisons[<policy>][<baseline>]``: every policy against each baseline evaluated beside it ("pid",
  "pid_formation", "station_keeper"; and each baseline against the ones before it), paired by episode: :func:`train.evaluation.stats.paired_comparison`
  of the per-episode RMS slot error (reduction = baseline - policy, m, mean and median with intervals,
  relative reduction of the mean, fraction of episodes better, sign test) and, with a moving slot,
  :func:`train.evaluation.stats.paired_rate_difference` of the reconfiguration success;
* ``groups[<name>]``: policies ``<name>_seed<k>`` (the same recipe trained with several seeds; two or
  more), or the ``groups`` argument: each summary metric's mean, std (ddof 1), min and max across the
  seeds, and the paired comparison of the seed-averaged per-episode metric against each baseline;
* ``aggregates`` (with a group of two or more seeds): rliable's IQM, mean and median of the task's
  score over runs x episodes with stratified bootstrap intervals, the probability of improvement of each
  group over each baseline, and the performance profiles (:func:`train.evaluation.aggregates.evaluation_aggregates`;
  ``performance_profile.png``); ``marl_eval.json`` has the same episodes in marl-eval's format.

The parts: :mod:`train.evaluation.policy` (:class:`EvalPolicy`), :mod:`train.policy_loader`
(:func:`load_policy`), :mod:`train.evaluation.episodes` (the episodes and their metrics),
:mod:`train.evaluation.summary`, :mod:`train.evaluation.comparisons`, :mod:`train.evaluation.aggregates`,
:mod:`train.evaluation.marl_eval` and :mod:`train.evaluation.report` (tables, plots).
This module runs them (:func:`evaluate`) and re-exports their names.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from ..config import TEST_SEED_BASE
from .episodes import SPAN_M, SUCCESS_WINDOW_S, eval_env_config, run_episodes
from .policy import EvalPolicy
from .aggregates import INSTALL_HINT, aggregates_table, evaluation_aggregates, plot_profiles, profile_panels
from .comparisons import BASELINES, compare_episodes, comparisons, group_report, seed_groups
from .policy_loader import load_policy
from .marl_eval import marl_eval_data, training_steps, write_marl_eval
from .report import write_plots, comparison_table, groups_table, markdown_table
from .stats import N_BOOT
from .summary import selection_score, summarise

__all__ = ["EvalPolicy", "load_policy", "run_episodes", "summarise", "evaluate", "eval_env_config", "compare_episodes",
           "comparisons", "seed_groups", "group_report", "BASELINES", "TEST_EPISODES", "SUCCESS_WINDOW_S", "SPAN_M",
           "selection_score", "markdown_table", "comparison_table", "groups_table"]

MAX_EPISODES = 10_000                  # episodes per policy at most (they fly as one batch)
from formation_env.constants import MAX_DURATION_S  # noqa: E402  longest episode a duration override may ask for
TEST_EPISODES = 100                    # held-out test episodes per policy by default


def evaluate(policies: Sequence[str], *, scenario: str, episodes: int = TEST_EPISODES, seeds: Sequence[int] | None = None,
             turbulence_sigma_mps: float | None = None, wake: bool = True, compute_benefit: bool = False,
             action_mode: str | None = None, out_dir: str | Path | None = None, overwrite: bool = False,
             plots: bool = True, duration_s: float | None = None, groups: dict[str, Sequence[str]] | None = None,
             turbulence_field: str | None = None, ablations: Sequence[str | Sequence[str]] = (),
             wake_fidelity: str | None = None, throttle_max: float = 1.0, leader_reference: str | None = None,
             n_boot: int = N_BOOT,
             log: Callable[[str], None] | None = None) -> dict:
    """Evaluate ``policies`` ("pid", "pid_formation", SB3 zips or RLlib checkpoints) on the same held-out
    episodes (``episodes`` seeds from ``TEST_SEED_BASE``, or from ``seeds[0]``, or exactly ``seeds`` when
    it holds several: then ``episodes`` is not used); optionally write ``results.json``, ``results.md``
    and comparison plots into ``out_dir`` (a new directory). ``ablations``: observation groups to hide, each an
    entry like ``"induced_wind,induced_rotation"``; every learned policy is also flown with each hidden
    (:mod:`train.evaluation.ablation`, named ``<policy>-without-<groups>``) on the same episodes. ``throttle_max``: the
    flight control's throttle ceiling (above 1 the counterfactual engine of a ceiling measurement; the report records
    it then). ``leader_reference``: "ground" or "air", how vehicle 0's reference moves (None: the scenario's; the report
    records a choice).

    The report: ``policies.<name>.summary`` / ``.episodes`` (see :func:`summarise`), ``comparisons``
    (:func:`comparisons`: every policy against each baseline evaluated with it), ``groups`` (seed groups:
    policies ``<name>_seed<k>`` and the ``groups`` argument {group: [policy names]}, see
    :func:`group_report`), ``statistics`` (how the intervals were computed) and the markdown tables."""
    from formation_env.sim.config import EnvConfig
    from formation_env.scenarios import get_scenario, scenario_names
    from formation_env.sim.formation import WakeConfig, resolve_coupling, resolve_fidelity

    if scenario not in scenario_names():
        raise ValueError(f"unknown scenario {scenario!r}; available: {scenario_names()}")
    if not policies:
        raise ValueError("give at least one policy (a .zip path, an RLlib checkpoint, 'pid' or 'pid_formation')")
    if isinstance(episodes, bool) or not isinstance(episodes, int) or not 1 <= episodes <= MAX_EPISODES:
        raise ValueError(f"episodes must be an integer in [1, {MAX_EPISODES}], got {episodes!r}")
    if duration_s is not None and not (isinstance(duration_s, (int, float)) and math.isfinite(duration_s)
                                       and 0 < duration_s <= MAX_DURATION_S):
        raise ValueError(f"duration must be a number of seconds in (0, {MAX_DURATION_S:g}], got {duration_s!r}")
    # a bad ceiling or leader reference fails before any output
    default = eval_env_config(scenario, "setpoints", throttle_max=throttle_max, leader_reference=leader_reference)
    if turbulence_sigma_mps is None:  # the test set's level: 1 m/s, or a task preset's own (wake_surfing)
        turbulence_sigma_mps = default.randomisation.turbulence_sigma_mps
    if not (isinstance(turbulence_sigma_mps, (int, float)) and math.isfinite(turbulence_sigma_mps) and turbulence_sigma_mps >= 0):
        raise ValueError(f"turbulence sigma must be a finite number >= 0, got {turbulence_sigma_mps!r}")
    if seeds is None or len(seeds) == 0:
        seeds = [TEST_SEED_BASE + i for i in range(episodes)]
    elif len(seeds) == 1:
        seeds = [int(seeds[0]) + i for i in range(episodes)]
    else:
        seeds = [int(s) for s in seeds]
    if any(s < 0 or s >= 2 ** 63 for s in seeds):
        raise ValueError(f"seeds must be in [0, 2**63), got {[s for s in seeds if s < 0 or s >= 2 ** 63]}")
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"seeds must be distinct (each is one episode), got duplicates "
                         f"{sorted({s for s in seeds if seeds.count(s) > 1})}")
    if len(seeds) > MAX_EPISODES:
        raise ValueError(f"at most {MAX_EPISODES} episodes (seeds), got {len(seeds)}")
    loaded, specs = [], {}
    for spec in policies:
        pol = load_policy(spec, action_mode=action_mode if spec not in BASELINES else None)
        base, n = pol.name, 2
        while pol.name in [p.name for p in loaded]:
            pol.name = f"{base}-{n}"
            n += 1
        loaded.append(pol)
        specs[pol.name] = spec
    if ablations:
        from formation_env.scenarios import get_scenario as _scenario
        from formation_env.sim.layout import ObservationLayout

        from .ablation import ablated, parse_ablation

        hidden = [parse_ablation(a) for a in ablations]
        sc = _scenario(scenario)
        for pol in [p for p in loaded if specs[p.name] not in BASELINES]:
            layout = ObservationLayout.of(sc.n_vehicles, sc.neighbour_count, pol.observation.options)  # the env's
            for hide in hidden:  # not ``groups``: that is the seed-group argument
                copy = ablated(pol, hide, layout)
                loaded.append(copy)
                specs[copy.name] = specs[pol.name]
    names = [p.name for p in loaded]
    group_spec = seed_groups(names)
    for g, members in (groups or {}).items():
        members = list(members)
        unknown = [m for m in members if m not in names]
        if not members or unknown:
            raise ValueError(f"group {g!r}: {'no policies' if not members else f'unknown policy name(s) {unknown}'}; "
                             f"the evaluated policies are {names}")
        group_spec[g] = members
    baselines = {}
    for name in names:  # the first policy of each baseline kind is the one compared against
        if specs[name] in BASELINES and specs[name] not in baselines:
            baselines[specs[name]] = name
    out = None
    if out_dir is not None:
        from formation_env.io import prepare_output_dir

        out = prepare_output_dir(out_dir, overwrite=overwrite)
    results = {}
    for pol in loaded:
        cfg = eval_env_config(scenario, pol.action_mode, turbulence_sigma_mps=turbulence_sigma_mps, wake=wake,
                              turbulence_field=turbulence_field, wake_fidelity=wake_fidelity, throttle_max=throttle_max,
                              leader_reference=leader_reference, control_hz=pol.control_hz, compute_benefit=compute_benefit, duration_s=duration_s,
                              observation=pol.observation)
        t0 = time.perf_counter()
        eps = run_episodes(pol, cfg, seeds, keep_series=True)
        summ = summarise(eps, n_boot=n_boot)
        summ["wall_s"] = round(time.perf_counter() - t0, 2)
        results[pol.name] = {"policy": pol.path or specs[pol.name], "action_mode": pol.action_mode, "summary": summ,
                             "episodes": eps}
        if log:
            lo, hi = summ["rms_slot_error_m_ci"]
            log(f"{pol.name}: RMS slot error {summ['rms_slot_error_m']:.3f} m [{lo:.3f}, {hi:.3f}] (along / lateral / "
                f"vertical {summ['rms_along_track_m']:.3f} / {summ['rms_lateral_m']:.3f} / {summ['rms_vertical_m']:.3f} m), "
                + (f"harvest ratio {summ['harvest_ratio']:.3f}, " if "harvest_ratio" in summ else "")
                + f"collisions {summ['collisions']}/{len(seeds)}"
                + (f", reconfiguration success {summ['reconfig_success_rate']:.2f}" if "reconfig_success_rate" in summ else "")
                + f" ({summ['wall_s']:.1f} s)")
    episodes_by_name = {n: r["episodes"] for n, r in results.items()}
    comps = comparisons(episodes_by_name, baselines, candidates=[n for n in names if specs[n] not in BASELINES],
                        n_boot=n_boot)
    base_eps = {b: episodes_by_name[b] for b in baselines.values()}
    group_reports = {g: group_report({m: results[m] for m in members}, base_eps, n_boot=n_boot)
                     for g, members in group_spec.items()}
    report = {"scenario": scenario, "seeds": seeds, "wake": wake, "turbulence_sigma_mps": turbulence_sigma_mps,
              "turbulence_field": EnvConfig.turbulence_field if turbulence_field is None else turbulence_field,
              "wake_coupling": resolve_coupling(WakeConfig(), scenario=get_scenario(scenario)),
              "wake_fidelity": wake_fidelity or resolve_fidelity(scenario=get_scenario(scenario)),
              **({} if throttle_max == 1.0 else {"throttle_max": float(throttle_max)}),
              **({} if leader_reference is None else {"leader_reference": leader_reference}),
              "policies": {n: {k: v for k, v in r.items()} for n, r in results.items()},
              "baselines": baselines, "comparisons": comps, "groups": group_reports,
              "statistics": {"confidence": 0.95, "n_boot": n_boot, "bootstrap_seed": 0,
                             "bootstrap": "scipy.stats.bootstrap, percentile, episodes resampled jointly across the "
                                          "paired policies (paired=True)",
                             "rates": "Wilson score interval (scipy.stats.binomtest.proportion_ci)",
                             "sign_test": "exact two-sided (scipy.stats.binomtest), ties left out",
                             "reduction": "baseline - policy, per episode, in the metric's units",
                             "aggregates": "rliable: IQM / mean / median, stratified bootstrap over runs x episodes, "
                                           "probability of improvement, performance profiles"}}
    report["table_markdown"] = markdown_table({n: r["summary"] for n, r in results.items()})
    report["comparison_markdown"] = comparison_table(comps, group_reports)
    report["groups_markdown"] = groups_table(group_reports)
    report["aggregates"] = _aggregates(episodes_by_name, group_spec, list(baselines.values()), n_boot, log)
    report["aggregates_markdown"] = aggregates_table(report["aggregates"])
    multi = {g: m for g, m in group_spec.items() if len(m) >= 2}
    sizes = sorted({len(m) for m in multi.values()})
    if out is not None and len(sizes) > 1:  # marl-eval's format cannot hold them; the evaluation stands (levels go on)
        report["marl_eval"] = (f"marl_eval.json not written: marl-eval needs the same number of runs for every "
                               f"algorithm, the seed groups have {sizes} ({', '.join(sorted(multi))})")
        if log:
            log(report["marl_eval"])
    if out is not None:
        from formation_env.io import atomic_write_json, atomic_write_text

        slim = json.loads(json.dumps(report, default=float))
        for r in slim["policies"].values():
            for e in r["episodes"]:
                e["series"]["slot_error_m"] = [round(x, 4) for x in e["series"]["slot_error_m"]]
                e["series"].pop("t")
        atomic_write_json(out / "results.json", slim, overwrite=overwrite)
        head = (f"# Evaluation: {scenario}\n\n{len(seeds)} held-out episodes (seeds {seeds[0]}..{seeds[-1]}), "
                f"wake {'on' if wake else 'off'} ({report['wake_coupling']} coupling, {report['wake_fidelity']} fidelity), turbulence {report['turbulence_field']} "
                f"sigma {turbulence_sigma_mps:g} m/s"
                + ("" if throttle_max == 1.0 else f", throttle ceiling {throttle_max:g} (a counterfactual engine)")
                + ("" if leader_reference is None else f", the leader's reference {leader_reference}-relative")
                + ". Intervals: 95 %, "
                f"percentile bootstrap over episodes (scipy.stats.bootstrap, {n_boot} resamples, seed 0) for errors, "
                f"Wilson for rates; rliable aggregates over training seeds x episodes.\n\n")
        text = head + report["table_markdown"]
        if report["comparison_markdown"]:
            text += ("\n## Paired comparisons (per-episode RMS slot error; reduction = baseline - policy)\n\n"
                     + report["comparison_markdown"])
        if report["groups_markdown"]:
            text += "\n## Training seeds\n\n" + report["groups_markdown"]
        if report["aggregates_markdown"]:
            text += ("\n## Aggregates over training seeds and episodes (rliable; stratified bootstrap, 95 %)\n\n"
                     + report["aggregates_markdown"])
        atomic_write_text(out / "results.md", text, overwrite=overwrite)
        if multi and "marl_eval" not in report:
            write_marl_eval(out / "marl_eval.json", marl_eval_data(
                scenario, episodes_by_name, multi, list(baselines.values()),
                step_counts={n: training_steps(r["policy"]) for n, r in results.items()}), overwrite=overwrite)
        if plots:
            report["plots"] = write_plots(out, results, scenario, overwrite=overwrite)
            if report["aggregates"].get("scores"):
                report["plots"].append(str(plot_profiles(
                    out / "performance_profile.png", profile_panels(report["aggregates"]), overwrite=overwrite,
                    title=f"{scenario}: {len(seeds)} held-out episodes")))
        report["out_dir"] = str(out)
    return report


def _aggregates(episodes: dict, groups: dict, baselines: list[str], n_boot: int, log) -> dict:
    """:func:`evaluation_aggregates` of the seed groups (two or more seeds) and baselines; without rliable
    (the evaluation extra) a note instead, so that an evaluation never fails for want of it."""
    if not any(len(m) >= 2 for m in groups.values()):
        return {}
    try:
        agg = evaluation_aggregates(episodes, groups, baselines, n_boot=n_boot)
    except ImportError:
        if log:
            log(f"note: no rliable aggregates ({INSTALL_HINT})")
        return {"skipped": INSTALL_HINT}
    return agg
