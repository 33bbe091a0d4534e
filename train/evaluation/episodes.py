"""The evaluation episodes: their env configuration and the batched rollout that measures every
per-episode metric (the table in :mod:`train.evaluation.evaluate`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from formation_env.rollout import Recorder
from formation_env.sim.energy import ENERGY_COLUMNS
from formation_env.tasks.evaluation import longest_run

from .summary import PER_UAV_PREFIX

__all__ = ["eval_env_config", "run_episodes", "reference_saving", "reference_savings", "longest_run", "SPAN_M", "SUCCESS_WINDOW_S",
           "FAILURE_SLOT_ERROR_M"]

from formation_env.constants import AEROSONDE_SPAN_M as SPAN_M  # noqa: E402
SUCCESS_WINDOW_S = 5.0
#: the slot error (m) an episode that ended early is charged for each decision it did not fly: far beyond any
#: error of an episode flown to the end (the thesis PID's worst RMS in turbulence is ~16 m), and the reward's own
#: terminal error cap (formation_env.sim.observe), so a crash never scores better than flying on
FAILURE_SLOT_ERROR_M = 100.0
DEFAULT_TURBULENCE_SIGMA_MPS = 1.0  # the test set's Dryden level (scenarios without a task preset)


def eval_env_config(scenario: str, action_mode: str, *, turbulence_sigma_mps: float | None = None, wake: bool = True,
                    control_hz: float = 10.0, compute_benefit: bool = False, duration_s: float | None = None,
                    turbulence_field: str | None = None, wake_fidelity: str | None = None, throttle_max: float = 1.0,
                    leader_reference: str | None = None, observation=None):
    """The evaluation episodes' EnvConfig: the thesis scenario with wake and turbulence on (``turbulence_field``
    None: the env's default field, one frozen von Karman field per formation). With
    its defaults (sigma 1 m/s, wake on, the scenario's duration, no other randomisation than the task's
    ``test_randomisation``: close_formation jitters the follower's start by 0.3 m; the benefit computed for a
    task with a reference optimum, whose harvest ratio needs it) it is the test set's distribution, which the training's validation (model selection) also uses. A scenario with a
    task whose evaluation protocol has a preset (:attr:`formation_env.tasks.EvaluationProtocol.preset`: ``wake_surfing``)
    flies its preset's randomisation and reward, with the benefit on, at ``turbulence_sigma_mps`` (None: the preset's
    level). ``wake_fidelity`` None: the
    scenario's (formation_env.sim.formation.WAKE_FIDELITIES; a record flown before a task changed fidelity is re-flown
    with the fidelity it records). ``throttle_max``: the flight control's throttle ceiling (1: the Aerosonde's; above 1
    the counterfactual engine of the ceiling measurements, :class:`formation_env.sim.config.EnvConfig`).
    ``leader_reference``: "ground" or "air" (how vehicle 0's reference moves, EnvConfig.leader_reference); None the
    scenario's. ``observation``: the :class:`~formation_env.sim.layout.ObservationLayout` a policy was trained on (its
    optional groups switched on; None: none)."""
    from formation_env.sim.config import EnvConfig, Randomisation
    from formation_env.tasks import task_for_scenario, task_learning

    if turbulence_field is None:
        turbulence_field = EnvConfig.turbulence_field  # the dataclass default
    switches = {} if observation is None else observation.options  # the optional groups it observes
    t = task_for_scenario(scenario)
    preset = None if t is None or t.evaluation.preset is None else dict(t.evaluation.preset)
    if preset:  # the task's own test distribution (wake_surfing): its randomisation, reward and benefit, at this level
        rnd = preset.pop("randomisation")
        if turbulence_sigma_mps is not None:
            rnd = dataclasses.replace(rnd, turbulence_sigma_mps=turbulence_sigma_mps)
        preset["compute_benefit"] = True
        return EnvConfig(scenario=scenario, learning=task_learning(scenario), action_mode=action_mode, wake=wake,
                         control_hz=control_hz, duration_s=duration_s, turbulence_field=turbulence_field,
                         wake_fidelity=wake_fidelity, throttle_max=throttle_max, leader_reference=leader_reference,
                         randomisation=rnd, **switches, **preset)
    if turbulence_sigma_mps is None:
        turbulence_sigma_mps = DEFAULT_TURBULENCE_SIGMA_MPS
    extra = dict(t.test_randomisation) if t is not None else {}
    # a task judged by its harvest (close_formation) always computes the saving its metric is made of
    compute_benefit = compute_benefit or (t is not None and t.reference is not None)
    return EnvConfig(scenario=scenario, learning=task_learning(scenario), action_mode=action_mode, wake=wake, control_hz=control_hz,
                     compute_benefit=compute_benefit, duration_s=duration_s, turbulence_field=turbulence_field,
                     wake_fidelity=wake_fidelity, throttle_max=throttle_max, leader_reference=leader_reference,
                     **switches, randomisation=Randomisation(turbulence_sigma_mps=turbulence_sigma_mps, **extra))


def reference_saving(scenario_name: str) -> float | None:
    """The denominator of ``harvest_ratio``: the follower's induced-drag saving at the reference optimum of the
    allowed region of the task flown on ``scenario_name``, in calm air (:meth:`formation_env.tasks.Task.optimum_saving`);
    None where the scenario's task has none (then no harvest ratio is reported)."""
    from formation_env.tasks import task_for_scenario

    task = task_for_scenario(scenario_name)
    return None if task is None else task.optimum_saving()


