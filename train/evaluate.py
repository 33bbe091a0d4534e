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
action_rms                     RMS of the agent's normalised action (0 for the PID)
fuel_used_kg, leader_fuel_kg   fuel burnt by the followers (mean) and by the leader
fuel_saving_pct                100 (1 - follower fuel / leader fuel)
induced_drag_saving            mean ELL induced-drag saving of the followers (with ``compute_benefit``)
reconfig_success               (scenarios with a moving slot) no collision or crash and every follower
                               within 1 span (2.9 m) of its final slot for the last 5 s
reconfig_time_s                time from the start of the slot schedule until the follower is within
                               1 span of its final slot for good (NaN when it never is)
=============================  ======================================================================

Statistics (``train/stats.py``; 95 %, bootstrap intervals percentile with 10,000 resamples drawn from a
fixed seed, so the same episodes always give the same numbers):

* per policy (``summary``): the means above, ``rms_slot_error_m_ci`` (bootstrap interval of the mean),
  ``collisions`` / ``collision_rate`` / ``collision_rate_ci`` (Wilson), ``reconfig_success_rate`` /
  ``reconfig_success_rate_ci`` (Wilson), ``min_separation_m`` (smallest over all episodes) and
  ``min_separation_m_p05`` (5th percentile of the per-episode minima);
* ``comparisons[<policy>][<baseline>]``: every policy against each baseline evaluated beside it ("pid",
  "pid_formation"; and pid_formation against pid), paired by episode: :func:`train.stats.paired_comparison`
  of the per-episode RMS slot error (reduction = baseline - policy, m, mean and median with intervals,
  relative reduction of the mean, fraction of episodes better, sign test) and, with a moving slot,
  :func:`train.stats.paired_rate_difference` of the reconfiguration success;
* ``groups[<name>]``: policies ``<name>_seed<k>`` (the same recipe trained with several seeds; two or
  more), or the ``groups`` argument: each summary metric's mean, std (ddof 1), min and max across the
  seeds, and the paired comparison of the seed-averaged per-episode metric against each baseline.
