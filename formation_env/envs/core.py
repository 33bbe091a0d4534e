"""The batched environment core: B formations stepped together, arrays in and out.

A thin view of the compiled decision step (:func:`formation_env.sim.step.step`) for the env
adapters (PettingZoo parallel/AEC, Gymnasium, the SB3 VecEnv and the Gymnasium VectorEnv): it picks
the agents' rows, validates nothing twice and builds the info dicts. No physics here.
"""

from __future__ import annotations

import numpy as np

from .config import EnvConfig
from .engine import AEROSONDE_SPAN_M, FormationEpisode
from .observations import observation_size

__all__ = ["FormationCore", "AEROSONDE_SPAN_M"]


class FormationCore:
    def __init__(self, config: EnvConfig, batch_size: int = 1) -> None:
        if isinstance(batch_size, bool) or not isinstance(batch_size, (int, np.integer)) or batch_size < 1:
            raise ValueError(f"batch_size must be an integer >= 1, got {batch_size!r}")
        self.config = config
        from ..scenarios import Scenario, get_scenario

        sc = config.scenario if isinstance(config.scenario, Scenario) else get_scenario(config.scenario)
        n = sc.n_vehicles
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
        physics_hz = 1.0 / sc.dt
        ratio = physics_hz / config.control_hz
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(f"control_hz must divide the physics rate {physics_hz:g} Hz, got {config.control_hz!r}")
        self.substeps = int(round(ratio))
        self.engine = FormationEpisode(config, batch_size=int(batch_size), mask=self.mask, substeps=self.substeps)
        self.obs_size = observation_size(n)
        self._actions = np.zeros((self.engine.batch_size, n, 4))
        self.last_terms: dict | None = None

    @property
    def batch_size(self) -> int:
        return self.engine.batch_size

    @property
    def n_vehicles(self) -> int:
        return self.engine.n_vehicles

    @property
    def out(self):
        return self.engine.out

    @property
    def collided(self) -> np.ndarray:
        return self.engine.out.collided

    @property
    def crashed(self) -> np.ndarray:
        return self.engine.out.crashed

    @property
    def last_saving(self) -> np.ndarray:
        return self.engine.out.saving

    @property
    def benefit_enabled(self) -> bool:
        return bool(self.engine.params.benefit_on)

    def reset(self, indices=None, seeds=None) -> None:
        self.engine.reset(indices, seeds)

    def step(self, agent_actions: np.ndarray):
        """agent_actions (B, A, 4) in [-1, 1] (validated by the caller).
        Returns (rewards (B, V), terminated (B,), truncated (B,))."""
        self._actions[:, self.mask] = agent_actions
        out = self.engine.decide(self._actions)
        self.last_terms = True
        return out.reward, out.terminated, out.truncated

    def observations(self) -> np.ndarray:
        """(B, V, D) float64 observation vectors of every vehicle (a view: copy to keep)."""
        return self.engine.out.observation

    def infos(self, i: int) -> list[dict]:
        """Per-vehicle info dicts of formation ``i`` (agents' metrics)."""
        eng, out = self.engine, self.engine.out
        err_vec = eng.state[i, :, 10:13] - eng.position_demand[i]
        gust = eng.turbulence_gust_ned(i)
        terms = eng.reward_terms(i) if self.last_terms is not None else None
        result = []
        for v in range(eng.n_vehicles):
            info = {
                "time_s": float(eng.time_s[i]),
                "slot_error_m": float(out.slot_error_m[i, v]) if self.last_terms is not None else float(np.linalg.norm(err_vec[v])),
                "slot_error_ned_m": err_vec[v].copy(),
                "min_separation_m": float(_separation(eng.state[i])[v]),
                "induced_wind_ned_mps": eng.induced[i, v].copy(),
                "induced_omega_body_rad_s": eng.omega[i, v].copy(),
                "fuel_kg": float(eng.state[i, v, 13]),
                "gust_ned_mps": gust[v].copy(),
                "status": int(eng.status[i, v]),
                "collision": bool(out.collided[i]),
                "crashed": bool(out.crashed[i, v]),
                "command": eng.commands[i, v].copy(),
            }
            if self.benefit_enabled:
                info["induced_drag_saving"] = float(out.saving[i, v])
            if terms is not None:
                info["reward_terms"] = {k: float(t[v]) for k, t in terms.items()}
            result.append(info)
        return result


def _separation(x: np.ndarray) -> np.ndarray:
    """(V,) distance from each UAV to its nearest neighbour, m (inf alone)."""
    d = np.linalg.norm(x[:, None, 10:13] - x[None, :, 10:13], axis=-1)
    np.fill_diagonal(d, np.inf)
    with np.errstate(invalid="ignore"):
        return d.min(axis=1)
