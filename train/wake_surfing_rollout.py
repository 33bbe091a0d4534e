"""Wake-surfing episodes: every controller flies the same held-out episodes (one batch, formation f is
the episode of ``seeds[f]``) and each episode is measured against its reference optimum.

A controller is an :class:`Surfer`: ``act(obs (N, D), saving (N,)) -> (N, 4)`` set-point actions,
with ``reset(n_rows)``. The saving passed in is the one measured at the previous decision (what the
extremum seeker climbs; the RL policies and the PIDs ignore it).

Per episode (10 Hz decisions, the follower):

=========================  =========================================================================
saving                     mean induced-drag saving over the episode (1 - D_i formation / D_i alone),
                           a decision outside the safe box counted as 0 (there the saving may be the
                           ELL's wake-plane artefact); ``saving_measured``: every decision as measured
reference_saving           mean over the episode of the reference optimum's saving at each instant's
                           crab angle (:func:`formation_env.verification.wake_surfing.episode_reference`)
saving_ratio               saving / reference_saving
time_to_80_s               first time the saving (counted as above), averaged over the last second,
                           reaches 80 % of the reference (NaN: never)
box_outside_frac           fraction of the decisions outside the safe box
box_outside_longest_s      longest continuous time outside the box
min_separation_m           smallest CG distance to the leader at the decision instants
collision / crashed        the episode ended by a collision / an envelope exit
lateral_b, vertical_b      the follower's path relative to the leader (track frame, spans), and the
                           reference optimum's, for the figure (with ``keep_series``)
=========================  =========================================================================
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = ["Surfer", "fly", "pid_surfer", "pid_formation_surfer", "es_surfer", "oracle_surfer", "sb3_surfer", "SPAN_M"]

SPAN_M = 2.9
WINDOW_S = 1.0  # the saving is averaged over this before the 80 % test


@dataclass
class Surfer:
    name: str
    act: Callable[[np.ndarray, np.ndarray], np.ndarray]
    reset: Callable[[int], None] | None = None
    bind: Callable[[object], None] | None = None  # given the FormationCore before the first decision (oracles only)


def _ranges():
    from formation_env.scenarios import get_scenario
    from formation_env.sim.params import setpoint_ranges, setpoint_speed_range

    sc = get_scenario("wake_surfing")
    low, high = setpoint_ranges(sc)
    return low, high, setpoint_speed_range(sc)


def pid_surfer() -> Surfer:
    """The thesis PID flying the nominal slot (zero set-point action)."""
    return Surfer("pid", lambda obs, saving: np.zeros((obs.shape[0], 4), dtype=np.float32))


def pid_formation_surfer() -> Surfer:
    """``pid_formation`` at the nominal slot (its set-point ranges mapped onto the safe box's)."""
    from agents.pid_formation import PIDFormation

    low, high, speed = _ranges()
    agent = PIDFormation(setpoint_low_m=low, setpoint_high_m=high, speed_range_mps=speed)
    return Surfer("pid_formation", lambda obs, saving: agent.act(obs), agent.reset)


def es_surfer(gains=None, name: str = "extremum_seeking") -> Surfer:
    from agents.extremum_seeking import ExtremumSeeking

    low, high, speed = _ranges()
    agent = ExtremumSeeking(low, high, speed, gains=gains)
    return Surfer(name, agent.act, agent.reset)


def oracle_surfer(margin_b: float, name: str | None = None) -> Surfer:
    """Not a controller but a ceiling: the thesis PID flown to the reference optimum itself (computed from
    the episode's true steady wind, the leader's demanded track and speed: knowledge no agent has),
    ``margin_b`` spans below the box floor's optimum, with ``pid_formation``'s speed channel holding the
    along-track station. What the set-point interface can achieve under the episode's turbulence."""
    from agents.pid_formation import PIDFormation
    from formation_env.verification.wake_surfing import crab_angle_rad, reference_optimum

    low, high, speed = _ranges()
    along = PIDFormation(setpoint_low_m=low, setpoint_high_m=high, speed_range_mps=speed)
    state = {}
    slot = np.array([1.0, 0.3])  # the nominal slot's (y, z), spans

    def act(obs, saving):
        eng = state["core"].engine
        vd0 = eng.velocity_demand[:, 0]
        crab = crab_angle_rad(eng.sim_state.steady_wind, np.arctan2(vd0[:, 1], vd0[:, 0]), np.linalg.norm(vd0, axis=1))
        y, z, _ = reference_optimum(crab)
        offset = (np.stack([y, np.asarray(z) + margin_b], axis=1) - slot) * SPAN_M
        a = np.zeros((obs.shape[0], 4))
        a[:, 1] = along.setpoint_action(offset[:, 0], 1)
        a[:, 2] = along.setpoint_action(offset[:, 1], 2)
        a[:, 3] = along.act(obs)[:, 3]
        return np.clip(a, -1.0, 1.0)

    return Surfer(name or f"oracle_setpoint_margin{margin_b:g}", act, along.reset, lambda core: state.update(core=core))


def sb3_surfer(path: str, name: str | None = None) -> Surfer:
    from pathlib import Path

    from stable_baselines3 import PPO

    model = PPO.load(path, device="cpu")
    return Surfer(name or Path(path).stem, lambda obs, saving: model.predict(obs, deterministic=True)[0])


def fly(surfer: Surfer, seeds: Sequence[int], *, config=None, keep_series: bool = False,
        crosswind_mps: float | None = None) -> list[dict]:
    """Fly ``surfer`` on the wake-surfing episodes ``seeds`` (one batch) and measure each (see the module).
    ``crosswind_mps`` replaces each episode's steady wind by this crosswind (east, m/s: the figure's
    demonstration episodes)."""
    from formation_env.envs.core import FormationCore
    from formation_env.verification.wake_surfing import episode_reference

    from formation_env.control.observation import ned_to_track_frame

    from .eval_episodes import eval_env_config, longest_run

    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("seeds must not be empty")
    cfg = config if config is not None else eval_env_config("wake_surfing", "setpoints")
    core = FormationCore(cfg, batch_size=len(seeds))
    core.reset(None, seeds)
    eng = core.engine
    b = len(seeds)
    if crosswind_mps is not None:
        eng.sim_state.steady_wind[:] = (0.0, float(crosswind_mps), 0.0)
        eng.observe()
    if surfer.reset is not None:
        surfer.reset(b)
    if surfer.bind is not None:
        surfer.bind(core)
    alive = np.ones(b, dtype=bool)
    end = np.zeros(b, dtype=np.int64)
    collided = np.zeros(b, dtype=bool)
    crashed = np.zeros(b, dtype=bool)
    rec = {k: [] for k in ("saving", "box", "sep", "rel", "chi", "speed")}
    saving = np.zeros(b)
    wind = eng.sim_state.steady_wind.copy()
    k = 0
    while alive.any():
        obs = core.observations()[:, 1].astype(np.float32)
        act = np.clip(np.asarray(surfer.act(obs, saving), dtype=float).reshape(b, 4), -1.0, 1.0)
        act[~alive] = 0.0
        with np.errstate(all="ignore"):
            _, term, trunc = core.step(act[:, None, :])
        k += 1
        saving = np.where(alive, core.last_saving[:, 1], 0.0)
        vd0 = eng.velocity_demand[:, 0]
        chi = np.arctan2(vd0[:, 1], vd0[:, 0])
        rel = ned_to_track_frame(eng.state[:, 1, 10:13] - eng.state[:, 0, 10:13], chi) / SPAN_M
        rec["saving"].append(np.where(alive, saving, np.nan))
        rec["box"].append(np.where(alive, eng.out.box_depth_m[:, 1], np.nan))
        rec["sep"].append(np.where(alive, eng.out.separation_m[:, 1], np.nan))
        rec["rel"].append(np.where(alive[:, None], rel, np.nan))
        rec["chi"].append(chi)
        rec["speed"].append(np.linalg.norm(vd0, axis=1))
        done = (term | trunc) & alive
        if done.any():
            idx = np.nonzero(done)[0]
            collided[idx] = core.collided[idx]
            crashed[idx] = core.crashed[idx].any(axis=1)
            end[idx] = k
            alive &= ~done
            early = idx[term[idx]]
            if len(early) and alive.any():  # restart ended formations so the batch stays finite
                core.reset(early, [seeds[i] for i in early])
    hz = cfg.control_hz
    arr = {key: np.stack(v) for key, v in rec.items()}  # (T, B, ...)
    window = max(1, int(round(WINDOW_S * hz)))
    out = []
    for i in range(b):
        n = int(end[i])
        sv = arr["saving"][:n, i]
        outside = arr["box"][:n, i] > 0.0
        # outside the box a decision earns nothing: there the ELL's saving may be the wake-plane band's
        # artefact (up to ~0.8), which no controller may claim
        sv_in = np.where(outside, 0.0, sv)
        ref = episode_reference(wind[i], arr["chi"][:n, i], arr["speed"][:n, i])
        ref_saving = float(ref["mean_saving"])
        smooth = np.convolve(sv_in, np.ones(window) / window, mode="full")[:n]
        smooth[:window - 1] = -np.inf  # a full second first
        reached = np.nonzero(smooth >= 0.8 * np.asarray(ref["saving"]))[0]
        m = {
            "seed": seeds[i],
            "duration_s": n / hz,
            "saving": float(np.mean(sv_in)),
            "saving_measured": float(np.mean(sv)),
            "reference_saving": ref_saving,
            "saving_ratio": float(np.mean(sv_in) / ref_saving),
            "time_to_80_s": float((reached[0] + 1) / hz) if len(reached) else float("nan"),
            "box_outside_frac": float(np.mean(outside)),
            "box_outside_longest_s": float(longest_run(outside) / hz),
            "min_separation_m": float(np.nanmin(arr["sep"][:n, i])),
            "collision": bool(collided[i]),
            "crashed": bool(crashed[i]),
            "crosswind_mps": float(wind[i, 1]),
        }
        if keep_series:
            m["series"] = {"lateral_b": arr["rel"][:n, i, 1].tolist(), "vertical_b": arr["rel"][:n, i, 2].tolist(),
                           "saving": sv.tolist(), "reference_lateral_b": np.asarray(ref["y_b"]).tolist(),
                           "reference_vertical_b": np.asarray(ref["z_b"]).tolist()}
        out.append(m)
    return out
