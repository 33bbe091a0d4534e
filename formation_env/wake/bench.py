"""ELL benchmarks: one evaluation (pose, joint solve, effective wind) for two Aerosondes with 10
horseshoes each, and batches of such formations through the per-formation kernel and the batch-lane kernel, with
one thread and with all. Medians of repeated runs; no assertions."""

from __future__ import annotations

import time

import numpy as np

from ..constants import AEROSONDE_SPAN_M
from ..geometry import aerosonde
from .model import WakeModel
from .state import FormationState

__all__ = ["run_benchmarks", "aerosonde_pair_states", "ell_flops", "peak_gflops_per_core", "FLOPS"]

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


# Floating-point operations of the kernels' primitives (issue 26: "report achieved GFLOP/s of the ELL with the
# flop count it assumes"). Counted from the source of formation_env.wake.biot_savart / aic / field, every +, -,
# *, /, sqrt and exp as one flop (the N-body convention), comparisons and min/max as none, each branch law on
# its usual path (the overlap core's factor exactly 1: beyond ~3 r_o of the source; a cored leg's exponential
# skipped beyond 40: the path of every point more than a few core radii away):
FLOPS = {
    "knot": 20,          # point_to_knots, per knot: P - X1 and P - X3 (3 each), |.|^2 (5 each), sqrt, 1/|.|
    "branch": 33,        # branch: d x a (9), h^2 (5), cos_gamma and cos_delta (6 each), 1/(4 pi h^2) law (4), f d x a (3)
    "branch_cored": 39,  # branch_cored: d x a (9), h^2 (5), d.a and d.b (5 each), distance to the segment (4),
    #                      overlap test (3), law (5), f d x a (3)
    "leg": 30,           # leg with a viscous core: d x a (9), h^2 (5), cos_gamma (6), core argument (3), law (4), f (3)
    "leg_cored": 38,     # leg_cored: leg plus |a|^2 (5) and the overlap test (3)
    "core_radius": 13,   # core_radius: P - origin, |.|, age, C sqrt(nu tau)
    "dot": 5,            # a branch's velocity . the panel normal
    "to_ned": 18,        # a body point to NED (rotation and offset)
}


def ell_flops(model: WakeModel) -> dict:
    """The flops of one :func:`formation_env.wake.kernels.evaluate_one` of ``model``'s formation as the kernels
    run it (the count above, per loop of :func:`~formation_env.wake.aic.assemble_and_solve`,
    :func:`~formation_env.wake.aic.lu_solve_inplace` and :func:`~formation_env.wake.field.field_velocity`);
    posing and the effective-wind sums (O(panels)) are left out. An estimate of the work, not a
    hardware count: the branch laws' rare paths (inside a core) cost a few flops more.

    Where the field's points and law are the solve's (evaluation at the control points, the viscous core in
    the AIC: ``shared``, the default), the AIC keeps the other vehicles' branch vectors (3 flops per other
    knot, 6 per other horseshoe) and the field is their sum weighted by the circulations (6 flops per other
    horseshoe and point); otherwise the field evaluates its branches again."""
    t, f = model.template, FLOPS
    pv, kv, sv = (np.asarray(x) for x in (t.panel_vehicle, t.knot_vehicle, t.surface_vehicle))
    n, k = len(pv), len(kv)
    shared = model.eval_points == "control" and model.viscous_aic
    aic = 0
    for j in range(n):
        own_k = int(np.sum(kv == pv[j]))
        own_p = int(np.sum(pv == pv[j]))
        aic += 2 * f["to_ned"] - 3 + f["knot"] * k          # control point and normal to NED, every knot's vectors
        aic += own_k * (f["leg"] + f["dot"])                  # own trailing legs (own bound/chordwise: static)
        aic += (k - own_k) * (f["leg_cored"] + f["branch_cored"] + 2 * f["dot"] + 3 * shared)
        aic += int(np.sum(sv != pv[j])) * f["core_radius"]   # once per other surface (its knots share it)
        aic += own_p * 3 + (n - own_p) * (f["branch_cored"] + f["dot"] + 4 + 6 * shared) + 5
    lu = int(round(2 * n ** 3 / 3 + 2 * n ** 2))
    field = 0
    for j in range(n):  # each evaluation point, the other vehicles' surfaces
        if shared:
            field += 6 * int(np.sum(pv != pv[j]))
            continue
        field += f["to_ned"]
        for s_ in np.nonzero(sv != pv[j])[0]:
            k0, k1 = int(t.surface_knot_start[s_]), int(t.surface_knot_start[s_ + 1])
            field += f["core_radius"] + f["knot"] * (k1 - k0)
            field += (k1 - k0) * (2 + f["leg_cored"] + f["branch_cored"] + 9) + (k1 - k0 - 1) * (f["branch_cored"] + 6)
    return {"aic": aic, "lu": lu, "field": field, "total": aic + lu + field}


