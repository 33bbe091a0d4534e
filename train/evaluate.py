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
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .config import ACTION_MODES, ALGOS, TEST_SEED_BASE

__all__ = ["EvalPolicy", "load_policy", "run_episodes", "summarise", "evaluate", "eval_env_config",
           "SUCCESS_WINDOW_S", "SPAN_M"]

SPAN_M = 2.9
SUCCESS_WINDOW_S = 5.0


@dataclass
class EvalPolicy:
    """A policy to evaluate: ``act(obs (N, D) float32) -> actions (N, 4)`` in ``action_mode``."""

    name: str
    action_mode: str
    act: Callable[[np.ndarray], np.ndarray]
    control_hz: float = 10.0
    path: str | None = None


def _pid_policy() -> EvalPolicy:
    return EvalPolicy("pid", "residual", lambda obs: np.zeros((obs.shape[0], 4), dtype=np.float32))


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
    """``"pid"``, the path of an SB3 zip (its algo and action mode come from the sidecar JSON or the
    run's config.yaml; ``action_mode`` overrides), or an RLlib checkpoint / run directory of
    ``formation-env train --backend rllib`` (its metadata fixes the action mode)."""
    if spec == "pid":
        return _pid_policy()
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
        raise ValueError(f"policy file {spec!r} does not exist (give an SB3 .zip, an RLlib checkpoint directory "
                         "or 'pid')")
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
                    control_hz: float = 10.0, compute_benefit: bool = False, duration_s: float | None = None):
    """The evaluation episodes' EnvConfig: the thesis scenario with wake and Dryden turbulence on."""
    from formation_env.envs.config import EnvConfig, Randomisation

    return EnvConfig(scenario=scenario, learning="followers", action_mode=action_mode, wake=wake, control_hz=control_hz,
                     compute_benefit=compute_benefit, duration_s=duration_s,
                     randomisation=Randomisation(turbulence_sigma_mps=turbulence_sigma_mps))


def _moving_slot(scenario) -> bool:
    return any(len(s.keyframes) > 1 for s in scenario.slots)


def run_episodes(act: Callable[[np.ndarray], np.ndarray], config, seeds: Sequence[int], *,
                 keep_series: bool = False) -> list[dict]:
    """Fly one episode per seed (all in one batch) and return the per-episode metrics."""
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


def summarise(episodes: list[dict]) -> dict:
    """Aggregate per-episode metrics (means, and the worst case where it matters)."""
    s = {"episodes": len(episodes)}
    for k in _MEAN_KEYS:
        vals = [e[k] for e in episodes if k in e]
        if vals:
            s[k] = float(np.mean(vals))
    s["rms_slot_error_m_std"] = float(np.std([e["rms_slot_error_m"] for e in episodes]))
    s["max_slot_error_m_worst"] = float(max(e["max_slot_error_m"] for e in episodes))
    s["min_separation_m"] = float(min(e["min_separation_m"] for e in episodes))
    s["collisions"] = int(sum(e["collision"] for e in episodes))
    s["crashes"] = int(sum(e["crashed"] for e in episodes))
    if "reconfig_success" in episodes[0]:
        s["reconfig_success_rate"] = float(np.mean([e["reconfig_success"] for e in episodes]))
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


# ------------------------------------------------------------------ report
_TABLE = (("rms_slot_error_m", "RMS slot error (m)", "{:.3f}"), ("max_slot_error_m", "max slot error (m, mean)", "{:.2f}"),
          ("max_slot_error_m_worst", "max slot error (m, worst)", "{:.2f}"),
          ("time_within_1m_frac", "time within 1 m (fraction)", "{:.3f}"),
          ("min_separation_m", "min separation (m)", "{:.2f}"), ("collisions", "collisions", "{:d}"),
          ("crashes", "crashes", "{:d}"), ("reconfig_success_rate", "reconfiguration success", "{:.2f}"),
          ("reconfig_time_s", "reconfiguration time (s)", "{:.1f}"),
          ("control_effort_rad", "control effort (rad RMS)", "{:.4f}"), ("throttle_mean", "mean throttle", "{:.3f}"),
          ("fuel_saving_pct", "follower fuel saving vs leader (%)", "{:.2f}"),
          ("induced_drag_saving", "induced-drag saving (ELL)", "{:.4f}"), ("return", "episode return", "{:.1f}"))


