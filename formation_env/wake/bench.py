"""ELL benchmarks: one evaluation (pose, joint solve, effective wind) for two Aerosondes with 10
horseshoes each, and batches of such formations. Medians of repeated runs; no assertions."""

from __future__ import annotations

import time

import numpy as np

from ..constants import AEROSONDE_SPAN_M
from ..geometry import aerosonde
from .model import WakeModel
from .state import FormationState

__all__ = ["run_benchmarks", "aerosonde_pair_states"]

THESIS_SECONDS_PER_EVALUATION = 0.072  # section 5.4.4, MATLAB on a Xeon E5410, nseg = 10


def aerosonde_pair_states(batch: int, seed: int = 0) -> FormationState:
    """B leader/follower Aerosonde pairs near the thesis's formation-keeping slot, jittered."""
    rng = np.random.default_rng(seed)
    b = AEROSONDE_SPAN_M
    pos = np.zeros((batch, 2, 3))
    pos[:, 1] = np.array([-2 * b, b, 0.3 * b]) + rng.normal(0.0, 0.1 * b, (batch, 3))
    euler = np.zeros((batch, 2, 3))
    euler[..., 1] = np.radians(3.2) + rng.normal(0.0, 0.01, (batch, 2))
    euler[..., 0] = rng.normal(0.0, 0.02, (batch, 2))
    return FormationState(pos, euler, 25.0 + rng.normal(0.0, 0.5, (batch, 2)),
                          np.radians(3.2) + rng.normal(0.0, 0.01, (batch, 2)), rng.normal(0.0, 0.005, (batch, 2)))


def _median_time(fn, repeats: int, inner: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(inner):
            fn()
        times.append((time.perf_counter() - t0) / inner)
    return float(np.median(times))


def run_benchmarks(quick: bool = False) -> dict:
    """Return ELL timings (seconds and rates) for batch 1 and the batch sizes of interest."""
    model = WakeModel([aerosonde(nseg=10), aerosonde(nseg=10)])
    single = aerosonde_pair_states(1)
    model.evaluate(single)  # compile / load the cache outside the timing
    repeats = 5 if quick else 15
    t_single = _median_time(lambda: model.evaluate(single), repeats, 200 if quick else 1000)
    t_cold = _median_time(lambda: WakeModel([aerosonde(nseg=10), aerosonde(nseg=10)]).evaluate(single), 3, 20)
    out = {
        "case": "2 Aerosondes (wing only), 10 horseshoes each, Kurylowich core, control points",
        "single_evaluation_s": t_single,
        "single_evaluation_us": t_single * 1e6,
        "single_with_meshing_us": t_cold * 1e6,
        "thesis_s": THESIS_SECONDS_PER_EVALUATION,
        "speedup_vs_thesis": THESIS_SECONDS_PER_EVALUATION / t_single,
        "batched": {},
    }
    for batch in (64, 1024) if not quick else (1024,):
        states = aerosonde_pair_states(batch)
        model.evaluate(states)
        t = _median_time(lambda: model.evaluate(states), repeats, 3 if quick else 10)
        out["batched"][str(batch)] = {
            "seconds_per_call": t,
            "formation_evaluations_per_s": batch / t,
            "us_per_formation": t / batch * 1e6,
        }
    return out
