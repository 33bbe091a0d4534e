"""What limits close-formation station keeping (issue 24): the station keeper flown with what a real controller
does not have, on the same episodes as the plain keeper.

* **Thrust** (``--throttle-max`` of ``formation-env evaluate``; :class:`formation_env.sim.config.EnvConfig`): the
  flight control's throttle ceiling raised for every UAV, a counterfactual engine. Any policy flies it.
* **Decision rate**: the keeper deciding at 25 or 50 Hz instead of 10 (its gains are per second).
* **Told the disturbance, its own gust** (:func:`wind_preview_keeper`): the keeper's ambient-wind feed-forwards
  (along-track speed, the vertical gust's angle of attack) read the wind the follower meets ``tau`` s later. The
  field is frozen and the follower's path differs little from a first pass over the same seeds, so the wind that
  first pass recorded at decision ``k + tau f`` is that preview.
* **Told the disturbance, the slot's motion** (:func:`slot_preview_keeper`): the slot is the leader's position
  plus its offset, and the PID-flown leader's path hardly depends on the follower (its wake on the leader moves it
  by centimetres: the check reports how far the second pass's leader strays from the first's). The keeper aims across
  the track at where the slot will be ``tau`` s later: its lateral and vertical slot errors and their rates less the
  slot's departure from straight flight over ``tau`` (slot frame).

``formation-env publish ceilings [--episodes N] [--seed S] [--sigma X]`` prints the table
(docs/close_formation.md, "Ceilings", has the measured one). A preview of 0 s is the plain keeper bit for bit
(``tests/train/test_ceilings.py``)."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["FirstPass", "first_pass", "wind_preview_keeper", "slot_preview_keeper", "ceiling_rows",
           "ceilings_report"]


def _keeper_policy(name: str, act, reset, control_hz: float = 10.0):
    from .policy import EvalPolicy

    return EvalPolicy(name, "setpoints", act, control_hz, reset=reset)


class _RecordingKeeper:
    """The station keeper that records each decision's observed ambient wind (slot frame, the observation's slog
    encoding) and, given ``preview`` (decisions, rows, 3) of a first pass, reads row-wise the one ``shift``
    decisions later instead of its own."""

    def __init__(self, preview: np.ndarray | None = None, shift: int = 0) -> None:
        from agents.station_keeper import StationKeeper

        self.keeper = StationKeeper()
        self.preview, self.shift = preview, int(shift)
        self.record: list[np.ndarray] = []
        self.k = 0

    def reset(self, n_rows: int) -> None:
        self.keeper.reset(n_rows)
        self.record, self.k = [], 0

    def act(self, obs):
        from agents.common import observation_groups

        o = np.array(obs, dtype=float)
        _, groups = observation_groups(o, "wind_preview_keeper")  # views into o
        self.record.append(np.array(groups["ambient_wind"]))
        if self.preview is not None and self.shift > 0:
            groups["ambient_wind"][:] = self.preview[min(self.k + self.shift, len(self.preview) - 1)]
        self.k += 1
        return self.keeper.act(o.astype(np.float32))


class FirstPass(NamedTuple):
    """The plain keeper's pass over the episodes, which every preview reads: its per-episode metrics, the ambient wind
    it observed at each decision (decisions, rows, 3; the observation's encoding) and its slot's path (decisions,
    rows, 3; m NED)."""

    episodes: list
    wind: np.ndarray
    slot_path: np.ndarray


def first_pass(config, seeds) -> FirstPass:
    """The plain station keeper over ``seeds``, recording what the previews need (one pass for every ceiling)."""
    from .episodes import run_episodes

    keeper, path = _RecordingKeeper(), _SlotPath()
    eps = run_episodes(_keeper_policy("station_keeper", keeper.act, keeper.reset), config, seeds, recorders=[path])
    return FirstPass(eps, np.array(keeper.record), np.array(path.path))


def wind_preview_keeper(config, seeds, tau_s: float, first: FirstPass | None = None) -> list[dict]:
    """Per-episode metrics (:func:`train.evaluation.episodes.run_episodes`) of the keeper told the ambient wind it
    meets ``tau_s`` later (``first``: the plain pass over the same ``seeds``, flown here when None)."""
    from .episodes import run_episodes

    first = first_pass(config, seeds) if first is None else first
    told = _RecordingKeeper(first.wind, int(round(tau_s * config.control_hz)))
    return run_episodes(_keeper_policy(f"station_keeper+wind_preview_{tau_s:g}s", told.act, told.reset), config, seeds)


class _SlotPath:
    """Rollout recorder of every follower's slot (its position demand, m NED) at each decision."""

    def __init__(self, vehicle: int = 1) -> None:
        self.vehicle, self.path = vehicle, []

    def start(self, sim, out) -> None:
        self.path = []

    def before_step(self, sim, alive, k) -> None:
        self.path.append(np.array(sim.position_demand[:, self.vehicle]))

    def after_step(self, sim, out, actions, alive, k) -> None:
        pass

    def ended(self, sim, out, formations, k) -> None:
        pass


class _SlotPreviewKeeper:
    """The keeper aiming across the track at the slot ``shift`` decisions ahead on the recorded ``path``
    (decisions, rows, 3; m NED)."""

    def __init__(self, path: np.ndarray, shift: int, control_hz: float) -> None:
        from agents.station_keeper import StationKeeper

        self.keeper, self.path, self.shift, self.dt = StationKeeper(), path, int(shift), 1.0 / control_hz
        self.k = 0

    def reset(self, n_rows: int) -> None:
        self.keeper.reset(n_rows)
        self.k = 0

    def act(self, obs):
        from agents.common import observation_groups
        from agents.pid_formation import inverse_slog
        from formation_env.envs.observations import POSITION_SCALE_M, VELOCITY_SCALE_MPS, slog
        from formation_env.frames import ned_to_track_frame

        o = np.array(obs, dtype=float)
        i, p = self.k, self.path
        j = min(i + self.shift, len(p) - 1)
        self.k += 1
        if j > i:
            _, groups = observation_groups(o, "slot_preview_keeper")
            v_now = (p[i] - p[max(i - 1, 0)]) / self.dt
            v_then = (p[j] - p[max(j - 1, 0)]) / self.dt
            dev = p[j] - p[i] - (j - i) * self.dt * v_now  # the slot's departure from straight flight, m NED
            heading = np.arctan2(v_now[:, 1], v_now[:, 0])

            def across(x):  # NED -> slot frame, the along-track component left out (the saving hardly needs it)
                return ned_to_track_frame(x, heading) * np.array([0.0, 1.0, 1.0])

            e = inverse_slog(groups["slot_position_error"], POSITION_SCALE_M)
            de = inverse_slog(groups["slot_velocity_error"], VELOCITY_SCALE_MPS)
            groups["slot_position_error"][:] = slog(e - across(dev), POSITION_SCALE_M)
            groups["slot_velocity_error"][:] = slog(de - across(v_then - v_now), VELOCITY_SCALE_MPS)
        return self.keeper.act(o.astype(np.float32))


def slot_preview_keeper(config, seeds, tau_s: float, first: FirstPass | None = None) -> tuple[list[dict], float]:
    """Per-episode metrics of the keeper aiming at its slot ``tau_s`` ahead on the path of ``first`` (the plain pass
    over the same ``seeds``, flown here when None), and how far (m) this pass's slot strayed from that path at most
    (the preview's accuracy)."""
    from .episodes import run_episodes

    first = first_pass(config, seeds) if first is None else first
    told, path = _SlotPreviewKeeper(first.slot_path, int(round(tau_s * config.control_hz)), config.control_hz), _SlotPath()
    eps = run_episodes(_keeper_policy(f"station_keeper+slot_preview_{tau_s:g}s", told.act, told.reset), config, seeds,
                       recorders=[path])
    n = min(len(path.path), len(first.slot_path))
    return eps, float(np.max(np.abs(np.array(path.path[:n]) - first.slot_path[:n])))


def _row(name: str, eps: list[dict], note: str = "") -> dict:
    g = {k: np.array([e[k] for e in eps], dtype=float) for k in ("harvest_ratio", "rms_lateral_m", "rms_vertical_m",
                                                                  "rms_along_track_m", "collision")}
    return {"controller": name, "harvest": float(g["harvest_ratio"].mean()),
            "rms_lateral_m": float(g["rms_lateral_m"].mean()), "rms_vertical_m": float(g["rms_vertical_m"].mean()),
            "rms_along_track_m": float(g["rms_along_track_m"].mean()),
            "surges": int((g["rms_along_track_m"] > 3.0).sum()), "collisions": int(g["collision"].sum()), "note": note}


def ceiling_rows(seeds, sigma: float = 1.0, taus=(0.5, 1.0, 2.0), slot_taus=(0.1, 0.2, 0.5), rates=(25.0, 50.0),
                 throttle_max: float = 1.5) -> list[dict]:
    """The table's rows (means over the episodes of ``seeds`` at turbulence ``sigma``): the plain keeper, then each
    ceiling."""
    from agents.station_keeper import StationKeeper

    from .episodes import eval_env_config, run_episodes

    cfg = eval_env_config("close_formation", "setpoints", turbulence_sigma_mps=sigma, compute_benefit=True)
    first = first_pass(cfg, seeds)  # the plain keeper's row, and what every preview reads
    rows = [_row("station_keeper", first.episodes)]
    k = StationKeeper()
    hi = eval_env_config("close_formation", "setpoints", turbulence_sigma_mps=sigma, compute_benefit=True,
                         throttle_max=throttle_max)
    rows.append(_row(f"throttle ceiling {throttle_max:g}", run_episodes(_keeper_policy("k", k.act, k.reset), hi, seeds),
                     "every UAV; counterfactual engine"))
    for hz in rates:
        k = StationKeeper(control_hz=hz)
        c = eval_env_config("close_formation", "setpoints", turbulence_sigma_mps=sigma, compute_benefit=True,
                            control_hz=hz)
        rows.append(_row(f"decisions at {hz:g} Hz", run_episodes(_keeper_policy("k", k.act, k.reset, hz), c, seeds)))
    for tau in taus:
        rows.append(_row(f"told its gust {tau:g} s ahead", wind_preview_keeper(cfg, seeds, tau, first)))
    for tau in slot_taus:
        eps, stray = slot_preview_keeper(cfg, seeds, tau, first)
        rows.append(_row(f"told its slot {tau:g} s ahead", eps, f"leader path within {stray:.2f} m of the first pass"))
    return rows


def _table(rows: list[dict]) -> str:
    head = ("| controller | harvest | lateral RMS m | vertical RMS m | along RMS m | surges (along > 3 m) | collisions | note |\n"
            "|---|---|---|---|---|---|---|---|\n")
    return head + "".join(f"| {r['controller']} | {r['harvest']:.3f} | {r['rms_lateral_m']:.3f} | {r['rms_vertical_m']:.3f} | "
                          f"{r['rms_along_track_m']:.2f} | {r['surges']} | {r['collisions']} | {r['note']} |\n" for r in rows)


def ceilings_report(episodes: int = 100, seed: int | None = None, sigma: float = 1.0) -> str:
    """``formation-env publish ceilings``: the ceilings table (markdown) on ``episodes`` (1..1000) consecutive seeds
    from ``seed`` (default the test seeds' base) at turbulence ``sigma`` (0..3 m/s). A bad value is a ValueError
    naming it and its range."""
    from train.config import TEST_SEED_BASE

    seed = TEST_SEED_BASE if seed is None else seed
    if not 1 <= episodes <= 1000:
        raise ValueError(f"--episodes must be an integer in [1, 1000], got {episodes}")
    if not (math.isfinite(sigma) and 0.0 <= sigma <= 3.0):
        raise ValueError(f"--sigma must be a number of m/s in [0, 3], got {sigma}")
    if seed < 0:
        raise ValueError(f"--seed must be an integer >= 0, got {seed}")
    rows = ceiling_rows(list(range(seed, seed + episodes)), sigma=sigma)
    return f"close_formation, {episodes} episodes from seed {seed}, sigma {sigma:g} m/s\n\n" + _table(rows)
