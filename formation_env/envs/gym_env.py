"""Single-agent Gymnasium environments: the learner flies one UAV, the others fly the PID baseline.

Registered ids (on ``import formation_env``): one per registered task (:mod:`formation_env.tasks`), its id
``Task.gym_id`` carrying the task's version (``formation_env/CloseFormation-v1``). ``gym.make(id)`` gives the
task's benchmark configuration (``Task.options``: the reward, action interface and training randomisation every
result on the task is trained with); the learner is the task's ``gym_learner`` (the first follower, uav_1, or the
single UAV of a one-UAV scenario), the other UAVs fly the thesis PID.

Keyword arguments of ``gymnasium.make`` replace options of the benchmark configuration
(:class:`~formation_env.sim.config.EnvConfig`, e.g. ``action_mode="residual"``, ``randomisation=Randomisation(...)``),
plus ``learner`` (the UAV
index; ``learning=(i,)`` means the same) and ``render_mode``. An unknown keyword raises ``TypeError``,
a bad value ``ValueError``. An id fixes its scenario: ``scenario=`` (or a ``config``) naming another one is a
``ValueError`` (use that scenario's id, or :func:`formation_env.parallel_env` for any scenario). Each id's ``spec.max_episode_steps`` is one full episode at 10 Hz.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from ..sim.config import EnvConfig
from ..tasks import make_config
from .parallel import FormationParallelEnv

from ..tasks import gym_ids, task_options

__all__ = ["FormationGymEnv", "GYM_IDS", "register_envs"]

GYM_IDS = gym_ids()  # id -> (scenario, learner), one per registered task (formation_env.tasks)


def _default_learner(n_vehicles: int) -> int:
    """The registered ids' learner: the first follower (uav_1), or the single UAV."""
    return 1 if n_vehicles > 1 else 0


def _episode_decisions(cfg: EnvConfig) -> int:
    """Decisions in one full episode of ``cfg`` (duration x control rate): the ids' ``max_episode_steps``."""
    from ..scenarios import Scenario, get_scenario

    sc = cfg.scenario if isinstance(cfg.scenario, Scenario) else get_scenario(cfg.scenario)
    duration = sc.duration_s if cfg.duration_s is None else cfg.duration_s
    physics_steps = int(round(duration / sc.dt))  # as the engine counts them
    substeps = max(1, int(round(1.0 / sc.dt / cfg.control_hz)))
    return -(-physics_steps // substeps)  # the step truncates once the physics steps reach the duration


def _check_id_scenario(registered: str | None, config, options: dict) -> None:
    """A registered id flies its own scenario: another one passed to ``gym.make`` is an error, not a switch."""
    if registered is None:
        return
    asked = options.get("scenario", registered) if config is None else getattr(config, "scenario", registered)
    name = getattr(asked, "name", asked)
    if name != registered:
        ids = {sc: i for i, (sc, _) in GYM_IDS.items()}
        hint = f"use {ids[name]!r}" if isinstance(name, str) and name in ids else "use its id"
        raise ValueError(f"this Gymnasium id flies scenario {registered!r}; got scenario={name!r}: {hint}, or "
                         f"formation_env.parallel_env({name!r}, ...) for any scenario")


class FormationGymEnv(gym.Env):
    """One learning UAV (``learner``, default: uav_1, or uav_0 in a one-UAV scenario); the others fly the
    PID baseline. ``learning=(i,)`` is accepted as a synonym of ``learner=i``; any ``learning`` that
    selects more than one UAV raises ``ValueError`` (use :func:`formation_env.parallel_env` or the vector
    envs for several learners)."""

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 10}

    def __init__(self, config: EnvConfig | None = None, learner: int | None = None, render_mode: str | None = None,
                 *, registered_scenario: str | None = None, **options):
        # ``registered_scenario``: set by the registered ids (register_envs), never by a user
        _check_id_scenario(registered_scenario, config, options)
        learning_given = "learning" in options or (config is not None and config.learning != "all")
        cfg = make_config(config, **options)
        if learner is not None and (isinstance(learner, bool) or not isinstance(learner, (int, np.integer))):
            raise ValueError(f"learner must be a UAV index (int), got {learner!r}")
        from ..scenarios import Scenario, get_scenario

        sc = cfg.scenario if isinstance(cfg.scenario, Scenario) else get_scenario(cfg.scenario)
        n = sc.n_vehicles
        if learning_given:
            chosen = {"all": tuple(range(n)), "followers": tuple(range(1, n))}.get(cfg.learning, cfg.learning)
            if len(chosen) != 1:
                raise ValueError(
                    f"learning={cfg.learning!r} selects {len(chosen)} UAVs of {n}, but a single-agent Gymnasium env has "
                    "one learner: pass learner=i or learning=(i,), or use formation_env.parallel_env(...) / "
                    "FormationVecEnv / FormationVectorEnv for several learners")
            if learner is not None and int(learner) != chosen[0]:
                raise ValueError(f"learner={learner!r} and learning={cfg.learning!r} disagree; give one of them")
            learner = chosen[0]
        elif learner is None:
            learner = _default_learner(n)
        if not 0 <= int(learner) < n:
            raise ValueError(f"learner {learner!r} out of range for {n} UAV(s) in {cfg.scenario!r}")
        cfg = EnvConfig(**{**cfg.__dict__, "learning": (int(learner),)})
        self._par = FormationParallelEnv(cfg, render_mode=render_mode)
        self.config = cfg
        self.learner = int(learner)
        self.agent = self._par.possible_agents[0]
        self.observation_space = self._par.observation_space(self.agent)
        self.action_space = self._par.action_space(self.agent)
        self.render_mode = render_mode
        self.episode_decisions = _episode_decisions(cfg)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        from ..sim.validation import check_seed

        super().reset(seed=check_seed(seed))  # a bad seed: the engine's ValueError, not Gymnasium's own error
        if seed is None:
            seed = int(self.np_random.integers(2**63 - 1))
        obs, infos = self._par.reset(seed=seed, options=options)
        return obs[self.agent], infos[self.agent]

    def step(self, action):
        obs, rewards, terms, truncs, infos = self._par.step({self.agent: action})
        return obs[self.agent], rewards[self.agent], terms[self.agent], truncs[self.agent], infos[self.agent]

    def render(self):
        return self._par.render()

    def close(self):
        self._par.close()


def register_envs() -> None:
    """Registers :data:`GYM_IDS` (every registered task's id: call it again after registering a task of your own), each with ``max_episode_steps`` = the scenario's duration x 10 Hz (one
    episode at the default control rate; the env truncates there itself too). With a longer
    ``duration_s`` or a higher ``control_hz``, pass ``gym.make(id, max_episode_steps=N)`` (or ``-1``) so
    Gymnasium's TimeLimit does not cut the episode short."""
    GYM_IDS.update(gym_ids())  # the tasks registered since import too (a task of the user's own)
    for env_id, (scenario, learner) in GYM_IDS.items():
        if env_id not in gym.registry:
            gym.register(env_id, entry_point="formation_env.envs.gym_env:FormationGymEnv",
                         max_episode_steps=_episode_decisions(EnvConfig(scenario=scenario, **task_options(scenario))),
                         kwargs={"scenario": scenario, "registered_scenario": scenario})
