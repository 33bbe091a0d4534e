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

from ..sim.validation import check_action, check_seed
from ..sim.validation import clipped_values as _clipped_values
from ..tasks import make_config
from ..sim.config import EnvConfig
from ..tasks.compose import task_simulation
from .observations import OBS_CLIP

__all__ = ["FormationParallelEnv", "make_config", "check_action", "reset_options", "IGNORED_RESET_OPTIONS"]

#: reset options accepted and ignored: exactly the key PettingZoo's own ``parallel_api_test`` and
#: ``api_test`` pass (``reset(seed=0, options={"options": 1})``, a placeholder testing that options are
#: accepted); Gymnasium's checker passes ``options={}``, which is fine as is.
IGNORED_RESET_OPTIONS: tuple[str, ...] = ("options",)


def reset_options(options) -> dict | None:
    """``options`` of a ``reset`` checked: None or a dict of :data:`formation_env.sim.simulation.RESET_OPTIONS`
    (an unknown key is a ``TypeError`` naming it and listing the valid ones); returns what goes to
    :meth:`Simulation.reset`, which checks the values."""
    from ..sim.simulation import RESET_OPTIONS

    if options is None:
        return None
    if not isinstance(options, dict):
        raise ValueError(f"reset options must be a dict or None, got {type(options).__name__}")
    unknown = sorted((str(k) for k in set(options) - set(RESET_OPTIONS) - set(IGNORED_RESET_OPTIONS)))
    if unknown:
        raise TypeError(f"unknown reset option(s) {unknown}; valid reset options: {list(RESET_OPTIONS)} (the "
                        "scenario, duration_s and every other EnvConfig option are set when the env is made)")
    return {k: v for k, v in options.items() if k in RESET_OPTIONS} or None


class FormationParallelEnv(ParallelEnv):
    metadata = {"name": "formation_env_v0", "render_modes": ["rgb_array", "human"], "render_fps": 10,
                "is_parallelizable": True}

    def __init__(self, config: EnvConfig | None = None, render_mode: str | None = None, **options) -> None:
        self.config = make_config(config, **options)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']} or None, got {render_mode!r}")
        self.render_mode = render_mode
        # the episode's state lives there, nowhere else (with the task's Python terms composed after the step)
        self.sim = task_simulation(self.config, batch_size=1)
        self.observation_layout = self.sim.observation_layout  # the groups of one observation (and the Dict's keys)
        self._out = None  # the last reset's or step's output
        n = self.sim.n_vehicles
        self.agent_indices = self.sim.agent_indices
        self.substeps = self.sim.substeps
        self.possible_agents = [f"uav_{i}" for i in self.agent_indices]
        self._index = {a: i for a, i in zip(self.possible_agents, self.agent_indices)}
        self._agent_set = frozenset(self.possible_agents)
        self.agents: list[str] = []
        if self.config.obs_mode == "dict":
            self._obs_space = spaces.Dict({k: spaces.Box(-OBS_CLIP, OBS_CLIP, (s,), dtype=np.float32)
                                           for k, s in self.sim.observation_layout.groups.items() if s})
        else:
            self._obs_space = spaces.Box(-OBS_CLIP, OBS_CLIP, (self.sim.obs_size,), dtype=np.float32)
        self._act_space = spaces.Box(-1.0, 1.0, (4,), dtype=np.float32)
        # centralised critics: ``state()`` is every UAV's observation vector, concatenated in index order
        self.state_space = spaces.Box(-OBS_CLIP, OBS_CLIP, (n * self.sim.obs_size,), dtype=np.float32)
        self._entropy = np.random.SeedSequence()
        self._renderer = None
        self._was_reset = False

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
        # ``options``: the simulation's reset options (formation_env.sim.simulation.RESET_OPTIONS); an
        # unknown one is a TypeError listing them (the env is configured at construction: scenario,
        # duration_s, ... are not reset options)
        sim_options = reset_options(options)
        if seed is None:
            seed = int(self._entropy.spawn(1)[0].generate_state(1)[0])
        else:
            seed = check_seed(seed)
            # Gymnasium's convention: a seed also seeds the stream later unseeded resets draw from, so a
            # trainer that seeds only the first reset (RLlib's env runners do) replays exactly.
            self._entropy = np.random.SeedSequence(int(seed))
        self._out = self.sim.reset(seeds=[int(seed)], options=sim_options)
        self._was_reset = True
        self.agents = list(self.possible_agents)
        return self._observations(), self._infos()

    def step(self, actions: dict):
        if not self._was_reset:
            raise RuntimeError("step() before any reset(): call reset() first")
        if not self.agents:
            raise RuntimeError("step() called on a finished episode; call reset() first")
        act = self._validate_actions(actions)
        out = self._out = self.sim.step(act[None])
        rewards_all, done, trunc = out.reward, bool(out.terminated[0]), bool(out.truncated[0])
        obs = self._observations()
        infos = self._infos()
        rewards_row = rewards_all[0].tolist()  # Python floats, as float() of each element
        rewards = {a: rewards_row[i] for a, i in self._index.items()}
        terminations = {a: done for a in self.agents}
        truncations = {a: trunc for a in self.agents}
        if done or trunc:
            self.agents = []
        if self.render_mode == "human":
            self.render()
        return obs, rewards, terminations, truncations, infos

    def state(self) -> np.ndarray:
        """Global state: every UAV's observation vector, concatenated (float32)."""
        obs = self._out.observation if self._out is not None else \
            getattr(self.sim, "observation", self.sim.output.observation)  # before any reset: the initial arrays
        return obs[0].reshape(-1).astype(np.float32)

    def render(self):
        if self.render_mode is None:
            return None
        from .render import FormationRenderer

        if self._renderer is None:
            self._renderer = FormationRenderer(self.sim, human=self.render_mode == "human")
        return self._renderer.draw()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # ---------------------------------------------------------------- helpers
    def _validate_actions(self, actions) -> np.ndarray:
        if not isinstance(actions, dict):
            raise ValueError(f"actions must be a dict agent -> array of shape (4,), got {type(actions).__name__}")
        if actions.keys() == self._agent_set:  # every agent acts (the common case): no name is unknown or missing
            rows = []
            for agent in self.possible_agents:
                vals = _clipped_values(actions[agent])
                rows.append(vals if vals is not None else check_action(agent, actions[agent]))
            return np.array(rows, dtype=float)
        unknown = sorted(set(actions) - set(self.possible_agents))
        if unknown:
            raise ValueError(f"unknown agent name(s) {unknown}; agents are {self.possible_agents}")
        missing = sorted(set(self.agents) - set(actions))
        if missing:
            raise ValueError(f"missing actions for agent(s) {missing}")
        act = np.zeros((len(self.possible_agents), 4))
        for k, agent in enumerate(self.possible_agents):
            if agent in actions:
                act[k] = check_action(agent, actions[agent])
        return act

    def _observations(self) -> dict:
        allobs = self._out.observation[0].astype(np.float32)
        split = self.observation_layout.split
        return {a: split(allobs[i]) if self.config.obs_mode == "dict" else allobs[i] for a, i in self._index.items()}

    def _infos(self) -> dict:
        per_vehicle = self.sim.infos(0)
        return {a: per_vehicle[i] for a, i in self._index.items()}
