"""Vector environments over the batched core: B formations stepped in one call.

* :class:`FormationVecEnv`: a Stable-Baselines3 ``VecEnv`` for shared-parameter learning. Every
  learning UAV of every formation is one SB3 env index (``num_envs = B x agents per formation``),
  index ``f * A + k`` being agent ``k`` of formation ``f``.
* :class:`FormationVectorEnv`: the same as a Gymnasium ``VectorEnv`` (same-step autoreset).

Only finished formations are reset (auto-reset); a formation's episode ends for all its agents at
once. SB3 conventions: ``infos[i]["terminal_observation"]`` carries the last observation of a
finished episode, ``infos[i]["TimeLimit.truncated"]`` whether it ended by the time limit, and
``infos[i]["episode"] = {"r", "l", "t"}`` its return and length (so no Monitor wrapper is needed).

Seeding: ``seed(s)`` (SB3) / ``reset(seed=s)`` (Gymnasium) give formation ``f`` the seed
``s + f * A`` for its next episode, exactly as a single env reset with that seed; later episodes
draw their seeds from a generator seeded by ``s``. Formations of a batch evolve exactly as the
same formations in single envs with those seeds (bit for bit; tested).
"""

from __future__ import annotations

import time

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

from ..sim.validation import MAX_SEED, check_actions, check_count, check_seed
from ..sim.config import EnvConfig
from .observations import OBS_CLIP
from ..tasks import make_config
from ..tasks.compose import task_simulation

__all__ = ["FormationVecEnv", "FormationVectorEnv", "BatchedFormations", "OneObjectVecEnvMethods"]

_RENDER_MODES = ("rgb_array",)

#: most formations one vector env may hold (more is a ValueError, not numpy's MemoryError): each holds its
#: UAVs' state, wake and turbulence arrays, 12 kB (formation_keeping) to 30 kB (a turbulent vee) measured,
#: so 65,536 of them is ~1-2 GB before the learner's own buffers
MAX_FORMATIONS = 65_536


def _check_n_formations(n_formations) -> int:
    return check_count(n_formations, "n_formations", 1, MAX_FORMATIONS)


def _check_render_mode(render_mode) -> str | None:
    if render_mode is not None and render_mode not in _RENDER_MODES:
        raise ValueError(f"render_mode must be one of {list(_RENDER_MODES)} or None, got {render_mode!r}")
    return render_mode


