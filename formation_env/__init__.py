"""formation-env: close-formation UAV flight simulation for reinforcement learning.

Layers (imports point down only): ``geometry`` -> ``wake`` (ELL) -> ``aircraft`` (Aerosonde
6-DOF) -> ``sim`` (the public :class:`~formation_env.sim.Simulation`) -> ``tasks`` -> ``rollout`` -> ``envs``
(docs/architecture.md). ``import formation_env`` registers the Gymnasium ids
(``formation_env/FormationKeeping-v1`` ...); ``formation_env.parallel_env(...)`` and
``formation_env.env(...)`` give the PettingZoo environments. See README.md.
"""

__version__ = "0.2.0"

from .kernel_cache import check_kernel_cache as _check_kernel_cache  # noqa: E402

# before any compiled kernel loads: a numba cache compiled from other sources of this package is deleted
# (numba keys each cached function on its own file only; formation_env.kernel_cache)
_check_kernel_cache()

from . import tasks as _tasks  # noqa: E402,F401  registers every task and its scenario (formation_env.tasks)


def parallel_env(scenario: str = "formation_keeping", render_mode=None, **options):
    """PettingZoo ParallelEnv (see :func:`formation_env.envs.parallel_env`)."""
    from .envs import parallel_env as _parallel_env

    return _parallel_env(scenario, render_mode=render_mode, **options)


def env(scenario: str = "formation_keeping", render_mode=None, **options):
    """PettingZoo AEC env (see :func:`formation_env.envs.env`)."""
    from .envs import env as _env

    return _env(scenario, render_mode=render_mode, **options)


def _register() -> None:
    try:
        import gymnasium  # noqa: F401
    except ModuleNotFoundError:  # the physics layers work without the RL stack
        return
    from .envs.gym_env import register_envs

    register_envs()


_register()
