"""The PettingZoo ParallelEnv: UAVs flying a thesis scenario in each other's wake.

>>> import formation_env
>>> env = formation_env.parallel_env(scenario="formation_keeping", learning="followers")
>>> obs, infos = env.reset(seed=0)
>>> obs, rewards, terms, truncs, infos = env.step({a: env.action_space(a).sample() for a in env.agents})

Agents are named ``uav_<index>``. Each decision holds its action for ``physics_hz / control_hz``
physics steps (50 Hz physics, 10 Hz decisions by default). Vehicles that are not agents fly the
thesis PID baseline. The episode ends for every agent at once: terminated on a collision (CG
separation below ``collision_separation_b`` spans), an aircraft leaving its flight envelope or a
non-finite state; truncated at the scenario's duration.
"""

from __future__ import annotations

import functools

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from .config import EnvConfig
from .engine import ActionTarget, FormationEpisode
from .observations import GROUPS, OBS_CLIP, build_observations, group_sizes, observation_size, to_dict
from .rewards import min_separation_m, reward_terms, slot_error_m

__all__ = ["FormationParallelEnv", "make_config"]

AEROSONDE_SPAN_M = 2.9


def make_config(config: EnvConfig | None = None, **options) -> EnvConfig:
    """An EnvConfig from keyword options (unknown options raise ValueError naming them)."""
    if config is not None and not isinstance(config, EnvConfig):
        raise ValueError(f"config must be an EnvConfig, got {type(config).__name__}")
    if config is None:
        valid = set(EnvConfig.__dataclass_fields__)
        unknown = sorted(set(options) - valid)
        if unknown:
            raise ValueError(f"unknown option(s) {unknown}; valid options: {sorted(valid)}")
        return EnvConfig(**options)
    if options:
        raise ValueError("give either config or keyword options, not both")
    return config