"""

from __future__ import annotations

import json
import math
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .config import ACTION_MODES, ALGOS, TEST_SEED_BASE
from .stats import N_BOOT, bootstrap_ci, paired_comparison, paired_rate_difference, seed_spread, wilson_interval

__all__ = ["EvalPolicy", "load_policy", "run_episodes", "summarise", "evaluate", "eval_env_config", "compare_episodes",
           "comparisons", "seed_groups", "group_report", "BASELINES", "TEST_EPISODES", "SUCCESS_WINDOW_S", "SPAN_M"]

SPAN_M = 2.9
SUCCESS_WINDOW_S = 5.0
TEST_EPISODES = 100                    # held-out test episodes per policy by default
BASELINES = ("pid", "pid_formation")   # the classical controllers every other policy is compared with
_SEED_NAME = re.compile(r"^(?P<group>.+)_seed(?P<seed>\d+)$")


@dataclass
class EvalPolicy:
    """A policy to evaluate: ``act(obs (N, D) float32) -> actions (N, 4)`` in ``action_mode``."""

    name: str
    action_mode: str
    act: Callable[[np.ndarray], np.ndarray]
    control_hz: float = 10.0
    path: str | None = None
    reset: Callable[[int], None] | None = None
    """Called once by :func:`run_episodes` with the number of rows (formations x learning UAVs)
    before the first decision (stateful policies: a PID's integrators)."""


def _pid_policy() -> EvalPolicy:
    return EvalPolicy("pid", "residual", lambda obs: np.zeros((obs.shape[0], 4), dtype=np.float32))


def _pid_formation_policy() -> EvalPolicy:
    """The classical formation-keeping controller (``agents.pid_formation.PIDFormation``), imported
    only here: a stateful agent whose ``reset(n_rows)`` runs before every batch of episodes."""
    try:
        from agents.pid_formation import PIDFormation
    except ModuleNotFoundError as exc:
        if exc.name not in ("agents.pid_formation", "agents"):
            raise
        raise ValueError("policy 'pid_formation' needs agents/pid_formation.py, which this checkout does not have") from None

    agent = PIDFormation()
    return EvalPolicy("pid_formation", str(agent.action_mode), agent.act, float(agent.control_hz), reset=agent.reset)


def _policy_metadata(path: Path) -> dict:
    """Metadata of a policy zip: its sidecar ``<stem>.json``, else its run's ``config.yaml``."""
    side = path.with_suffix(".json")
    if side.is_file():
        data = json.loads(side.read_text())
        return data.get("env", data)
    for parent in (path.parent, path.parent.parent):
        cfg = parent / "config.yaml"
        if cfg.is_file():
            import yaml

            data = yaml.safe_load(cfg.read_text()) or {}
            return {"algo": data.get("algo"), "action_mode": data.get("action_mode"), "scenario": data.get("scenario"),
                    "control_hz": (data.get("env_kwargs") or {}).get("control_hz", 10.0)}
    return {}


def load_policy(spec: str, *, action_mode: str | None = None, name: str | None = None, device: str = "cpu") -> EvalPolicy:
    """``"pid"`` (the thesis FCS: zero residual), ``"pid_formation"`` (the classical formation-keeping
    baseline of ``agents.pid_formation``), the path of an SB3 zip (its algo and action mode come from
    the sidecar JSON or the run's config.yaml; ``action_mode`` overrides), or an RLlib checkpoint / run
    directory of ``formation-env train --backend rllib`` (its metadata fixes the action mode)."""
    if spec == "pid":
        return _pid_policy()
    if spec == "pid_formation":
        return _pid_formation_policy()
    path = Path(spec)
    if path.is_dir():
        # An RLlib checkpoint (or run directory); ray is imported only here, and only then.
        from .rllib_backend import is_rllib_checkpoint, load_rllib_policy

        if not is_rllib_checkpoint(path):
            raise ValueError(f"policy directory {spec!r} is not an RLlib checkpoint or run directory of this project")
        pol = load_rllib_policy(path, name=name)
        if action_mode is not None and action_mode != pol.action_mode:
            raise ValueError(f"policy {spec!r} was trained with {pol.action_mode!r} actions, not {action_mode!r} "
                             "(an RLlib checkpoint's metadata fixes its action mode; leave out --action-mode)")
        return pol
    if not path.is_file():
        raise ValueError(f"policy file {spec!r} does not exist (give an SB3 .zip, an RLlib checkpoint directory, "
                         "'pid' or 'pid_formation')")
    meta = _policy_metadata(path)
    mode = action_mode or meta.get("action_mode")
    if mode is None:
        raise ValueError(f"policy {spec!r}: its action mode is unknown (no {path.with_suffix('.json').name} or "
                         "config.yaml beside it); pass --action-mode")
    if mode not in ACTION_MODES:
        raise ValueError(f"unknown action mode {mode!r}; choose one of {ACTION_MODES}")
    from stable_baselines3 import PPO, SAC, TD3

    classes = {"ppo": PPO, "sac": SAC, "td3": TD3}
    algo = meta.get("algo")
    order = [algo] if algo in ALGOS else list(ALGOS)
    model, errors = None, []
    for a in order:
        try:
            model = classes[a].load(str(path), device=device)
            break
        except Exception as exc:  # noqa: BLE001 - try the next algorithm
            errors.append(f"{a}: {exc}")
    if model is None:
        raise ValueError(f"policy {spec!r} is not a loadable SB3 PPO/SAC/TD3 zip ({'; '.join(errors)})")

    def act(obs: np.ndarray) -> np.ndarray:
        return model.predict(obs, deterministic=True)[0]

    return EvalPolicy(name or path.stem, mode, act, float(meta.get("control_hz", 10.0) or 10.0), str(path))


def eval_env_config(scenario: str, action_mode: str, *, turbulence_sigma_mps: float = 1.0, wake: bool = True,
                    control_hz: float = 10.0, compute_benefit: bool = False, duration_s: float | None = None,
                    turbulence_field: str = "frozen"):
    """The evaluation episodes' EnvConfig: the thesis scenario with wake and Dryden turbulence on. With
    its defaults (sigma 1 m/s, wake on, the scenario's duration, no other randomisation) it is the test
    set's distribution, which the training's validation (model selection) also uses."""
    from formation_env.envs.config import EnvConfig, Randomisation

    return EnvConfig(scenario=scenario, learning="followers", action_mode=action_mode, wake=wake, control_hz=control_hz,
                     compute_benefit=compute_benefit, duration_s=duration_s, turbulence_field=turbulence_field,
                     randomisation=Randomisation(turbulence_sigma_mps=turbulence_sigma_mps))


def _moving_slot(scenario) -> bool:
    return any(len(s.keyframes) > 1 for s in scenario.slots)


def run_episodes(act: Callable[[np.ndarray], np.ndarray], config, seeds: Sequence[int], *,
                 keep_series: bool = False, reset: Callable[[int], None] | None = None) -> list[dict]:
    """Fly one episode per seed (all in one batch) and return the per-episode metrics. ``reset`` (a
    stateful policy's) is called once with the number of observation rows, formations x learning
    UAVs, before the first decision."""
    from agents.observation import slot_demand
    from formation_env.envs.core import FormationCore
    from formation_env.envs.rewards import min_separation_m, slot_error_m

    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("seeds must not be empty")
    core = FormationCore(config, batch_size=len(seeds))
    core.reset(None, seeds)
    eng = core.engine
    sc = eng.scenario
    agents = list(core.agent_indices)
    b, a_n = len(seeds), len(agents)
    alive = np.ones(b, dtype=bool)
    series = {k: [] for k in ("t", "err", "sep", "act", "cmd", "saving", "final_err")}
    end_step = np.zeros(b, dtype=np.int64)
    returns = np.zeros(b)
    collided = np.zeros(b, dtype=bool)
    crashed = np.zeros(b, dtype=bool)
    fuel0 = eng.state[:, :, 13].copy()
    fuel_end = fuel0.copy()
    moving = _moving_slot(sc)
    duration = eng.duration_s
    final_offsets = [np.asarray(s.offset_and_rate(duration)[0]) for s in sc.slots]
    trim = eng.trim.controls[0, :4]
    if reset is not None:
        reset(b * a_n)
    k = 0
    while alive.any():
        obs = core.observations()[:, agents].reshape(b * a_n, -1).astype(np.float32)
        act_now = np.clip(np.asarray(act(obs), dtype=float).reshape(b, a_n, 4), -1.0, 1.0)
        act_now[~alive] = 0.0
        with np.errstate(all="ignore"):
            rewards, term, trunc = core.step(act_now)
            err = slot_error_m(eng.state, eng.position_demand_now())[:, agents]
            sep = min_separation_m(eng.state)[:, agents]
        k += 1
        series["t"].append(k / config.control_hz)
        series["err"].append(np.where(alive[:, None], err, np.nan))
        series["sep"].append(np.where(alive[:, None], sep, np.nan))
        series["act"].append(np.where(alive[:, None, None], act_now, np.nan))
        series["cmd"].append(np.where(alive[:, None, None], eng.commands[:, agents], np.nan))
        series["saving"].append(np.where(alive[:, None], core.last_saving[:, agents], np.nan))
        if moving:
            fe = np.full((b, a_n), np.nan)
            vd0 = eng.velocity_demand[:, 0]
            chi = np.arctan2(vd0[:, 1], vd0[:, 0])
            vel0 = eng._velocity_ned()[:, 0]
            for j, v in enumerate(agents):
                if v == 0:
                    continue
                p, _ = slot_demand(eng.state[:, 0, 10:13], vel0, final_offsets[v - 1] + eng.slot_jitter[:, v], None,
                                   track_angle_rad=chi)
                fe[:, j] = np.linalg.norm(eng.state[:, v, 10:13] - p, axis=-1)
            series["final_err"].append(np.where(alive[:, None], fe, np.nan))
        returns[alive] += rewards[alive][:, agents].mean(axis=1)
        done = (term | trunc) & alive
        if done.any():
            idx = np.nonzero(done)[0]
            collided[idx] = core.collided[idx]
            crashed[idx] = core.crashed[idx].any(axis=1)
            fuel_end[idx] = eng.state[idx, :, 13]
            end_step[idx] = k
            alive &= ~done
            early = idx[term[idx]]
            if len(early) and alive.any():  # restart crashed formations so the batch stays finite
                core.reset(early, [seeds[i] for i in early])
    t = np.asarray(series["t"])
    err = np.stack(series["err"])          # (T, B, A)
    sep = np.stack(series["sep"])
    acts = np.stack(series["act"])         # (T, B, A, 4)
    cmd = np.stack(series["cmd"])
    saving = np.stack(series["saving"])
    final_err = np.stack(series["final_err"]) if moving else None
    schedule_start = sc.slots[0].keyframes[1][0] if moving else 0.0
    out = []
    for i in range(b):
        n = end_step[i]
        e = err[:n, i]
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
            "action_rms": float(np.sqrt(np.mean(acts[:n, i] ** 2))),
            "fuel_used_kg": float(np.mean(fuel0[i, agents] - fuel_end[i, agents])),
            "leader_fuel_kg": float(fuel0[i, 0] - fuel_end[i, 0]),
        }
        m["fuel_saving_pct"] = float(100.0 * (1.0 - m["fuel_used_kg"] / m["leader_fuel_kg"])) if m["leader_fuel_kg"] > 0 else float("nan")
        if core.benefit_enabled:
            m["induced_drag_saving"] = float(np.mean(saving[:n, i]))
        if moving:
            fe = final_err[:n, i]
            ok = not (m["collision"] or m["crashed"]) and n >= round(eng.duration_s * config.control_hz)
            window = t[:n] > t[n - 1] - SUCCESS_WINDOW_S
            m["reconfig_success"] = bool(ok and np.all(fe[window] < SPAN_M))
            outside = np.nonzero(np.any(fe >= SPAN_M, axis=1))[0]
            if not ok or (len(outside) and outside[-1] == n - 1):
                m["reconfig_time_s"] = float("nan")
            else:
                settle = t[outside[-1] + 1] if len(outside) else t[0]
                m["reconfig_time_s"] = float(settle - schedule_start)
        out.append(m)
    if keep_series:
        for i, m in enumerate(out):
            n = end_step[i]
            m["series"] = {"t": t[:n].tolist(), "slot_error_m": err[:n, i].mean(axis=1).tolist()}
    return out


