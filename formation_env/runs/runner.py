"""Fly a thesis scenario (:mod:`formation_env.scenarios`) with the PID agents on the formation
simulator; time histories, metrics, and an output directory with metrics JSON and figures.

Public API:

* :func:`run_scenario` ``(name_or_scenario, wake=None, duration_s=None) -> ScenarioRun``
* :func:`scenario_metrics` ``(run) -> dict``
* :func:`run_scenario_to_dir` ``(name, out_dir, wake=True, overwrite=False, duration_s=None) -> metrics``

Vehicle 0 tracks the scenario's reference; each follower tracks vehicle 0's position plus its
slot offset along vehicle 0's ground track (virtual leader). Every aircraft runs the same
:class:`~formation_env.control.PIDFlightControl` (batched over the formation). Deterministic: no random
numbers are drawn, so runs repeat bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..aircraft import air_data_of
from ..aircraft.envelope import describe_status
from ..atmosphere.wind import WindInput
from ..control.observation import fcs_observation
from ..control.tracker import track_errors
from ..sim import WakeConfig
from ..rollout import Recorder, ZeroPolicy, rollout
from ..scenarios import Scenario, get_scenario

__all__ = ["ScenarioRun", "run_scenario", "scenario_metrics", "run_scenario_to_dir", "MAX_DURATION_S"]

from ..constants import AEROSONDE_SPAN_M, MAX_DURATION_S  # noqa: E402  (the histories are preallocated)


@dataclass(frozen=True, eq=False)
class ScenarioRun:
    """Time histories of one run, arrays (T, V, ...) sampled at the start of each step."""

    scenario: Scenario
    wake: bool
    time: np.ndarray  # (T,)
    h: dict  # name -> array (T, V[, k])
    completed: bool
    status_message: str


def run_scenario(scenario: str | Scenario, wake: bool | None = None, duration_s: float | None = None,
                 wake_config: WakeConfig | None = None) -> ScenarioRun:
    """Fly ``scenario`` (a name or a :class:`Scenario`) with the PID baseline on every aircraft;
    ``wake`` None uses its default. The physics step is the environments' episode engine (so an
    env flown by the PID gives exactly these numbers); this function records the histories."""
    from ..sim import EnvConfig, Simulation

    sc = get_scenario(scenario) if isinstance(scenario, str) else scenario
    if not isinstance(sc, Scenario):
        raise ValueError(f"scenario must be a name or a Scenario, got {type(scenario).__name__}")
    wake = sc.wake_default if wake is None else bool(wake)
    if duration_s is not None and not (math.isfinite(duration_s) and 0 < duration_s <= MAX_DURATION_S):
        raise ValueError(f"duration_s must be in (0, {MAX_DURATION_S:g}] s, got {duration_s!r}")
    if duration_s is not None and duration_s < sc.dt:
        raise ValueError(f"duration_s {duration_s!r} is shorter than one step of {sc.name!r} ({sc.dt:g} s)")
    # every UAV PID-flown (no agents), one physics step per decision; a collision does not end the run (the
    # thesis's runs measure the separation instead), an envelope exit does
    sim = Simulation(EnvConfig(scenario=sc, wake=wake, duration_s=duration_s, control_hz=1.0 / sc.dt,
                               collision_separation_b=0.0), 1, agents=(), wake_config=wake_config)
    rec = _HistoryRecorder(sim)
    res = rollout(sim, ZeroPolicy(), [0], recorders=[rec])  # nothing is randomised: the seed is not used
    n = int(res.decisions[0])
    time, h = np.arange(n) * sc.dt, {key: val[:n] for key, val in rec.h.items()}
    completed, message = True, "completed"
    if res.terminated[0]:
        status = h["status"][-1].astype(np.int64)
        completed = False
        bad = int(np.nonzero(status)[0][0])
        message = f"vehicle {bad} left the envelope at t = {n * sc.dt:.2f} s ({describe_status(status[bad])})"
    return ScenarioRun(sc, wake, time, h, completed, message)


class _HistoryRecorder(Recorder):
    """The run's time histories, sampled at the start of each physics step (the controls and the induced
    wind: those the step applied), into arrays (T, V, ...) preallocated for the full duration."""

    def __init__(self, sim) -> None:
        n_steps, v = sim.n_steps, sim.n_vehicles
        names3 = ("position_ned", "velocity_ned", "euler", "rates_body", "controls", "induced_wind_ned",
                  "induced_omega_body", "position_demand_ned", "ambient_wind_ned")
        self.h = {k: np.full((n_steps, v, 4 if k == "controls" else 3), np.nan) for k in names3}
        for k in ("airspeed", "alpha", "beta", "along_track", "off_track", "altitude_error", "track_angle", "status"):
            self.h[k] = np.full((n_steps, v), np.nan)

    def before_step(self, sim, alive, k) -> None:
        state, amb = sim.aircraft[0].copy(), sim.ambient_wind()[0]
        self._pre = (state, amb, fcs_observation(state, np.zeros(3), np.zeros(3), WindInput(wind_ned=amb + sim.induced[0])),
                     sim.position_demand[0].copy(), sim.velocity_demand[0].copy())  # the demands of this step

    def after_step(self, sim, out, actions, alive, k) -> None:
        h, i = self.h, k - 1
        state, amb, obs, pd, vd = self._pre
        cmd, induced, status = sim.commands[0], sim.induced[0], sim.state.status[0]
        ad = air_data_of(state, WindInput(wind_ned=amb + induced))
        atd, otd, _, _ = track_errors(obs["position_ned"], obs["velocity_ned"], pd, vd)
        h["position_ned"][i], h["velocity_ned"][i], h["euler"][i] = obs["position_ned"], obs["velocity_ned"], obs["euler"]
        h["rates_body"][i], h["controls"][i], h["induced_wind_ned"][i] = obs["rates_body"], cmd, induced
        h["induced_omega_body"][i], h["position_demand_ned"][i], h["ambient_wind_ned"][i] = sim.omega[0], pd, amb
        h["airspeed"][i], h["alpha"][i], h["beta"][i] = ad["airspeed_raw"], ad["alpha_raw"], ad["beta_raw"]
        h["along_track"][i], h["off_track"][i] = atd, otd
        h["altitude_error"][i] = -(obs["position_ned"][:, 2] - pd[:, 2])
        h["track_angle"][i] = np.arctan2(obs["velocity_ned"][:, 1], obs["velocity_ned"][:, 0])
        h["status"][i] = status


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def _window(run: ScenarioRun, t0: float, t1: float = np.inf) -> np.ndarray:
    """Samples with t0 <= t < t1; a run too short for the window uses its last sample."""
    w = (run.time >= t0) & (run.time < t1)
    if not w.any():
        w = np.zeros(run.time.size, bool)
        w[-1] = True
    return w


def _vehicle_stats(run: ScenarioRun, i: int, t0: float = 0.0, t1: float = np.inf) -> dict:
    h, w = run.h, _window(run, t0, t1)
    iw = h["induced_wind_ned"][w, i]
    return {
        "window_s": [float(run.time[w][0]), float(run.time[w][-1] + run.scenario.dt)],
        "along_track_error_m": {"rms": _rms(h["along_track"][w, i]), "max_abs": float(np.max(np.abs(h["along_track"][w, i]))),
                                "mean": float(np.mean(h["along_track"][w, i]))},
        "off_track_error_m": {"rms": _rms(h["off_track"][w, i]), "max_abs": float(np.max(np.abs(h["off_track"][w, i]))),
                              "mean": float(np.mean(h["off_track"][w, i]))},
        "altitude_error_m": {"rms": _rms(h["altitude_error"][w, i]), "max_abs": float(np.max(np.abs(h["altitude_error"][w, i]))),
                             "mean": float(np.mean(h["altitude_error"][w, i]))},
        "sideslip_rad": {"rms": _rms(h["beta"][w, i]), "std": float(np.std(h["beta"][w, i]))},
        "yaw_rate_rad_s": {"rms": _rms(h["rates_body"][w, i, 2]), "std": float(np.std(h["rates_body"][w, i, 2]))},
        "roll_rate_rad_s": {"rms": _rms(h["rates_body"][w, i, 0])},
        "rudder_rad": {"std": float(np.std(h["controls"][w, i, 2])), "mean": float(np.mean(h["controls"][w, i, 2]))},
        "elevator_rad": {"mean": float(np.mean(h["controls"][w, i, 0]))},
        "throttle": {"mean": float(np.mean(h["controls"][w, i, 3])), "max": float(np.max(h["controls"][w, i, 3]))},
        "induced_wind_ned_mps": {"mean": iw.mean(axis=0).tolist(), "max_abs": np.abs(iw).max(axis=0).tolist()},
    }


def _recovery_time(run: ScenarioRun, t_end: float, t_stop: float, pos_tol: float, alt_tol: float) -> float | None:
    """Seconds after ``t_end`` from which |dx|, |dy| <= pos_tol and |dh| <= alt_tol hold until ``t_stop``."""
    h, w = run.h, _window(run, t_end, t_stop)
    ok = (np.abs(h["along_track"][w, 0]) <= pos_tol) & (np.abs(h["off_track"][w, 0]) <= pos_tol) & \
         (np.abs(h["altitude_error"][w, 0]) <= alt_tol)
    if not ok[-1]:
        return None
    bad = np.nonzero(~ok)[0]
    k = 0 if bad.size == 0 else bad[-1] + 1
    return float(run.time[w][k] - t_end)


RECOVERY_TOLERANCE_M = {"position": 0.25, "altitude": 0.25}


def scenario_metrics(run: ScenarioRun) -> dict:
    """Scenario-specific numbers (SI units) for the metrics JSON and the tests."""
    sc, h = run.scenario, run.h
    m: dict = {"scenario": sc.name, "wake": run.wake, "completed": run.completed, "status": run.status_message,
               "duration_s": float(run.time[-1] + sc.dt), "dt_s": sc.dt}
    if sc.name == "tracking":
        err = h["position_ned"][:, 0] - h["position_demand_ned"][:, 0]
        dist = np.linalg.norm(err, axis=1)
        within = np.nonzero(dist > 1.0)[0]
        m.update({
            "initial_error_m": float(dist[0]), "final_error_m": float(dist[-1]),
            "final_error_ned_m": err[-1].tolist(),
            "time_to_within_1m_s": None if within.size == 0 or within[-1] + 1 >= dist.size else float(run.time[within[-1] + 1]),
            "max_bank_rad": float(np.max(np.abs(h["euler"][:, 0, 0]))),
            "max_speed_mps": float(np.max(h["airspeed"][:, 0])),
            "max_track_angle_rad": float(np.max(np.abs(h["track_angle"][:, 0]))),
            "altitude_overshoot_m": float(max(0.0, np.max(-(h["altitude_error"][:, 0])))),
        })
    elif sc.name == "gust":
        windows = sc.notes.get("recovery_windows_s", {})
        out = {}
        stops = [g.start_s for g in sc.gusts[1:]] + [run.time[-1] + sc.dt]
        for g, key, stop in zip(sc.gusts, ("gust_40s", "gust_20s"), stops):
            w = _window(run, g.start_s, g.end_s)
            out[key] = {
                "start_s": g.start_s, "end_s": g.end_s, "amplitude_ned_mps": list(g.amplitude_ned),
                "max_altitude_loss_m": float(max(0.0, np.max(-h["altitude_error"][w, 0]))),
                "max_abs_along_track_m": float(np.max(np.abs(h["along_track"][_window(run, g.start_s, stop), 0]))),
                "max_abs_off_track_m": float(np.max(np.abs(h["off_track"][_window(run, g.start_s, stop), 0]))),
                "throttle_saturated_s": float(np.sum(h["controls"][w, 0, 3] >= 0.999) * sc.dt),
                "overtakes_after_gust": bool(np.max(h["along_track"][_window(run, g.end_s - g.decay_s, stop), 0]) > 0.0),
                "recovery_time_s": _recovery_time(run, g.end_s, stop, RECOVERY_TOLERANCE_M["position"],
                                                  RECOVERY_TOLERANCE_M["altitude"]),
                "thesis_recovery_within_s": windows.get(key),
            }
        m["gusts"] = out
        m["recovery_tolerance_m"] = RECOVERY_TOLERANCE_M
    elif sc.name == "formation_keeping":
        m["follower"] = _vehicle_stats(run, 1, 10.0)
        m["follower_first_10s"] = _vehicle_stats(run, 1, 0.0, 10.0)
        m["leader"] = _vehicle_stats(run, 0, 10.0)
    elif sc.name == "reconfiguration":
        rel = h["position_ned"][:, 1] - h["position_ned"][:, 0]
        sep = np.linalg.norm(rel, axis=1)
        ahead = rel[:, 0]  # leader flies north: relative north is the along-track separation
        cross = np.nonzero((ahead[:-1] < 0) & (ahead[1:] >= 0))[0]
        iw = h["induced_wind_ned"]
        before, after = _window(run, 0.0, 10.0), _window(run, 52.0)
        m.update({
            "min_separation_m": float(sep.min()), "min_separation_spans": float(sep.min() / AEROSONDE_SPAN_M),
            "time_of_min_separation_s": float(run.time[int(np.argmin(sep))]),
            "level_in_north_at_s": None if cross.size == 0 else float(run.time[cross[0] + 1]),
            "final_relative_position_track_frame_m": [float(ahead[-1]), float(rel[-1, 1]), float(rel[-1, 2])],
            "final_slot_error_m": float(np.linalg.norm(h["position_ned"][-1, 1] - h["position_demand_ned"][-1, 1])),
            "induced_wind_on_vehicle0_mps": {"first_10s_mean": iw[before, 0].mean(0).tolist(),
                                              "after_52s_mean": iw[after, 0].mean(0).tolist()},
            "induced_wind_on_vehicle1_mps": {"first_10s_mean": iw[before, 1].mean(0).tolist(),
                                              "after_52s_mean": iw[after, 1].mean(0).tolist()},
            "vehicle0_after_swap": _vehicle_stats(run, 0, 52.0),
            "vehicle1_before_swap": _vehicle_stats(run, 1, 0.0, 10.0),
        })
    return m


def run_scenario_to_dir(name: str, out_dir, wake: bool = True, overwrite: bool = False,
                        duration_s: float | None = None, figures: bool = True) -> dict:
    """Run scenario ``name`` and write ``metrics.json`` and its figures into ``out_dir`` (created;
    an existing non-empty directory is an error unless ``overwrite``). Returns the metrics dict.

    ``formation_keeping`` runs twice (wake on and off) and reports both; ``wake`` selects the
    primary run of the others (``--no-wake``)."""
    from ..io import atomic_write_json, prepare_output_dir

    sc = get_scenario(name)
    if duration_s is not None and not (math.isfinite(duration_s) and sc.dt <= duration_s <= MAX_DURATION_S):
        raise ValueError(f"duration_s must be in [{sc.dt:g}, {MAX_DURATION_S:g}] s, got {duration_s!r}")
    out = prepare_output_dir(out_dir, overwrite=overwrite)
    runs = {}
    if sc.name == "formation_keeping":
        runs["wake_on"] = run_scenario(sc, True, duration_s)
        runs["wake_off"] = run_scenario(sc, False, duration_s)
        metrics = {"scenario": sc.name, "description": sc.description,
                   "wake_on": scenario_metrics(runs["wake_on"]), "wake_off": scenario_metrics(runs["wake_off"])}
        on, off = metrics["wake_on"]["follower"], metrics["wake_off"]["follower"]
        metrics["wake_vs_no_wake"] = {
            k: {"wake_on": on[k]["rms"], "wake_off": off[k]["rms"]}
            for k in ("along_track_error_m", "off_track_error_m", "altitude_error_m", "sideslip_rad", "yaw_rate_rad_s")}
    else:
        runs["wake_on" if wake else "wake_off"] = run_scenario(sc, wake, duration_s)
        metrics = {"description": sc.description, **scenario_metrics(next(iter(runs.values())))}
    files = []
    if figures:
        from ..plotting.scenario_figures import scenario_figures

        files = [str(p.name) for p in scenario_figures(runs, out, overwrite=overwrite)]
    metrics["figures"] = files
    atomic_write_json(Path(out) / "metrics.json", metrics, overwrite=overwrite)
    return metrics
