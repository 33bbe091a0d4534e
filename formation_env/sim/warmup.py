"""Compile the kernels ahead of time, with progress, instead of silently on the first step.

The kernels are numba functions cached on disk (``cache=True``: ``__pycache__`` beside each source file). A fresh
clone has no cache, so its first simulation step compiles them: about 90 s on 2 idle cores (two processes compile
at once), longer when other processes share the cores. ``make install`` runs :func:`warm_up`
(``formation-env warmup``), so the first run after it is warm; and when a :class:`~formation_env.sim.Simulation` is
built while the cache is cold (a stamp beside this module, written after a complete warm-up of the current sources,
is missing or older than a source file), :func:`ensure_warm` says so on stderr and compiles stage by stage, naming
each stage and how far it is.

``FORMATION_ENV_NO_WARMUP=1`` turns the automatic warm-up off (the kernels then compile on first use, silently).

The decision step compiles by flying simulations: the Simulation class comes as an argument (from the Simulation
being built, or from the command), so that this module, which the simulation imports, does not import it.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

__all__ = ["warm_up", "ensure_warm", "is_warm", "STAGES"]

_PACKAGE = Path(__file__).resolve().parents[1]
_STAMP = Path(__file__).resolve().parent / "__pycache__" / "formation_env_warm.stamp"
_BUSY = False  # a warm-up is running (its own Simulation must not start another)
_WARM = False  # this process has seen a warm cache (no more stat calls)


def _newest_source_mtime() -> float:
    return max(p.stat().st_mtime for p in _PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)


def is_warm() -> bool:
    """True when a complete warm-up ran after the newest change of any source file (an edit makes the cache
    cold again: numba recompiles the edited file's functions, and :mod:`formation_env.kernel_cache` deletes
    the cached callers in other files)."""
    try:
        return _STAMP.stat().st_mtime >= _newest_source_mtime()
    except OSError:
        return False


def _aircraft(simulation) -> None:
    from ..aircraft import trim

    trim(25.0, 1000.0)


def _wake(simulation) -> None:
    from ..geometry import aerosonde
    from ..wake import FormationState, WakeModel, formation_benefit

    b = 2.9
    model = WakeModel([aerosonde(), aerosonde()])
    st = FormationState.from_degrees([[0, 0, 0], [-2 * b, b, 0.3 * b]], [[0, 3, 0]] * 2, 25.0, 3.0)
    model.evaluate(st)
    formation_benefit(model, st)


def _decision(simulation) -> None:
    import numpy as np

    from .config import EnvConfig, Randomisation

    from .step import ENTRY_POINTS, decide_packed

    # one configuration exercises every branch type of the step (turbulence, benefit, set-points, a formation);
    # every task flies the same compiled step (the wake's sheet law and residual table are values, not types)
    cfg = EnvConfig(scenario="formation_keeping", action_mode="setpoints", compute_benefit=True, duration_s=0.2,
                    randomisation=Randomisation(turbulence_sigma_mps=1.0))
    sim = simulation(cfg, batch_size=2)
    # the decision kernel first, for no formation (no reset needed): the reset's kernel meanwhile compiles in the
    # second process (SECOND_PROCESS_STAGES: the energy stage's reset comes first there)
    ENTRY_POINTS.get(decide_packed, sim.params, sim.state, sim.output, (np.zeros((2, sim.n_vehicles, 4)),), 1)
    sim.reset(seeds=[0, 1])
    sim.step(np.zeros((2, sim.n_agents, 4)))
    solo = simulation(EnvConfig(scenario="tracking", duration_s=0.2), batch_size=1)
    solo.reset(seeds=[0])
    solo.step(np.zeros((1, solo.n_agents, 4)))


def _energy(simulation) -> None:
    from .config import EnvConfig

    # the energy account of the energy tasks' infos (computed when read); read after a reset, not a decision, so
    # that a second process compiling it does not compile the decision step beside the first
    energy = simulation(EnvConfig(scenario="close_formation", compute_benefit=True, duration_s=0.2), batch_size=1)
    energy.reset(seeds=[0])
    energy.info.energy_account  # noqa: B018


def _control(simulation) -> None:
    import numpy as np

    from ..aircraft import trim
    from ..control import PIDFlightControl
    from ..control.observation import fcs_observation

    tr = trim(25.0, 1000.0)
    fcs = PIDFlightControl.from_trim(tr)
    obs = fcs_observation(tr.state, np.zeros(3), np.zeros(3))
    obs["position_demand_ned"] = obs["position_ned"]
    obs["velocity_demand_ned"] = obs["velocity_ned"]
    fcs.act(obs, fcs.initial_state(1))


#: (what compiles, function of the Simulation class): in the order the first run needs them
STAGES = (("Aerosonde aerodynamics, propulsion and trim", _aircraft),
          ("ELL wake solve and loads", _wake),
          ("the batched decision step (guidance, PID, wake, RK4, turbulence, reward, observation)", _decision),
          ("the thesis PID as a stand-alone policy", _control),
          ("the energy account", _energy))
#: the stages a second process compiles while this one compiles the decision step: that step is about half of the
#: compile time, the wake's stand-alone kernels, the PID, the energy account and the reset's kernel the rest. The
#: energy stage comes first there: its reset compiles the reset's kernel, which the decision stage here reaches
#: after the decision kernel and then loads from the cache
SECOND_PROCESS_STAGES = (4, 1, 3)


class _Heartbeat:
    """Prints the elapsed time of a long stage every ``every_s`` seconds (numba compiles one function at a time
    and says nothing meanwhile)."""

    def __init__(self, stream, k: int, n: int, every_s: float = 15.0) -> None:
        self.stream, self.k, self.n, self.every_s = stream, k, n, every_s
        self._stop = threading.Event()
        self._thread = None

    def __enter__(self):
        if self.stream is not None:
            self._t0 = time.perf_counter()
            self._thread = threading.Thread(target=self._beat, daemon=True)
            self._thread.start()
        return self

    def _beat(self) -> None:
        while not self._stop.wait(self.every_s):
            print(f"  [{self.k}/{self.n}] still compiling, {time.perf_counter() - self._t0:.0f} s "
                  "(the decision step is the longest stage)", file=self.stream, flush=True)

    def __exit__(self, *exc) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()


def _second_process() -> tuple[subprocess.Popen, object]:
    """Start compiling :data:`SECOND_PROCESS_STAGES` in a new interpreter importing this same package (its own
    automatic warm-up off); numba writes what it compiles to the shared cache. Returns the process and the
    temporary file its messages go to (not a pipe: nothing reads them until this process reaches that stage)."""
    env = dict(os.environ, FORMATION_ENV_NO_WARMUP="1",
               PYTHONPATH=os.pathsep.join(p for p in (str(_PACKAGE.parent), os.environ.get("PYTHONPATH")) if p))
    code = ("from formation_env.sim import Simulation; from formation_env.sim.warmup import STAGES, "
            "SECOND_PROCESS_STAGES\nfor k in SECOND_PROCESS_STAGES: STAGES[k][1](Simulation)")
    log = tempfile.TemporaryFile()
    return subprocess.Popen([sys.executable, "-c", code], env=env, stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=log), log


def warm_up(simulation, stream=sys.stderr, processes: int | None = None) -> float:
    """Compile (or load from the cache) every kernel, reporting each stage on ``stream`` (None: silent); writes
    the stamp :func:`is_warm` reads. ``simulation``: the :class:`~formation_env.sim.Simulation` class the decision
    step's stages fly. ``processes``: 2 compiles :data:`SECOND_PROCESS_STAGES` in a second process at the same
    time as the other stages (then, after the others, waits for it and loads them from the cache here, which also
    compiles whatever that process did not finish); 1 compiles everything here, one stage after the other; None: 2
    when the machine has two cores or more. Returns the seconds it took."""
    global _BUSY
    if processes is None:
        processes = 2 if (os.cpu_count() or 1) >= 2 else 1
    if processes not in (1, 2):
        raise ValueError(f"warm_up: processes must be 1 or 2, got {processes!r}")
    t0 = time.perf_counter()
    _BUSY = True
    second, second_log = _second_process() if processes == 2 else (None, None)
    try:
        # this process's stages first, then the second process's (loaded from the cache it wrote)
        order = [k for k in range(len(STAGES)) if second is None or k not in SECOND_PROCESS_STAGES]
        order += [k for k in range(len(STAGES)) if k not in order]
        for n, k in enumerate(order, 1):
            what, fn = STAGES[k]
            t = time.perf_counter()
            in_second = second is not None and k in SECOND_PROCESS_STAGES
            if stream is not None:
                where = " (in a second process since the start)" if in_second else ""
                print(f"  [{n}/{len(STAGES)}] compiling {what}{where} ...", file=stream, flush=True)
            with _Heartbeat(stream, n, len(STAGES)):
                if in_second and second.returncode is None:
                    second.wait()
                    second_log.seek(0)
                    err = second_log.read()
                    second_log.close()
                    if second.returncode != 0 and stream is not None:  # compiled here instead, below
                        print(f"  [{n}/{len(STAGES)}] the second process failed (compiling here instead): "
                              f"{err.decode(errors='replace').strip().splitlines()[-1:]}", file=stream, flush=True)
                fn(simulation)
            if stream is not None:
                print(f"  [{n}/{len(STAGES)}] done in {time.perf_counter() - t:.1f} s", file=stream, flush=True)
        second = None
    finally:
        _BUSY = False
        if second is not None:  # a stage before it failed: nothing waits for the second process any more
            second.kill()
            second.wait()
            second_log.close()
    try:
        _STAMP.parent.mkdir(parents=True, exist_ok=True)
        _STAMP.write_text(f"warm-up {time.strftime('%Y-%m-%d %H:%M:%S')}\n")
    except OSError:  # a read-only install: numba falls back to its own cache directory; nothing to stamp
        pass
    return time.perf_counter() - t0


def ensure_warm(simulation, stream=sys.stderr) -> None:
    """Warm up (:func:`warm_up` with the Simulation class ``simulation``; progress on ``stream``) when the cache
    is cold; a no-op when warm, during a warm-up, or with ``FORMATION_ENV_NO_WARMUP=1``."""
    global _WARM
    if _WARM or _BUSY or os.environ.get("FORMATION_ENV_NO_WARMUP") == "1":
        return
    if is_warm():
        _WARM = True
        return
    if stream is not None:
        print("formation-env: compiling the simulation kernels (first run after an install or a source change; "
              "cached afterwards; `formation-env warmup` does it ahead of time):", file=stream, flush=True)
    total = warm_up(simulation, stream)
    _WARM = True
    if stream is not None:
        print(f"formation-env: kernels ready in {total:.0f} s", file=stream, flush=True)
