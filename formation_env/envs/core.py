"""The batched environment core: B formations stepped together, arrays in and out.

Both the PettingZoo ParallelEnv (B = 1) and the vector environments (B = many) are thin views of
this class, so a formation behaves identically whichever env carries it.

Per decision: the agents' actions (B, A, 4) are held for ``substeps`` physics steps; collisions
and envelope exits are latched over those steps; then observations (B, A, D), rewards (B, A),
``terminated`` (B,) and ``truncated`` (B,) are read off the state.
"""

from __future__ import annotations

import numpy as np

from .config import EnvConfig
from .engine import ActionTarget, FormationEpisode
from .observations import build_observations, observation_size
from .rewards import min_separation_m, reward_terms, slot_error_m

__all__ = ["FormationCore", "AEROSONDE_SPAN_M"]

AEROSONDE_SPAN_M = 2.9


class FormationCore:
    def __init__(self, config: EnvConfig, batch_size: int = 1) -> None:
        if isinstance(batch_size, bool) or not isinstance(batch_size, (int, np.integer)) or batch_size < 1:
            raise ValueError(f"batch_size must be an integer >= 1, got {batch_size!r}")
        self.config = config
        self.engine = FormationEpisode(config, batch_size=int(batch_size))
        eng = self.engine
        n = eng.n_vehicles
        learning = config.learning
        if learning == "all":
            idx = tuple(range(n))
        elif learning == "followers":
            if n < 2:
                raise ValueError(f"learning='followers' needs a formation; scenario {config.scenario!r} has one UAV")
            idx = tuple(range(1, n))
        else:
            bad = [i for i in learning if not 0 <= i < n]
            if bad:
                raise ValueError(f"learning indices {bad} out of range for {n} UAVs in {config.scenario!r}")
            idx = tuple(sorted(learning))
        self.agent_indices = idx
        self.mask = np.zeros(n, dtype=bool)
        self.mask[list(idx)] = True
        physics_hz = 1.0 / eng.dt
        ratio = physics_hz / config.control_hz
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(f"control_hz must divide the physics rate {physics_hz:g} Hz, got {config.control_hz!r}")
        self.substeps = int(round(ratio))
        self.obs_size = observation_size(n)
        b = eng.batch_size
        self.previous_action = np.zeros((b, n, 4))
        self.previous_error = np.zeros((b, n))
        self.last_terms: dict | None = None
        self.last_saving = np.zeros((b, n))
        self.collided = np.zeros(b, dtype=bool)
        self.crashed = np.zeros((b, n), dtype=bool)

    @property
    def batch_size(self) -> int:
        return self.engine.batch_size

    @property
    def n_vehicles(self) -> int:
        return self.engine.n_vehicles

    def reset(self, indices=None, seeds=None) -> None:
        eng = self.engine
        idx = np.arange(eng.batch_size) if indices is None else np.atleast_1d(np.asarray(indices, dtype=np.int64))
        eng.reset(idx, seeds)
        self.previous_action[idx] = 0.0
        self.previous_error[idx] = slot_error_m(eng.state[idx], eng.position_demand[idx])
        self.collided[idx] = False
        self.crashed[idx] = False
        self.last_saving[idx] = 0.0

    def step(self, agent_actions: np.ndarray):
        """agent_actions (B, A, 4) in [-1, 1] (validated by the caller).
        Returns (rewards (B, V), terminated (B,), truncated (B,))."""
        eng = self.engine
        b, n = eng.batch_size, eng.n_vehicles
        act = np.zeros((b, n, 4))
        act[:, self.mask] = agent_actions
        target = ActionTarget(self.config.action_mode, act, self.mask)
        status_any, min_sep = eng.advance(target, self.substeps)
        collided = min_sep < self.config.collision_separation_b * AEROSONDE_SPAN_M
        crashed = status_any != 0
        error = slot_error_m(eng.state, eng.position_demand_now())
        saving = self._saving()
        with np.errstate(invalid="ignore"):
            separation = min_separation_m(eng.state)
        terms = reward_terms(self.config.reward, error, self.previous_error, act, self.previous_action, saving,
                             separation, np.broadcast_to(collided[:, None], error.shape), crashed,
                             self.config.collision_separation_b * AEROSONDE_SPAN_M, AEROSONDE_SPAN_M,
                             remaining_decisions=np.maximum(eng.n_steps - eng.step_count, 0) / self.substeps)
        self.previous_error = error
        self.previous_action = act
        self.last_terms, self.last_saving = terms, saving
        self.collided, self.crashed = collided, crashed
        terminated = collided | crashed.any(axis=1)
        truncated = ~terminated & (eng.step_count >= eng.n_steps)
        return terms["total"], terminated, truncated

    def observations(self) -> np.ndarray:
        """(B, V, D) float64 observation vectors of every vehicle."""
        eng = self.engine
        sc = eng.scenario
        return build_observations(eng.state, eng.induced, eng.omega, eng.ambient_wind(), eng.turbulence_body(),
                                  eng.position_demand_now(), eng.velocity_demand, self.previous_action,
                                  eng.slot_schedule_features(), eng.controller_state(), sc.airspeed_mps, sc.altitude_m)

    @property
    def benefit_enabled(self) -> bool:
        return (self.config.compute_benefit or self.config.reward.benefit > 0) and self.engine.sim.wake_model is not None

    def _saving(self) -> np.ndarray:
        eng = self.engine
        out = np.zeros((eng.batch_size, eng.n_vehicles))
        if not self.benefit_enabled:
            return out
        ok = np.all(eng.status == 0, axis=1) & np.all(np.isfinite(eng.state.reshape(eng.batch_size, -1)), axis=1)
        if not ok.any():
            return out
        from ..sim.formation import ell_state_from_aircraft
        from ..wake import formation_benefit

        ell = ell_state_from_aircraft(eng.state[ok], eng.ambient_wind()[ok], eng.sim.wing_origin_body)
        out[ok] = formation_benefit(eng.sim.wake_model, ell)["induced_drag_saving"]
        return out

    def infos(self, i: int) -> list[dict]:
        """Per-vehicle info dicts of formation ``i`` (agents' metrics)."""
        eng = self.engine
        err_vec = eng.state[i, :, 10:13] - eng.position_demand[i]
        with np.errstate(invalid="ignore"):
            sep = min_separation_m(eng.state[i:i + 1])[0]
        gust = eng.turbulence_gust_ned(i)
        out = []
        for v in range(eng.n_vehicles):
            info = {
                "time_s": float(eng.time_s[i]),
                "slot_error_m": float(np.linalg.norm(err_vec[v])),
                "slot_error_ned_m": err_vec[v].copy(),
                "min_separation_m": float(sep[v]),
                "induced_wind_ned_mps": eng.induced[i, v].copy(),
                "induced_omega_body_rad_s": eng.omega[i, v].copy(),
                "fuel_kg": float(eng.state[i, v, 13]),
                "gust_ned_mps": gust[v].copy(),
                "status": int(eng.status[i, v]),
                "collision": bool(self.collided[i]),
                "crashed": bool(self.crashed[i, v]),
                "command": eng.commands[i, v].copy(),
            }
            if self.benefit_enabled:
                info["induced_drag_saving"] = float(self.last_saving[i, v])
            if self.last_terms is not None:
                info["reward_terms"] = {k: float(t[i, v]) for k, t in self.last_terms.items()}
            out.append(info)
        return out
