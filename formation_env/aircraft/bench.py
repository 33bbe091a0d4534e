"""Speed of the Aerosonde RK4 step: steps per second for 1 aircraft and for a batch of 1,024."""

from __future__ import annotations

import time

import numpy as np

from .eom import step
from .trim import trim


def _steps_per_s(batch: int, n_steps: int, repeats: int) -> dict:
    t = trim()
    state = np.repeat(t.state, batch, axis=0)
    controls = np.repeat(t.controls, batch, axis=0)
    step(state, controls)  # warm-up
    rates = []
    for _ in range(repeats):
        s = state
        t0 = time.perf_counter()
        for _ in range(n_steps):
            s = step(s, controls)
        rates.append(n_steps / (time.perf_counter() - t0))
    med = float(np.median(rates))
    return {"batch": batch, "steps_per_s": med, "aircraft_steps_per_s": med * batch,
            "us_per_step": 1e6 / med, "repeats": repeats, "steps_per_repeat": n_steps}


def run_benchmarks(quick: bool = False) -> dict:
    """RK4 steps/s (dt = 0.02 s, trimmed flight, still air), median of repeats."""
    repeats = 3 if quick else 7
    return {
        "integrator": "RK4, dt = 0.02 s, compiled (numba) kernel, one loop over the batch axis",
        "batch_1": _steps_per_s(1, 100 if quick else 500, repeats),
        "batch_1024": _steps_per_s(1024, 10 if quick else 50, repeats),
    }