_MEAN_KEYS = ("return", "rms_slot_error_m", "max_slot_error_m", "time_within_1m_s", "time_within_1m_frac",
              "control_effort_rad", "throttle_mean", "action_rms", "fuel_used_kg", "leader_fuel_kg", "fuel_saving_pct",
              "induced_drag_saving", "duration_s")


def summarise(episodes: list[dict], *, n_boot: int = N_BOOT, seed: int = 0) -> dict:
    """Aggregate per-episode metrics: means, the worst case where it matters, and 95 % intervals
    (bootstrap of the mean RMS error with ``n_boot`` resamples from ``seed``; Wilson intervals of the
    collision and reconfiguration-success rates)."""
    n = len(episodes)
    s = {"episodes": n}
    for k in _MEAN_KEYS:
        vals = [e[k] for e in episodes if k in e]
        if vals:
            s[k] = float(np.mean(vals))
    rms = np.array([e["rms_slot_error_m"] for e in episodes], dtype=float)
    s["rms_slot_error_m_ci"] = list(bootstrap_ci(rms, "mean", n_boot=n_boot, seed=seed))
    s["rms_slot_error_m_median"] = float(np.median(rms))
    s["rms_slot_error_m_std"] = float(np.std(rms))
    s["max_slot_error_m_worst"] = float(max(e["max_slot_error_m"] for e in episodes))
    seps = np.array([e["min_separation_m"] for e in episodes], dtype=float)
    s["min_separation_m"] = float(np.min(seps))
    s["min_separation_m_p05"] = float(np.percentile(seps, 5))
    s["collisions"] = int(sum(e["collision"] for e in episodes))
    s["collision_rate"] = s["collisions"] / n
    s["collision_rate_ci"] = list(wilson_interval(s["collisions"], n))
    s["crashes"] = int(sum(e["crashed"] for e in episodes))
    if "reconfig_success" in episodes[0]:
        k = int(sum(e["reconfig_success"] for e in episodes))
        s["reconfig_success_rate"] = k / n
        s["reconfig_success_rate_ci"] = list(wilson_interval(k, n))
        times = [e["reconfig_time_s"] for e in episodes if not math.isnan(e["reconfig_time_s"])]
        s["reconfig_time_s"] = float(np.mean(times)) if times else float("nan")
    return s