def reference_savings(scenario_name: str) -> np.ndarray | None:
    """Each follower's saving at the reference optimum (an N-UAV task's joint optimum: its reference's
    ``optimum_savings()``), each follower's saving counted up to its own; None where the reference has one
    optimum for every follower (then the scalar :func:`reference_saving` caps them all)."""
    from formation_env.tasks import task_for_scenario

    task = task_for_scenario(scenario_name)
    ref = None if task is None else task.reference
    fn = getattr(ref, "optimum_savings", None)
    return None if fn is None else np.asarray(fn(), dtype=float)


def _moving_slot(scenario) -> bool:
    return any(len(s.keyframes) > 1 for s in scenario.slots)


class _EpisodeSeries(Recorder):
    """The per-decision series the metrics below are computed from (NaN once a formation's episode ended)."""

    def __init__(self, config) -> None:
        self.hz = config.control_hz

    def start(self, sim, out) -> None:
        sc = sim.scenario
        self.agents = list(sim.agent_indices)
        b, a_n = sim.batch_size, len(self.agents)
        self.series = {k: [] for k in ("t", "err", "trk", "sep", "act", "cmd", "saving", "final_err", "box", "ell",
                                       "sixdof", "formation")}
        self.energy = sim.wake_model is not None  # the energy account (formation_env.sim.energy) needs the wake
        self.returns = np.zeros(b)
        self.fuel0 = sim.aircraft[:, :, 13].copy()
        self.fuel_end = self.fuel0.copy()
        self.moving = _moving_slot(sc)
        self.final_offsets = [np.asarray(s.offset_and_rate(sim.duration_s)[0]) for s in sc.slots]
        self.shape = (b, a_n)

    def after_step(self, sim, out, act_now, alive, k) -> None:
        from formation_env.control.observation import slot_demand
        from formation_env.envs.rewards import min_separation_m, slot_error_m

        agents, series, (b, a_n) = self.agents, self.series, self.shape
        with np.errstate(all="ignore"):
            err = slot_error_m(sim.aircraft, sim.position_demand)[:, agents]
            sep = min_separation_m(sim.aircraft)[:, agents]
        series["t"].append(k / self.hz)
        series["err"].append(np.where(alive[:, None], err, np.nan))
        series["trk"].append(np.where(alive[:, None, None], out.info.slot_error_track_m[:, agents], np.nan))
        series["sep"].append(np.where(alive[:, None], sep, np.nan))
        series["act"].append(np.where(alive[:, None, None], act_now, np.nan))
        series["cmd"].append(np.where(alive[:, None, None], sim.commands[:, agents], np.nan))
        series["saving"].append(np.where(alive[:, None], out.info.induced_drag_saving[:, agents], np.nan))
        series["box"].append(np.where(alive[:, None], out.info.box_depth_m[:, agents], np.nan))
        if self.energy:  # the ELL's and the 6-DOF's drag saving at the flown state, % of the drag alone
            # computed when read (an ELL solve per formation and per UAV alone): read once per decision, it was a
            # third of an N-UAV evaluation's time when read twice
            every = out.info.energy_account
            acc = every[:, agents]
            for key, col in (("ell", "drag_saving_pct_ell"), ("sixdof", "drag_saving_pct_6dof")):
                series[key].append(np.where(alive[:, None], acc[..., ENERGY_COLUMNS.index(col)], np.nan))
            if sim.benefit_enabled:  # the formation's induced-drag saving: every UAV's, the leader's included,
                # against every UAV alone, 1 - sum D_i(formation) / sum D_i(alone) (the ELL's newtons)
                cut = every[..., ENERGY_COLUMNS.index("ell_saving_n")].sum(axis=1)
                alone = every[..., ENERGY_COLUMNS.index("ell_induced_alone_n")].sum(axis=1)
                with np.errstate(all="ignore"):
                    series["formation"].append(np.where(alive & (alone > 0), cut / alone, np.nan))
        if self.moving:
            fe = np.full((b, a_n), np.nan)
            vd0 = sim.velocity_demand[:, 0]
            chi = np.arctan2(vd0[:, 1], vd0[:, 0])
            vel0 = sim.velocity_ned()[:, 0]
            for j, v in enumerate(agents):
                if v == 0:
                    continue
                p, _ = slot_demand(sim.aircraft[:, 0, 10:13], vel0, self.final_offsets[v - 1] + sim.state.slot_jitter[:, v],
                                   None, track_angle_rad=chi)
                fe[:, j] = np.linalg.norm(sim.aircraft[:, v, 10:13] - p, axis=-1)
            series["final_err"].append(np.where(alive[:, None], fe, np.nan))
        self.returns[alive] += out.reward[alive][:, agents].mean(axis=1)

    def ended(self, sim, out, formations, k) -> None:
        self.fuel_end[formations] = sim.aircraft[formations, :, 13]