def _median_time(fn, repeats: int, inner: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(inner):
            fn()
        times.append((time.perf_counter() - t0) / inner)
    return float(np.median(times))


def peak_gflops_per_core() -> dict:
    """The nominal float64 peak of one core of this machine, and how it is derived: 2 FMA pipes x the vector's
    float64 lanes (8 with AVX-512, 4 with AVX2, else 2) x 2 flops an FMA x the clock (``cpu MHz`` of
    /proc/cpuinfo, Linux; None elsewhere). An upper bound: cores that run 512-bit vectors as two 256-bit halves
    (AMD Zen 4) reach half of it, and code without FMA contraction (the kernels here: no fastmath) half again."""
    try:
        text = open("/proc/cpuinfo", encoding="utf-8").read()
    except OSError:
        return {"gflops": None, "derivation": "no /proc/cpuinfo: the clock is unknown"}
    mhz = next((float(line.split(":")[1]) for line in text.splitlines() if line.startswith("cpu MHz")), None)
    flags = next((line.split(":")[1].split() for line in text.splitlines() if line.startswith("flags")), [])
    lanes, isa = (8, "AVX-512") if "avx512f" in flags else (4, "AVX2") if "avx2" in flags else (2, "SSE2")
    if mhz is None:
        return {"gflops": None, "derivation": "no cpu MHz in /proc/cpuinfo: the clock is unknown"}
    return {"gflops": 2 * lanes * 2 * mhz / 1e3,
            "derivation": f"2 FMA pipes x {lanes} float64 lanes ({isa}) x 2 flops x {mhz / 1e3:.2f} GHz"}


def _lane_kernel_timer(model: WakeModel, states: FormationState):
    """A call of the batch-lane ELL (:func:`formation_env.wake.across.evaluate_batch_lanes_parallel`, the
    decision's chunked solve) on ``states``."""
    from .across import evaluate_batch_lanes_parallel
    from .biot_savart import SHEET_OFF, SHEET_ON

    b, v, n = states.batch_size, model.n_vehicles, model.n_panels
    out = [np.empty((b, n)), np.empty((b, n, 3))] + [np.empty((b, v, 3)) for _ in range(4)]
    args = (model._lattice, states.position_ned, states.euler_rad, states.airspeed_mps, states.alpha_rad,
            states.beta_rad, *out, SHEET_ON if model.sheet else SHEET_OFF)
    return lambda: evaluate_batch_lanes_parallel(*args)


def run_benchmarks(quick: bool = False) -> dict:
    """Return ELL timings (seconds and rates) for batch 1 and the batch sizes of interest: the per-formation
    kernel (:meth:`WakeModel.evaluate`) and the batch-lane kernel (:mod:`formation_env.wake.across`), each with one
    thread and with all of numba's, and the core's nominal peak they are measured against."""
    import numba

    model = WakeModel([aerosonde(nseg=10), aerosonde(nseg=10)])
    single = aerosonde_pair_states(1)
    model.evaluate(single)  # compile / load the cache outside the timing
    repeats = 5 if quick else 15
    t_single = _median_time(lambda: model.evaluate(single), repeats, 200 if quick else 1000)
    t_cold = _median_time(lambda: WakeModel([aerosonde(nseg=10), aerosonde(nseg=10)]).evaluate(single), 3, 20)
    flops = ell_flops(model)
    out = {
        "case": "2 Aerosondes (wing only), 10 horseshoes each, Kurylowich core, control points",
        "flops_per_evaluation": flops,
        "gflops_single": flops["total"] / t_single / 1e9,
        "single_evaluation_s": t_single,
        "single_evaluation_us": t_single * 1e6,
        "single_with_meshing_us": t_cold * 1e6,
        "thesis_s": THESIS_SECONDS_PER_EVALUATION,
        "speedup_vs_thesis": THESIS_SECONDS_PER_EVALUATION / t_single,
        "peak_per_core": peak_gflops_per_core(),
        "batched": {},
    }
    n_threads = numba.get_num_threads()
    for batch in (64, 1024) if not quick else (1024,):
        states = aerosonde_pair_states(batch)
        kernels = {"per_formation": lambda: model.evaluate(states), "across_lanes": _lane_kernel_timer(model, states)}
        rows = {}
        for threads in sorted({1, n_threads}):
            numba.set_num_threads(threads)
            try:
                for name, fn in kernels.items():
                    fn()  # compile / load the cache outside the timing
                    t = _median_time(fn, repeats, 3 if quick else 10)
                    gflops = flops["total"] * batch / t / 1e9
                    rows[f"{name}/{threads}"] = {
                        "kernel": name, "threads": threads, "seconds_per_call": t,
                        "formation_evaluations_per_s": batch / t, "us_per_formation": t / batch * 1e6,
                        "gflops": gflops, "gflops_per_core": gflops / threads}
            finally:
                numba.set_num_threads(n_threads)
        out["batched"][str(batch)] = rows
    return out