def selection_score(summary: dict) -> float:
    """Lower is better: the model-selection criterion of the eval callback (RMS slot error; a
    collision or crash disqualifies; failed reconfigurations add 100 m each as a fraction)."""
    if summary["collisions"] or summary["crashes"]:
        return float("inf")
    score = summary["rms_slot_error_m"]
    if "reconfig_success_rate" in summary:
        score += 100.0 * (1.0 - summary["reconfig_success_rate"])
    return float(score)


# ------------------------------------------------------------------ comparisons and seed groups
def _column(episodes: list[dict], key: str) -> np.ndarray:
    return np.array([float(e[key]) for e in episodes])


def _check_paired(a: list[dict], b: list[dict]) -> None:
    sa, sb = [e["seed"] for e in a], [e["seed"] for e in b]
    if sa != sb:
        raise ValueError("paired comparison needs the same episodes (seeds) in the same order")


def compare_episodes(baseline: list[dict], candidate: list[dict] | None = None, *,
                     candidate_values: dict[str, np.ndarray] | None = None, n_boot: int = N_BOOT, seed: int = 0) -> dict:
    """Paired comparison of a candidate with a baseline on the same episodes: ``rms_slot_error_m``
    (:func:`train.stats.paired_comparison`, reduction = baseline - candidate in m) and, when the
    episodes have it, ``reconfig_success`` (:func:`train.stats.paired_rate_difference`, candidate -
    baseline). The candidate is its episode list or, for a seed group, ``candidate_values``: the
    per-episode values (seed-averaged) keyed by metric."""
    if candidate is not None:
        _check_paired(baseline, candidate)
        candidate_values = {k: _column(candidate, k) for k in ("rms_slot_error_m", "reconfig_success")
                            if k in candidate[0]}
    assert candidate_values is not None
    out = {"rms_slot_error_m": paired_comparison(_column(baseline, "rms_slot_error_m"),
                                                 candidate_values["rms_slot_error_m"], n_boot=n_boot, seed=seed)}
    if "reconfig_success" in baseline[0] and "reconfig_success" in candidate_values:
        out["reconfig_success"] = paired_rate_difference(_column(baseline, "reconfig_success"),
                                                         candidate_values["reconfig_success"], n_boot=n_boot, seed=seed)
    return out