class FormationParallelEnv(ParallelEnv):
    metadata = {"name": "formation_env_v0", "render_modes": ["rgb_array", "human"], "render_fps": 10,
                "is_parallelizable": True}

    def __init__(self, config: EnvConfig | None = None, render_mode: str | None = None, **options) -> None:
        self.config = make_config(config, **options)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']} or None, got {render_mode!r}")
        self.render_mode = render_mode
        self.engine = FormationEpisode(self.config, batch_size=1)
        eng = self.engine
        n = eng.n_vehicles
        learning = self.config.learning
        if learning == "all":
            idx = tuple(range(n))
        elif learning == "followers":
            if n < 2:
                raise ValueError(f"learning='followers' needs a formation; scenario {self.config.scenario!r} has one UAV")
            idx = tuple(range(1, n))
        else:
            bad = [i for i in learning if not 0 <= i < n]
            if bad:
                raise ValueError(f"learning indices {bad} out of range for {n} UAVs in {self.config.scenario!r}")
            idx = tuple(sorted(learning))
        self.agent_indices = idx
        self.possible_agents = [f"uav_{i}" for i in idx]
        self._index = {a: i for a, i in zip(self.possible_agents, idx)}
        self.agents: list[str] = []
        physics_hz = 1.0 / eng.dt
        ratio = physics_hz / self.config.control_hz
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(f"control_hz must divide the physics rate {physics_hz:g} Hz, got {self.config.control_hz!r}")
        self.substeps = int(round(ratio))
        self.max_decisions = int(np.ceil(eng.n_steps / self.substeps))
        self._mask = np.zeros(n, dtype=bool)
        self._mask[list(idx)] = True
        d = observation_size(n)
        box = spaces.Box(-OBS_CLIP, OBS_CLIP, (d,), dtype=np.float32)
        if self.config.obs_mode == "dict":
            self._obs_space = spaces.Dict({k: spaces.Box(-OBS_CLIP, OBS_CLIP, (s,), dtype=np.float32)
                                           for k, s in group_sizes(n).items() if s})
        else:
            self._obs_space = box
        self._act_space = spaces.Box(-1.0, 1.0, (4,), dtype=np.float32)
        self._previous_action = np.zeros((1, n, 4))
        self._previous_error = np.zeros((1, n))
        self._entropy = np.random.SeedSequence()
        self._decisions = 0
        self._renderer = None

    # ---------------------------------------------------------------- spaces
    @functools.lru_cache(maxsize=None)  # noqa: B019 - one space object per agent, as PettingZoo expects
    def observation_space(self, agent: str):
        self._check_agent(agent)
        return self._obs_space

    @functools.lru_cache(maxsize=None)  # noqa: B019
    def action_space(self, agent: str):
        self._check_agent(agent)
        return self._act_space

    def _check_agent(self, agent: str) -> None:
        if agent not in self._index:
            raise ValueError(f"unknown agent {agent!r}; agents are {self.possible_agents}")

    # ---------------------------------------------------------------- API
    def reset(self, seed: int | None = None, options: dict | None = None):
        # ``options`` is accepted for API compatibility (PettingZoo's own test passes some); the env is
        # configured at construction, so nothing in it is used.
        if options is not None and not isinstance(options, dict):
            raise ValueError(f"options must be a dict or None, got {type(options).__name__}")
        if seed is None:
            seed = int(self._entropy.spawn(1)[0].generate_state(1)[0])
        elif isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
            raise ValueError(f"seed must be an int or None, got {seed!r}")
        self.engine.reset(seeds=[int(seed)])
        self.agents = list(self.possible_agents)
        self._decisions = 0
        self._previous_action[:] = 0.0
        eng = self.engine
        self._previous_error = slot_error_m(eng.state, eng.position_demand)
        obs = self._observations()
        infos = self._infos(np.zeros((1, eng.n_vehicles), bool), np.zeros((1, eng.n_vehicles), bool))
        return obs, infos

    def step(self, actions: dict):
        if not self.agents:
            raise RuntimeError("step() called on a finished episode; call reset() first")
        act = self._validate_actions(actions)
        eng = self.engine
        target = ActionTarget(self.config.action_mode, act, self._mask)
        for _ in range(self.substeps):
            eng.physics_step(target)
            if np.any(eng.status != 0) or self._collided().any():
                break
        self._decisions += 1
        collided = self._collided()
        crashed = eng.status != 0
        error = slot_error_m(eng.state, eng.position_demand_now())
        saving = self._saving()
        terms = reward_terms(self.config.reward, error, self._previous_error, act, self._previous_action, saving,
                             np.broadcast_to(collided[:, None], error.shape), crashed)
        self._previous_error = error
        self._previous_action = act
        done = bool(collided.any() or crashed.any())
        truncated = (not done) and eng.step_count[0] >= eng.n_steps
        obs = self._observations()
        infos = self._infos(np.broadcast_to(collided[:, None], error.shape), crashed, terms, saving)
        rewards = {a: float(terms["total"][0, i]) for a, i in self._index.items() if a in self.agents}
        terminations = {a: done for a in self.agents}
        truncations = {a: bool(truncated) for a in self.agents}
        if done or truncated:
            self.agents = []
        if self.render_mode == "human":
            self.render()
        return obs, rewards, terminations, truncations, infos

    def state(self) -> np.ndarray:
        """Global state: every UAV's observation vector, concatenated (float32)."""
        return self._all_observations().reshape(-1).astype(np.float32)

    def render(self):
        if self.render_mode is None:
            return None
        from .render import FormationRenderer

        if self._renderer is None:
            self._renderer = FormationRenderer(self.engine, human=self.render_mode == "human")
        return self._renderer.draw()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # ---------------------------------------------------------------- helpers
    def _validate_actions(self, actions) -> np.ndarray:
        if not isinstance(actions, dict):
            raise ValueError(f"actions must be a dict agent -> array of shape (4,), got {type(actions).__name__}")
        unknown = sorted(set(actions) - set(self.possible_agents))
        if unknown:
            raise ValueError(f"unknown agent name(s) {unknown}; agents are {self.possible_agents}")
        missing = sorted(set(self.agents) - set(actions))
        if missing:
            raise ValueError(f"missing actions for agent(s) {missing}")
        act = np.zeros((1, self.engine.n_vehicles, 4))
        for agent in self.agents:
            a = np.asarray(actions[agent], dtype=float)
            if a.shape != (4,):
                raise ValueError(f"action of {agent!r} must have shape (4,), got {a.shape}")
            if not np.all(np.isfinite(a)):
                raise ValueError(f"action of {agent!r} contains NaN or inf: {a.tolist()}")
            act[0, self._index[agent]] = np.clip(a, -1.0, 1.0)  # the Box is [-1, 1]; out-of-range values saturate
        return act

    def _collided(self) -> np.ndarray:
        if self.engine.n_vehicles < 2:
            return np.zeros(1, dtype=bool)
        with np.errstate(invalid="ignore"):
            sep = min_separation_m(self.engine.state).min(axis=1)
        return sep < self.config.collision_separation_b * AEROSONDE_SPAN_M

    def _saving(self) -> np.ndarray:
        eng = self.engine
        if not (self.config.compute_benefit or self.config.reward.benefit > 0) or eng.sim.wake_model is None:
            return np.zeros((1, eng.n_vehicles))
        if np.any(eng.status != 0):
            return np.zeros((1, eng.n_vehicles))
        from ..sim.formation import ell_state_from_aircraft
        from ..wake import formation_benefit

        ell = ell_state_from_aircraft(eng.state, eng.ambient_wind(), eng.sim.wing_origin_body)
        return formation_benefit(eng.sim.wake_model, ell)["induced_drag_saving"]

    def _all_observations(self) -> np.ndarray:
        eng = self.engine
        sc = eng.scenario
        return build_observations(eng.state, eng.induced, eng.omega, eng.ambient_wind(), eng.turbulence_body(),
                                  eng.position_demand_now(), eng.velocity_demand, self._previous_action,
                                  sc.airspeed_mps, sc.altitude_m)[0]

    def _observations(self) -> dict:
        allobs = self._all_observations().astype(np.float32)
        n = self.engine.n_vehicles
        out = {}
        for a, i in self._index.items():
            out[a] = to_dict(allobs[i], n) if self.config.obs_mode == "dict" else allobs[i]
        return out

    def _infos(self, collided, crashed, terms=None, saving=None) -> dict:
        eng = self.engine
        err_vec = eng.state[0, :, 10:13] - eng.position_demand[0]
        with np.errstate(invalid="ignore"):
            sep = min_separation_m(eng.state)[0]
        infos = {}
        for a, i in self._index.items():
            info = {
                "time_s": float(eng.time_s[0]),
                "slot_error_m": float(np.linalg.norm(err_vec[i])),
                "slot_error_ned_m": err_vec[i].copy(),
                "min_separation_m": float(sep[i]),
                "induced_wind_ned_mps": eng.induced[0, i].copy(),
                "induced_omega_body_rad_s": eng.omega[0, i].copy(),
                "fuel_kg": float(eng.state[0, i, 13]),
                "status": int(eng.status[0, i]),
                "collision": bool(collided[0, i]),
                "crashed": bool(crashed[0, i]),
                "command": eng.commands[0, i].copy(),
            }
            if saving is not None and (self.config.compute_benefit or self.config.reward.benefit > 0):
                info["induced_drag_saving"] = float(saving[0, i])
            if terms is not None:
                info["reward_terms"] = {k: float(v[0, i]) for k, v in terms.items()}
            infos[a] = info
        return infos


GROUP_NAMES = GROUPS