def _formation_frames(owner, batch: "BatchedFormations") -> list[np.ndarray]:
    """One RGB frame (H, W, 3) uint8 per env index: formation f's frame for each of its agents (the
    same array object), drawn by one renderer kept on ``owner``."""
    renderer = getattr(owner, "_renderer", None)
    if renderer is None:
        from .render import FormationRenderer

        renderer = owner._renderer = FormationRenderer(batch.sim)
    frames = [renderer.draw(f) for f in range(batch.n_formations)]
    return [frames[i // batch.agents_per_formation] for i in range(batch.num_envs)]


def _close_renderer(owner) -> None:
    renderer = getattr(owner, "_renderer", None)
    if renderer is not None:
        renderer.close()
        owner._renderer = None


class BatchedFormations:
    """Shared logic of the vector envs: flat (num_envs, ...) arrays over a :class:`~formation_env.sim.Simulation`."""

    def __init__(self, n_formations: int, config: EnvConfig, seed: int | None = None) -> None:
        n_formations = _check_n_formations(n_formations)
        if config.obs_mode != "flat":
            raise ValueError("vector envs use flat observations (obs_mode='flat')")
        self.sim = task_simulation(config, batch_size=n_formations)  # the task's Python terms composed after the step
        self._out = None  # the last output
        self.n_formations = self.sim.batch_size
        self.agents = list(self.sim.agent_indices)
        self.agents_per_formation = len(self.agents)
        self.num_envs = self.n_formations * self.agents_per_formation
        self.obs_size = self.sim.obs_size
        self._seed_stream = np.random.SeedSequence(check_seed(seed))
        self._pending_seeds: list[int | None] = [None] * self.n_formations
        self.t_start = time.perf_counter()
        self.was_reset = False

    def set_seed(self, seed: int | None) -> None:
        if seed is None:
            self._seed_stream = np.random.SeedSequence()
            self._pending_seeds = [None] * self.n_formations
            return
        a = self.agents_per_formation
        # formation f's first episode gets seed + f * a, which must stay a seed too
        seed = check_seed(seed, top=MAX_SEED - (self.n_formations - 1) * a)
        self._seed_stream = np.random.SeedSequence(int(seed))
        self._pending_seeds = [int(seed) + f * a for f in range(self.n_formations)]

    def _seeds_for(self, formations) -> list[int]:
        out = []
        for f in formations:
            s = self._pending_seeds[f]
            if s is None:
                s = int(self._seed_stream.spawn(1)[0].generate_state(1)[0])
            self._pending_seeds[f] = None
            out.append(s)
        return out

    def reset(self, formations=None) -> None:
        idx = np.arange(self.n_formations) if formations is None else np.asarray(formations, dtype=np.int64)
        self._out = self.sim.reset(idx, self._seeds_for(idx))
        self.was_reset = True

    def observations(self) -> np.ndarray:
        obs = self._out.observation[:, self.agents]
        return obs.reshape(self.num_envs, -1).astype(np.float32)

    def validate(self, actions) -> np.ndarray:
        """(num_envs, 4) real, finite actions clipped to [-1, 1] (:func:`formation_env.sim.validation.check_actions`)."""
        return check_actions(actions, (self.num_envs, 4), rows="env index")

    def step(self, actions: np.ndarray):
        """Returns obs (after auto-reset), rewards, terminated, truncated (num_envs,) and, for the
        finished formations, their final observations (num_envs, D) and finished mask."""
        if not self.was_reset:
            raise RuntimeError("step() before any reset(): call reset() first")
        a = self.validate(actions).reshape(self.n_formations, self.agents_per_formation, 4)
        out = self._out = self.sim.step(a)
        rewards, term_f, trunc_f = out.reward[:, self.agents].reshape(-1), out.terminated.copy(), out.truncated.copy()
        rep = self.agents_per_formation
        terminated, truncated = np.repeat(term_f, rep), np.repeat(trunc_f, rep)
        done_f = term_f | trunc_f
        final_obs = None
        if done_f.any():
            final_obs = self.observations()
            st = self.sim.state  # episode sums kept by the compiled step
            self.final_episode = (st.episode_return[:, self.agents].reshape(-1).copy(),
                                  np.repeat(st.episode_decisions, rep))
            self.reset(np.nonzero(done_f)[0])
        return self.observations(), rewards.astype(np.float32), terminated, truncated, final_obs, np.repeat(done_f, rep)


class OneObjectVecEnvMethods:
    """SB3 ``VecEnv`` attribute access for a vector env that is one object (every env index shares it):
    ``get_attr`` / ``set_attr`` / ``env_method`` act on that object, once per requested index."""

    def get_attr(self, attr_name, indices=None):
        return [getattr(self, attr_name) for _ in self._get_indices(indices)]

    def set_attr(self, attr_name, value, indices=None) -> None:
        setattr(self, attr_name, value)

    def env_method(self, method_name, *method_args, indices=None, **method_kwargs):
        return [getattr(self, method_name)(*method_args, **method_kwargs) for _ in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class, indices=None):
        return [False for _ in self._get_indices(indices)]


class FormationVecEnv(OneObjectVecEnvMethods, VecEnv):
    """SB3 VecEnv of ``n_formations`` formations (see the module docstring).

    >>> from stable_baselines3 import PPO
    >>> venv = FormationVecEnv(64, scenario="formation_keeping", learning="followers", action_mode="residual")
    >>> PPO("MlpPolicy", venv).learn(10_000)
    """

    def __init__(self, n_formations: int, config: EnvConfig | None = None, seed: int | None = None,
                 detailed_infos: bool = False, render_mode: str | None = None, **options) -> None:
        cfg = make_config(config, **options)
        self.batch = BatchedFormations(n_formations, cfg, seed)
        self.config = cfg
        self.observation_layout = self.batch.sim.observation_layout  # the groups of one observation
        self.detailed_infos = bool(detailed_infos)
        obs_space = spaces.Box(-OBS_CLIP, OBS_CLIP, (self.batch.obs_size,), dtype=np.float32)
        act_space = spaces.Box(-1.0, 1.0, (4,), dtype=np.float32)
        self.render_mode = _check_render_mode(render_mode)
        self._renderer = None
        super().__init__(self.batch.num_envs, obs_space, act_space)
        self.metadata["render_fps"] = cfg.control_hz
        self._actions = None
        if seed is not None:
            self.batch.set_seed(seed)

    def seed(self, seed: int | None = None):
        self.batch.set_seed(seed)
        a = self.batch.agents_per_formation
        return [None if seed is None else int(seed) + (i // a) * a for i in range(self.num_envs)]

    def reset(self):
        if any(s is not None for s in self._seeds):  # SB3's seed() stores per-index seeds
            self.batch.set_seed(self._seeds[0])
        self.batch.reset()
        self._reset_seeds()
        self._reset_options()
        self.reset_infos = [{} for _ in range(self.num_envs)]
        return self.batch.observations()

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self):
        if self._actions is None:
            raise RuntimeError("step_wait() called without step_async()")
        obs, rewards, terminated, truncated, final_obs, done = self.batch.step(self._actions)
        self._actions = None
        infos: list[dict] = [{} for _ in range(self.num_envs)]
        if self.detailed_infos:
            sim = self.batch.sim
            for f in range(self.batch.n_formations):
                per_vehicle = sim.infos(f)
                for k, v in enumerate(sim.agent_indices):
                    infos[f * self.batch.agents_per_formation + k] = per_vehicle[v]
        if final_obs is not None:
            ret, length = self.batch.final_episode
            elapsed = time.perf_counter() - self.batch.t_start
            for i in np.nonzero(done)[0]:
                infos[i]["terminal_observation"] = final_obs[i]
                infos[i]["TimeLimit.truncated"] = bool(truncated[i])
                infos[i]["episode"] = {"r": float(ret[i]), "l": int(length[i]), "t": round(elapsed, 6)}
        return obs, rewards, terminated | truncated, infos

    def close(self) -> None:
        _close_renderer(self)

    def get_images(self) -> list[np.ndarray]:
        """One RGB frame (H, W, 3) uint8 per env index; the agents of a formation share its frame."""
        return _formation_frames(self, self.batch)

    def render(self, mode: str | None = None) -> np.ndarray | None:
        """SB3's render: with ``render_mode="rgb_array"`` the frames of all env indices tiled into one
        image (what ``VecVideoRecorder`` records); None (with a warning) without a render mode."""
        return super().render(mode=mode)



class FormationVectorEnv(gym.vector.VectorEnv):
    """Gymnasium VectorEnv of ``n_formations`` formations with same-step autoreset: a finished
    sub-env's last observation and info are in ``infos["final_obs"]`` / ``infos["final_info"]``."""

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": list(_RENDER_MODES), "render_fps": 10}

    def __init__(self, n_formations: int, config: EnvConfig | None = None, seed: int | None = None,
                 render_mode: str | None = None, **options) -> None:
        self.render_mode = _check_render_mode(render_mode)
        self._renderer = None
        cfg = make_config(config, **options)
        self.batch = BatchedFormations(n_formations, cfg, seed)
        self.config = cfg
        self.observation_layout = self.batch.sim.observation_layout  # the groups of one observation
        self.num_envs = self.batch.num_envs
        self.single_observation_space = spaces.Box(-OBS_CLIP, OBS_CLIP, (self.batch.obs_size,), dtype=np.float32)
        self.single_action_space = spaces.Box(-1.0, 1.0, (4,), dtype=np.float32)
        self.observation_space = gym.vector.utils.batch_space(self.single_observation_space, self.num_envs)
        self.action_space = gym.vector.utils.batch_space(self.single_action_space, self.num_envs)

    def reset(self, *, seed=None, options=None):
        if seed is not None:
            if isinstance(seed, (list, tuple)):
                raise ValueError("pass one int seed: formation f gets seed + f * agents_per_formation")
            self.batch.set_seed(seed)
        self.batch.reset()
        return self.batch.observations(), {}

    def step(self, actions):
        obs, rewards, terminated, truncated, final_obs, done = self.batch.step(actions)
        infos: dict = {}
        if final_obs is not None:
            fo = np.full(self.num_envs, None, dtype=object)
            fi = np.full(self.num_envs, None, dtype=object)
            ret, length = self.batch.final_episode
            for i in np.nonzero(done)[0]:
                fo[i] = final_obs[i]
                fi[i] = {"episode_return": float(ret[i]), "episode_length": int(length[i])}
            infos = {"final_obs": fo, "_final_obs": done.copy(), "final_info": fi, "_final_info": done.copy()}
        return obs, rewards, terminated, truncated, infos

    def render(self) -> tuple[np.ndarray, ...] | None:
        """A tuple of RGB frames (H, W, 3) uint8, one per sub-env (the agents of a formation share its
        frame), as ``gymnasium.vector`` envs return; None without ``render_mode="rgb_array"``."""
        if self.render_mode is None:
            return None
        return tuple(_formation_frames(self, self.batch))

    def close_extras(self, **kwargs) -> None:
        _close_renderer(self)