def comparisons(episodes: dict[str, list[dict]], baselines: dict[str, str] | None = None, *,
                candidates: Sequence[str] | None = None, n_boot: int = N_BOOT) -> dict:
    """``{policy: {baseline: compare_episodes(...)}}`` for every candidate policy against every
    baseline present, and pid_formation against pid when both are. ``baselines`` maps the baseline
    kind ("pid", "pid_formation") to its policy name (default: the names themselves, when evaluated);
    ``candidates`` defaults to every other policy except a baseline given twice ("pid-2")."""
    if baselines is None:
        baselines = {b: b for b in BASELINES if b in episodes}
    base_names = set(baselines.values())
    if candidates is None:
        candidates = [n for n in episodes if n not in base_names and not _is_duplicate_baseline(n, base_names)]
    out: dict[str, dict] = {}
    for name in candidates if baselines else ():
        out[name] = {b: compare_episodes(episodes[b], episodes[name], n_boot=n_boot) for b in baselines.values()}
    if "pid" in baselines and "pid_formation" in baselines:
        pf, p = baselines["pid_formation"], baselines["pid"]
        out[pf] = {p: compare_episodes(episodes[p], episodes[pf], n_boot=n_boot)}
    return out


def _is_duplicate_baseline(name: str, base_names: set[str]) -> bool:
    """"pid-2" etc.: a baseline given twice (renamed by :func:`evaluate`) is not a candidate."""
    head, _, tail = name.rpartition("-")
    return head in base_names and tail.isdigit()