def run_episodes(policy, config, seeds: Sequence[int], *, keep_series: bool = False, recorders: Sequence = ()) -> list[dict]:
    """Fly one episode per seed (all in one batch) with ``policy`` (the :class:`formation_env.rollout.Policy`
    protocol) and return the per-episode metrics (the module's table); ``recorders``: more
    :class:`formation_env.rollout.Recorder` s to see the same rollout."""
    from formation_env.rollout import rollout
    from formation_env.tasks.compose import task_simulation, task_terms

    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("seeds must not be empty")
    sim = task_simulation(config, batch_size=len(seeds))  # a task's Python terms composed after the step
    rec = _EpisodeSeries(config)
    terms = task_terms(config.scenario)
    term_metrics = terms.episode_metrics() if terms is not None else None  # a task's Python metric terms
    term_rec = [term_metrics.recorder()] if term_metrics is not None else []
    res = rollout(sim, policy, seeds, recorders=[rec, *term_rec, *recorders])
    sc, agents = sim.scenario, rec.agents
    b, a_n = rec.shape
    has_box = sc.safe_box_b is not None
    series, returns, fuel0, fuel_end, moving = rec.series, rec.returns, rec.fuel0, rec.fuel_end, rec.moving
    end_step, collided, crashed = res.decisions, res.collided, res.crashed
    optimum = reference_saving(sc.name)
    optima = reference_savings(sc.name) if optimum is not None else None
    if optima is not None and optima.shape != (a_n,):
        optima = None  # learners other than every follower: the scalar optimum caps them
    cap = optimum if optima is None else optima[None, :]
    trim = sim.trim.controls[0, :4]
    # the throttle counts as saturated within 1e-3 of a limit (the FCS clips it exactly there)
    thr_lo, thr_hi = sim.throttle_limits[0] + 1e-3, sim.throttle_limits[1] - 1e-3
    t = np.asarray(series["t"])
    err = np.stack(series["err"])          # (T, B, A)
    trk = np.stack(series["trk"])          # (T, B, A, 3) slot frame: along-track, lateral, vertical
    sep = np.stack(series["sep"])
    acts = np.stack(series["act"])         # (T, B, A, 4)
    cmd = np.stack(series["cmd"])
    saving = np.stack(series["saving"])
    box = np.stack(series["box"])
    energy = {key: np.stack(series[key]) for key in ("ell", "sixdof")} if rec.energy else {}
    formation = np.stack(series["formation"]) if series["formation"] else None  # (T, B)
    final_err = np.stack(series["final_err"]) if moving else None
    schedule_start = sc.slots[0].keyframes[1][0] if moving else 0.0
    out = []
    full = -(-sim.n_steps // sim.substeps)  # decisions in an episode flown to the end
    for i in range(b):
        n = end_step[i]
        # an episode that ended early (collision, envelope) is scored as a failure for the time it did not
        # fly: the slot error of every missing decision is FAILURE_SLOT_ERROR_M, never an accurate short run
        missing = full - n if res.terminated[i] else 0
        e = np.concatenate([err[:n, i], np.full((missing, a_n), max(FAILURE_SLOT_ERROR_M, float(np.max(err[:n, i]))))])
        m = {
            "seed": seeds[i],
            "duration_s": float(n / config.control_hz),
            "return": float(returns[i]),
            "rms_slot_error_m": float(np.sqrt(np.mean(e ** 2))),
            "max_slot_error_m": float(np.max(e)),
            "time_within_1m_s": float(np.sum(e < 1.0) / config.control_hz / a_n),
            "time_within_1m_frac": float(np.mean(e < 1.0)),
            "min_separation_m": float(np.nanmin(sep[:n, i])),
            "collision": bool(collided[i]),
            "crashed": bool(crashed[i]),
            "control_effort_rad": float(np.sqrt(np.mean((cmd[:n, i, :, :3] - trim[:3]) ** 2))),
            "throttle_mean": float(np.mean(cmd[:n, i, :, 3])),
            # the control-saturation measure of what limits a controller (issue 24): the throttle at either limit
            "throttle_saturated_frac": float(np.mean((cmd[:n, i, :, 3] <= thr_lo) | (cmd[:n, i, :, 3] >= thr_hi))),
            "action_rms": float(np.sqrt(np.mean(acts[:n, i] ** 2))),
            "fuel_used_kg": float(np.mean(fuel0[i, agents] - fuel_end[i, agents])),
            "leader_fuel_kg": float(fuel0[i, 0] - fuel_end[i, 0]),
        }
        m["fuel_saving_pct"] = float(100.0 * (1.0 - m["fuel_used_kg"] / m["leader_fuel_kg"])) if m["leader_fuel_kg"] > 0 else float("nan")
        # the slot-frame components (the saving lives across the track): the time not flown charged
        # FAILURE_SLOT_ERROR_M on every axis, as the 3D error is
        for j, key in enumerate(("rms_along_track_m", "rms_lateral_m", "rms_vertical_m")):
            c = np.concatenate([trk[:n, i, :, j].ravel(), np.full(missing * a_n, FAILURE_SLOT_ERROR_M)])
            m[key] = float(np.sqrt(np.mean(c ** 2)))
        if sim.benefit_enabled:  # no saving for the time not flown
            m["induced_drag_saving"] = float(np.sum(saving[:n, i]) / ((n + missing) * a_n))
            if optimum is not None:
                # each decision's saving counted up to the optimum of the task's allowed region: above it the
                # follower is inside the band where the lattice overstates the saving (issue 23 part 6), so no
                # excursion into it can make up for time off the slot; the uncapped ratio is reported beside it
                capped = np.minimum(saving[:n, i], cap)
                m["harvest_ratio"] = float(np.sum(capped) / ((n + missing) * a_n)) / optimum
                m["harvest_ratio_uncapped"] = m["induced_drag_saving"] / optimum
            if a_n > 1:  # each learning follower's own saving (an N-UAV task is judged follower by follower)
                for j, v in enumerate(agents):
                    m[f"{PER_UAV_PREFIX}{v}"] = float(np.sum(saving[:n, i, j]) / (n + missing))
            if formation is not None:
                m["formation_saving"] = float(np.nansum(formation[:n, i]) / (n + missing))
        if rec.energy:  # the energy account's means over the decisions, the time not flown as no saving
            for key, name in (("ell", "drag_saving_pct_ell"), ("sixdof", "drag_saving_pct_6dof")):
                m[name] = float(np.sum(energy[key][:n, i]) / ((n + missing) * a_n))
        if has_box:  # the time not flown counts as outside the box
            out_of_box = np.concatenate([box[:n, i] > 0.0, np.ones((missing, a_n), bool)])  # (T, A)
            m["box_outside_frac"] = float(np.mean(out_of_box))
            m["box_outside_longest_s"] = float(max(longest_run(out_of_box[:, j]) for j in range(a_n)) / config.control_hz)
            m["box_depth_max_m"] = float(np.max(box[:n, i]))
            if sim.benefit_enabled:  # what the task is judged by: a decision outside the box saves nothing
                inside = np.where(box[:n, i] > 0.0, 0.0, saving[:n, i])
                m["induced_drag_saving_in_box"] = float(np.sum(inside) / ((n + missing) * a_n))
        if moving:
            fe = final_err[:n, i]
            ok = not (m["collision"] or m["crashed"]) and n >= round(sim.duration_s * config.control_hz)
            window = t[:n] > t[n - 1] - SUCCESS_WINDOW_S
            fe = fe[:, [j for j, v in enumerate(agents) if v != 0]]  # the followers (vehicle 0 has no slot)
            m["reconfig_success"] = bool(ok and np.all(fe[window] < SPAN_M))
            outside = np.nonzero(np.any(fe >= SPAN_M, axis=1))[0]
            if not ok or (len(outside) and outside[-1] == n - 1):
                m["reconfig_time_s"] = float("nan")
            else:
                settle = t[outside[-1] + 1] if len(outside) else t[0]
                m["reconfig_time_s"] = float(settle - schedule_start)
        out.append(m)
    if term_rec:  # the task's own columns beside the generic ones
        for m, extra in zip(out, term_metrics.episodes(term_rec[0], res)):
            m.update({k: v for k, v in extra.items() if k != "seed"})
    if keep_series:
        for i, m in enumerate(out):
            if sim.benefit_enabled:
                m["saving_series"] = saving[:end_step[i], i].mean(axis=1).tolist()
        for i, m in enumerate(out):
            n = end_step[i]
            m["series"] = {"t": t[:n].tolist(), "slot_error_m": err[:n, i].mean(axis=1).tolist()}
    return out
