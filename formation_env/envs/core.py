"""The batched environment core: B formations stepped together, arrays in and out.

A thin view of the compiled decision step (:func:`formation_env.sim.step.step`) for the env
adapters (PettingZoo parallel/AEC, Gymnasium, the SB3 VecEnv and the Gymnasium VectorEnv): it picks
the agents' rows, validates nothing twice and builds the info dicts. No physics here.
"""

from __future__ import annotations

import math

import numpy as np

from .config import EnvConfig
from .engine import AEROSONDE_SPAN_M, FormationEpisode
from .observations import observation_size
from ..sim.observe import REWARD_TERMS

__all__ = ["FormationCore", "AEROSONDE_SPAN_M", "INFO_REWARD_KEYS", "reward_info_key"]

_REWARD_TERM_NAMES = (*REWARD_TERMS, "total")


def reward_info_key(term: str) -> str:
    """The flat info key of a reward term: ``"slot"`` -> ``"reward_slot"`` (``"total"``: the reward itself)."""
    if term not in _REWARD_TERM_NAMES:
        raise ValueError(f"unknown reward term {term!r}; terms: {list(_REWARD_TERM_NAMES)}")
    return f"reward_{term}"


#: the flat info keys of the reward's terms, in REWARD_TERMS order, then ``reward_total``
INFO_REWARD_KEYS = tuple(reward_info_key(t) for t in _REWARD_TERM_NAMES)


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
        self._fresh = np.ones(self.engine.batch_size, dtype=bool)  # reset, not stepped since: reward infos are 0

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
        self._fresh[slice(None) if indices is None else np.asarray(indices, dtype=np.int64)] = True

    def step(self, agent_actions: np.ndarray):
        """agent_actions (B, A, 4) in [-1, 1] (validated by the caller).
        Returns (rewards (B, V), terminated (B,), truncated (B,))."""
        self._actions[:, self.mask] = agent_actions
        out = self.engine.decide(self._actions)
        self.last_terms = True
        self._fresh[:] = False
        return out.reward, out.terminated, out.truncated

    def observations(self) -> np.ndarray:
        """(B, V, D) float64 observation vectors of every vehicle (a view: copy to keep)."""
        return self.engine.out.observation

    def infos(self, i: int) -> list[dict]:
        """Per-vehicle info dicts of formation ``i`` (agents' metrics).

        Flat: every value is a Python scalar or a numpy array, and the keys are the same at reset and
        after every step (TorchRL builds its info specs from the reset infos). The reward's terms are
        ``reward_<term>`` (:data:`INFO_REWARD_KEYS`; 0.0 at reset)."""
        eng, out = self.engine, self.engine.out
        err_vec = eng.state[i, :, 10:13] - eng.position_demand[i]
        gust = eng.turbulence_gust_ned(i)
        terms = None if self._fresh[i] else eng.reward_terms(i)
        separation = _separation(eng.state[i], out.separation_m[i])
        # a formation whose state is finite has finite infos (they derive from it): check once
        clean = bool(np.isfinite(eng.state[i]).all())
        result = []
        for v in range(eng.n_vehicles):
            info = {
                "time_s": float(eng.time_s[i]),
                "slot_error_m": float(out.slot_error_m[i, v]) if self.last_terms is not None else float(np.linalg.norm(err_vec[v])),
                "slot_error_ned_m": err_vec[v].copy(),
                "min_separation_m": float(separation[v]),
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
            info["box_depth_m"] = float(out.box_depth_m[i, v])
            for key, name in zip(INFO_REWARD_KEYS, _REWARD_TERM_NAMES):
                info[key] = 0.0 if terms is None else float(terms[name][v])
            if not clean:
                _finite_values(info)
            result.append(info)
        return result


def _separation(x: np.ndarray, fallback: np.ndarray | None = None) -> np.ndarray:
    """(V,) distance from each UAV to its nearest neighbour, m (inf alone); never NaN.

    Pairs with a non-finite position (a UAV that diverged: its episode is ending) are left out;
    a UAV with no finite pair gets ``fallback`` (the decision step's separation at the last finite
    positions, ``StepOutput.separation_m``) where that is not NaN, else inf."""
    with np.errstate(invalid="ignore", over="ignore"):
        d = np.linalg.norm(x[:, None, 10:13] - x[None, :, 10:13], axis=-1)
    d[~np.isfinite(d)] = np.inf
    np.fill_diagonal(d, np.inf)
    sep = d.min(axis=1)
    if fallback is not None and x.shape[0] > 1:
        fb = np.asarray(fallback, dtype=float)
        sep = np.where(~np.isfinite(sep) & ~np.isnan(fb), fb, sep)
    return sep


def _finite_values(info: dict) -> None:
    """Infos never carry NaN or inf from a diverged UAV (its state is non-finite on the step that ends
    its episode): non-finite numbers become 0.0 and non-finite array entries 0.0, except
    ``min_separation_m``, which stays inf for a lone UAV (no neighbour)."""
    for key, value in info.items():
        if isinstance(value, float):
            if not math.isfinite(value) and not (key == "min_separation_m" and value == math.inf):
                info[key] = 0.0
        elif isinstance(value, np.ndarray) and value.dtype.kind == "f" and not np.all(np.isfinite(value)):
            info[key] = np.where(np.isfinite(value), value, 0.0)