def seed_groups(names: Sequence[str]) -> dict[str, list[str]]:
    """Groups of policy names ``<group>_seed<k>`` with two or more members (in the given order)."""
    found: dict[str, list[str]] = {}
    for n in names:
        m = _SEED_NAME.match(n)
        if m:
            found.setdefault(m.group("group"), []).append(n)
    return {g: members for g, members in found.items() if len(members) >= 2}


def _scalar_metrics(summary: dict) -> list[str]:
    return [k for k, v in summary.items()
            if k not in ("episodes", "wall_s") and isinstance(v, (int, float)) and not isinstance(v, bool)]


def group_report(members: dict[str, dict], baselines: dict[str, list[dict]], *, n_boot: int = N_BOOT) -> dict:
    """One policy trained with several seeds: ``members`` maps each seed's policy name to its
    ``{"summary", "episodes"}``. Returns ``policies``, ``n_seeds``, ``summary`` (for every scalar
    summary metric, :func:`train.stats.seed_spread` of the seeds' values: mean, std, min, max, n),
    ``per_episode`` (the seed-averaged per-episode RMS error, and success when present) and
    ``comparisons`` ({baseline: compare_episodes} of the seed-averaged per-episode metrics)."""
    names = list(members)
    if not names:
        raise ValueError("a seed group needs at least one policy")
    first = members[names[0]]["episodes"]
    for n in names[1:]:
        _check_paired(first, members[n]["episodes"])
    keys = [k for k in _scalar_metrics(members[names[0]]["summary"]) if all(k in members[n]["summary"] for n in names)]
    summary = {k: seed_spread([members[n]["summary"][k] for n in names]) for k in keys}
    per_episode = {k: np.mean([_column(members[n]["episodes"], k) for n in names], axis=0)
                   for k in ("rms_slot_error_m", "reconfig_success") if k in first[0]}
    comps = {b: compare_episodes(eps, candidate_values=per_episode, n_boot=n_boot) for b, eps in baselines.items()}
    return {"policies": names, "n_seeds": len(names), "summary": summary,
            "per_episode": {k: v.tolist() for k, v in per_episode.items()}, "comparisons": comps}


# ------------------------------------------------------------------ report
_TABLE = (("rms_slot_error_m", "RMS slot error (m)", "{:.3f}"), ("max_slot_error_m", "max slot error (m, mean)", "{:.2f}"),
          ("max_slot_error_m_worst", "max slot error (m, worst)", "{:.2f}"),
          ("time_within_1m_frac", "time within 1 m (fraction)", "{:.3f}"),
          ("min_separation_m", "min separation (m)", "{:.2f}"),
          ("min_separation_m_p05", "min separation (m, 5th percentile of episodes)", "{:.2f}"),
          ("collisions", "collisions", "{:d}"),
          ("crashes", "crashes", "{:d}"), ("reconfig_success_rate", "reconfiguration success", "{:.2f}"),
          ("reconfig_time_s", "reconfiguration time (s)", "{:.1f}"),
          ("control_effort_rad", "control effort (rad RMS)", "{:.4f}"), ("throttle_mean", "mean throttle", "{:.3f}"),
          ("fuel_saving_pct", "follower fuel saving vs leader (%)", "{:.2f}"),
          ("induced_drag_saving", "induced-drag saving (ELL)", "{:.4f}"), ("return", "episode return", "{:.1f}"))
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
    if key == "rms_slot_error_m" and "rms_slot_error_m_ci" in s:
        lo, hi = s["rms_slot_error_m_ci"]
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
    for key, label, fmt in _TABLE:
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