def markdown_table(summaries: dict[str, dict]) -> str:
    names = list(summaries)
    lines = ["| metric | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
    for key, label, fmt in _TABLE:
        if not any(key in s for s in summaries.values()):
            continue
        cells = []
        for n in names:
            v = summaries[n].get(key)
            cells.append("-" if v is None else ("nan" if isinstance(v, float) and math.isnan(v) else fmt.format(v)))
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    if "pid" in summaries:
        base = summaries["pid"]["rms_slot_error_m"]
        cells = [f"{100.0 * (1.0 - summaries[n]['rms_slot_error_m'] / base):+.1f} %" for n in names]
        lines.append("| RMS error reduction vs PID | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _plots(out_dir: Path, results: dict[str, dict], scenario: str, *, overwrite: bool) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from formation_env.io import atomic_write

    names = list(results)
    written = []
    keys = [(k, lbl) for k, lbl, _ in _TABLE[:5] + _TABLE[9:10] + _TABLE[11:12]
            if all(k in results[n]["summary"] for n in names)]
    fig, axes = plt.subplots(1, len(keys), figsize=(3.0 * len(keys), 3.2))
    for ax, (k, lbl) in zip(np.atleast_1d(axes), keys):
        vals = [results[n]["summary"][k] for n in names]
        ax.bar(range(len(names)), vals, color=[f"C{i}" for i in range(len(names))])
        ax.set_xticks(range(len(names)), names, rotation=30, ha="right", fontsize=8)
        ax.set_title(lbl, fontsize=9)
    fig.suptitle(f"{scenario}: held-out episodes, wake + Dryden turbulence")
    fig.tight_layout()
    written.append(str(atomic_write(out_dir / "metrics.png", lambda p: fig.savefig(p, dpi=110, format="png"), overwrite=overwrite)))
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(8, 4))
    for i, n in enumerate(names):
        eps = results[n]["episodes"]
        length = min(len(e["series"]["t"]) for e in eps)
        t = np.asarray(eps[0]["series"]["t"][:length])
        e = np.array([ep["series"]["slot_error_m"][:length] for ep in eps])
        mean, lo, hi = e.mean(0), np.percentile(e, 10, axis=0), np.percentile(e, 90, axis=0)
        ax.plot(t, mean, color=f"C{i}", label=f"{n} (mean, 10-90 %)")
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


def evaluate(policies: Sequence[str], *, scenario: str, episodes: int = 20, seeds: Sequence[int] | None = None,
             turbulence_sigma_mps: float = 1.0, wake: bool = True, compute_benefit: bool = False,
             action_mode: str | None = None, out_dir: str | Path | None = None, overwrite: bool = False,
             plots: bool = True, duration_s: float | None = None, log: Callable[[str], None] | None = None) -> dict:
    """Evaluate ``policies`` ("pid" or zip paths) on the same held-out episodes; optionally write
    ``results.json``, ``results.md`` and comparison plots into ``out_dir`` (a new directory)."""
    from formation_env.scenarios import scenario_names

    if scenario not in scenario_names():
        raise ValueError(f"unknown scenario {scenario!r}; available: {scenario_names()}")
    if not policies:
        raise ValueError("give at least one policy (a .zip path or 'pid')")
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
    loaded = []
    for spec in policies:
        pol = load_policy(spec, action_mode=action_mode if spec != "pid" else None)
        base, n = pol.name, 2
        while pol.name in [p.name for p in loaded]:
            pol.name = f"{base}-{n}"
            n += 1
        loaded.append(pol)
    out = None
    if out_dir is not None:
        from formation_env.io import prepare_output_dir

        out = prepare_output_dir(out_dir, overwrite=overwrite)
    results = {}
    for pol in loaded:
        cfg = eval_env_config(scenario, pol.action_mode, turbulence_sigma_mps=turbulence_sigma_mps, wake=wake,
                              control_hz=pol.control_hz, compute_benefit=compute_benefit, duration_s=duration_s)
        t0 = time.perf_counter()
        eps = run_episodes(pol.act, cfg, seeds, keep_series=True)
        summ = summarise(eps)
        summ["wall_s"] = round(time.perf_counter() - t0, 2)
        results[pol.name] = {"policy": pol.path or "pid", "action_mode": pol.action_mode, "summary": summ, "episodes": eps}
        if log:
            log(f"{pol.name}: RMS slot error {summ['rms_slot_error_m']:.3f} m, collisions {summ['collisions']}"
                + (f", reconfiguration success {summ['reconfig_success_rate']:.2f}" if "reconfig_success_rate" in summ else "")
                + f" ({summ['wall_s']:.1f} s)")
    report = {"scenario": scenario, "seeds": seeds, "wake": wake, "turbulence_sigma_mps": turbulence_sigma_mps,
              "policies": {n: {k: v for k, v in r.items()} for n, r in results.items()}}
    report["table_markdown"] = markdown_table({n: r["summary"] for n, r in results.items()})
    if out is not None:
        from formation_env.io import atomic_write_json, atomic_write_text

        slim = json.loads(json.dumps(report, default=float))
        for r in slim["policies"].values():
            for e in r["episodes"]:
                e["series"]["slot_error_m"] = [round(x, 4) for x in e["series"]["slot_error_m"]]
                e["series"].pop("t")
        atomic_write_json(out / "results.json", slim, overwrite=overwrite)
        head = (f"# Evaluation: {scenario}\n\n{len(seeds)} held-out episodes (seeds {seeds[0]}..{seeds[-1]}), "
                f"wake {'on' if wake else 'off'}, Dryden turbulence sigma {turbulence_sigma_mps:g} m/s.\n\n")
        atomic_write_text(out / "results.md", head + report["table_markdown"], overwrite=overwrite)
        if plots:
            report["plots"] = _plots(out, results, scenario, overwrite=overwrite)
        report["out_dir"] = str(out)
    return report
