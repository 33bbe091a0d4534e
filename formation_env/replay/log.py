"""Episode log: what a replay needs, per sample and UAV, in SI units and named frames.

Build one from a scenario run (:meth:`EpisodeLog.from_scenario_run`) or record an environment
episode with :class:`EpisodeRecorder` (call ``record()`` after ``reset`` and after every step)::

    env = formation_env.parallel_env("formation_keeping")
    env.reset(seed=0)
    rec = EpisodeRecorder(env.sim)   # records formation 0 of the simulation
    rec.record()
    while env.agents:
        env.step({a: env.action_space(a).sample() for a in env.agents})
        rec.record()
    log = rec.log()
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..frames import dcm_body_to_ned_from_quaternion, euler_from_quaternion
from ..io import atomic_write

__all__ = ["EpisodeLog", "EpisodeRecorder"]

_ARRAYS = ("time_s", "position_ned", "euler_rad", "velocity_ned", "induced_wind_ned", "induced_omega_body",
           "ambient_wind_ned", "position_demand_ned")


@dataclass(frozen=True, eq=False)
class EpisodeLog:
    """Arrays (T, V, 3) unless noted. ``time_s`` (T,) s; ``position_ned`` flat-earth NED m;
    ``euler_rad`` 3-2-1 (phi, theta, psi) rad; ``velocity_ned`` ground velocity m/s;
    ``induced_wind_ned`` the ELL effective induced wind, NED m/s; ``induced_omega_body`` the ELL
    rotational wind, body axes rad/s; ``ambient_wind_ned`` m/s (zeros if unknown);
    ``position_demand_ned`` the slot/reference (NaN if unknown)."""

    time_s: np.ndarray
    position_ned: np.ndarray
    euler_rad: np.ndarray
    velocity_ned: np.ndarray
    induced_wind_ned: np.ndarray
    induced_omega_body: np.ndarray
    ambient_wind_ned: np.ndarray
    position_demand_ned: np.ndarray
    scenario: str = ""
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        t = np.asarray(self.time_s, dtype=float)
        if t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t)):
            raise ValueError(f"EpisodeLog.time_s must be a non-empty finite 1-D array, got shape {t.shape}")
        object.__setattr__(self, "time_s", t)
        shape = None
        for name in _ARRAYS[1:]:
            a = np.asarray(getattr(self, name), dtype=float)
            if a.ndim != 3 or a.shape[0] != t.size or a.shape[2] != 3:
                raise ValueError(f"EpisodeLog.{name} must have shape (T={t.size}, V, 3), got {a.shape}")
            shape = shape or a.shape
            if a.shape != shape:
                raise ValueError(f"EpisodeLog.{name} has shape {a.shape}, expected {shape}")
            object.__setattr__(self, name, a)

    @property
    def n_vehicles(self) -> int:
        return self.position_ned.shape[1]

    @property
    def n_samples(self) -> int:
        return self.time_s.size

    @classmethod
    def from_scenario_run(cls, run) -> "EpisodeLog":
        """From :class:`formation_env.runs.runner.ScenarioRun` (its ``time`` and ``h`` histories)."""
        h = run.h
        return cls(run.time, h["position_ned"], h["euler"], h["velocity_ned"], h["induced_wind_ned"],
                   h["induced_omega_body"], h["ambient_wind_ned"], h["position_demand_ned"],
                   scenario=run.scenario.name, meta={"wake": bool(run.wake), "dt_s": run.scenario.dt,
                                                     "status": run.status_message})

    def save_npz(self, path, *, overwrite: bool = False):
        """Write the arrays to ``path`` (.npz), atomically."""
        def w(tmp):
            with open(tmp, "wb") as f:
                np.savez_compressed(f, scenario=np.array(self.scenario), **{k: getattr(self, k) for k in _ARRAYS})
        return atomic_write(path, w, overwrite=overwrite)

    @classmethod
    def load_npz(cls, path) -> "EpisodeLog":
        with np.load(path) as d:
            return cls(*(d[k] for k in _ARRAYS), scenario=str(d["scenario"]))


class EpisodeRecorder:
    """Records formation ``index`` of a :class:`~formation_env.sim.Simulation` (``env.sim``): call
    :meth:`record` after reset and after every step; :meth:`log` gives the :class:`EpisodeLog`. Reads
    only ``aircraft``, ``induced``, ``omega``, ``time_s``, ``position_demand`` and ``ambient_wind()``."""

    def __init__(self, sim, index: int = 0) -> None:
        self.sim = sim
        self.index = int(index)
        self._rows: list[tuple] = []

    def record(self) -> None:
        e, i = self.sim, self.index
        s = np.array(e.aircraft[i], dtype=float)
        q = s[:, 6:10]
        vel = np.einsum("vij,vj->vi", dcm_body_to_ned_from_quaternion(q), s[:, 0:3])
        amb = np.asarray(e.ambient_wind()[i], dtype=float)
        pd = np.array(e.position_demand[i], dtype=float)
        self._rows.append((float(np.asarray(e.time_s)[i]), s[:, 10:13].copy(), euler_from_quaternion(q), vel,
                           np.array(e.induced[i], dtype=float), np.array(e.omega[i], dtype=float), amb, pd))

    def __len__(self) -> int:
        return len(self._rows)

    def log(self) -> EpisodeLog:
        if not self._rows:
            raise ValueError("EpisodeRecorder: nothing recorded yet (call record() after reset and each step)")
        cols = list(zip(*self._rows))
        sc = self.sim.scenario.name
        return EpisodeLog(np.array(cols[0]), *(np.stack(c) for c in cols[1:]), scenario=sc,
                          meta={"dt_s": float(self.sim.dt)})