def _plots(out_dir: Path, results: dict[str, dict], scenario: str, *, overwrite: bool) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from formation_env.io import atomic_write

    names = list(results)
    written = []
    labels = {k: lbl for k, lbl, _ in _TABLE}
    keys = [(k, labels[k]) for k in _PLOT_KEYS if all(k in results[n]["summary"] for n in names)]
    fig, axes = plt.subplots(1, len(keys), figsize=(3.0 * len(keys), 3.2))
    for ax, (k, lbl) in zip(np.atleast_1d(axes), keys):
        summ = [results[n]["summary"] for n in names]
        vals = [s[k] for s in summ]
        yerr = None
        if all(f"{k}_ci" in s for s in summ):
            yerr = np.array([[v - s[f"{k}_ci"][0], s[f"{k}_ci"][1] - v] for v, s in zip(vals, summ)]).T
            lbl += " (95 % CI)"
        ax.bar(range(len(names)), vals, yerr=yerr, capsize=3, color=[f"C{i}" for i in range(len(names))])
        ax.set_xticks(range(len(names)), names, rotation=30, ha="right", fontsize=8)
        ax.set_title(lbl, fontsize=9)
    fig.suptitle(f"{scenario}: held-out episodes, wake + Dryden turbulence")
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


def evaluate(policies: Sequence[str], *, scenario: str, episodes: int = TEST_EPISODES, seeds: Sequence[int] | None = None,
             turbulence_sigma_mps: float = 1.0, wake: bool = True, compute_benefit: bool = False,
             action_mode: str | None = None, out_dir: str | Path | None = None, overwrite: bool = False,
             plots: bool = True, duration_s: float | None = None, groups: dict[str, Sequence[str]] | None = None,
             turbulence_field: str = "frozen",
             n_boot: int = N_BOOT, log: Callable[[str], None] | None = None) -> dict:
    """Evaluate ``policies`` ("pid", "pid_formation", SB3 zips or RLlib checkpoints) on the same held-out
    episodes (``episodes`` seeds from ``TEST_SEED_BASE``, or from ``seeds[0]``, or exactly ``seeds`` when
    it holds several: then ``episodes`` is not used); optionally write ``results.json``, ``results.md``
    and comparison plots into ``out_dir`` (a new directory).

    The report: ``policies.<name>.summary`` / ``.episodes`` (see :func:`summarise`), ``comparisons``
    (:func:`comparisons`: every policy against each baseline evaluated with it), ``groups`` (seed groups:
    policies ``<name>_seed<k>`` and the ``groups`` argument {group: [policy names]}, see
    :func:`group_report`), ``statistics`` (how the intervals were computed) and the markdown tables."""
    from formation_env.scenarios import scenario_names

    if scenario not in scenario_names():
        raise ValueError(f"unknown scenario {scenario!r}; available: {scenario_names()}")
    if not policies:
        raise ValueError("give at least one policy (a .zip path, an RLlib checkpoint, 'pid' or 'pid_formation')")
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes must be an integer >= 1, got {episodes!r}")
    if not (isinstance(turbulence_sigma_mps, (int, float)) and math.isfinite(turbulence_sigma_mps) and turbulence_sigma_mps >= 0):
        raise ValueError(f"turbulence sigma must be a finite number >= 0, got {turbulence_sigma_mps!r}")
    if seeds is None or len(seeds) == 0:
        seeds = [TEST_SEED_BASE + i for i in range(episodes)]
    elif len(seeds) == 1:
        seeds = [int(seeds[0]) + i for i in range(episodes)]
    else:
        seeds = [int(s) for s in seeds]
    if any(s < 0 for s in seeds):
        raise ValueError(f"seeds must be >= 0, got {[s for s in seeds if s < 0]}")
    loaded, specs = [], {}
    for spec in policies:
        pol = load_policy(spec, action_mode=action_mode if spec not in BASELINES else None)
        base, n = pol.name, 2
        while pol.name in [p.name for p in loaded]:
            pol.name = f"{base}-{n}"
            n += 1
        loaded.append(pol)
        specs[pol.name] = spec
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
                              turbulence_field=turbulence_field,
                              control_hz=pol.control_hz, compute_benefit=compute_benefit, duration_s=duration_s)
        t0 = time.perf_counter()
        eps = run_episodes(pol.act, cfg, seeds, keep_series=True, reset=pol.reset)
        summ = summarise(eps, n_boot=n_boot)
        summ["wall_s"] = round(time.perf_counter() - t0, 2)
        results[pol.name] = {"policy": pol.path or specs[pol.name], "action_mode": pol.action_mode, "summary": summ,
                             "episodes": eps}
        if log:
            lo, hi = summ["rms_slot_error_m_ci"]
            log(f"{pol.name}: RMS slot error {summ['rms_slot_error_m']:.3f} m [{lo:.3f}, {hi:.3f}], "
                f"collisions {summ['collisions']}/{len(seeds)}"
                + (f", reconfiguration success {summ['reconfig_success_rate']:.2f}" if "reconfig_success_rate" in summ else "")
                + f" ({summ['wall_s']:.1f} s)")
    episodes_by_name = {n: r["episodes"] for n, r in results.items()}
    comps = comparisons(episodes_by_name, baselines, candidates=[n for n in names if specs[n] not in BASELINES],
                        n_boot=n_boot)
    base_eps = {b: episodes_by_name[b] for b in baselines.values()}
    group_reports = {g: group_report({m: results[m] for m in members}, base_eps, n_boot=n_boot)
                     for g, members in group_spec.items()}
    report = {"scenario": scenario, "seeds": seeds, "wake": wake, "turbulence_sigma_mps": turbulence_sigma_mps,
              "turbulence_field": turbulence_field,
              "policies": {n: {k: v for k, v in r.items()} for n, r in results.items()},
              "baselines": baselines, "comparisons": comps, "groups": group_reports,
              "statistics": {"confidence": 0.95, "n_boot": n_boot, "bootstrap_seed": 0,
                             "bootstrap": "percentile, episodes resampled jointly across the paired policies",
                             "rates": "Wilson score interval", "sign_test": "exact two-sided, ties left out",
                             "reduction": "baseline - policy, per episode, in the metric's units"}}
    report["table_markdown"] = markdown_table({n: r["summary"] for n, r in results.items()})
    report["comparison_markdown"] = comparison_table(comps, group_reports)
    report["groups_markdown"] = groups_table(group_reports)
    if out is not None:
        from formation_env.io import atomic_write_json, atomic_write_text

        slim = json.loads(json.dumps(report, default=float))
        for r in slim["policies"].values():
            for e in r["episodes"]:
                e["series"]["slot_error_m"] = [round(x, 4) for x in e["series"]["slot_error_m"]]
                e["series"].pop("t")
        atomic_write_json(out / "results.json", slim, overwrite=overwrite)
        head = (f"# Evaluation: {scenario}\n\n{len(seeds)} held-out episodes (seeds {seeds[0]}..{seeds[-1]}), "
                f"wake {'on' if wake else 'off'}, Dryden turbulence sigma {turbulence_sigma_mps:g} m/s. Intervals: 95 %, "
                f"percentile bootstrap over episodes ({n_boot} resamples, seed 0) for errors, Wilson for rates.\n\n")
        text = head + report["table_markdown"]
        if report["comparison_markdown"]:
            text += ("\n## Paired comparisons (per-episode RMS slot error; reduction = baseline - policy)\n\n"
                     + report["comparison_markdown"])
        if report["groups_markdown"]:
            text += "\n## Training seeds\n\n" + report["groups_markdown"]
        atomic_write_text(out / "results.md", text, overwrite=overwrite)
        if plots:
            report["plots"] = _plots(out, results, scenario, overwrite=overwrite)
        report["out_dir"] = str(out)
    return report
