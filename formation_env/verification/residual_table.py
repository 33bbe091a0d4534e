"""Building the ELL residual table of pairs (:mod:`formation_env.wake.residual`; issue 23 part 6, docs/ell.md
"Converged saving"): one pair's outputs on a grid of relative poses with the fine and the base lattice, their
difference, and the command that writes the shipped table.

``python -m formation_env.verification.residual_table [--processes 2] [--force]`` (slow: the fine lattice is solved
at every node of the grid, so ``--processes`` spreads the nodes over processes).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..wake.residual import N_VALUES, TABLE_PATH, VALUE_SAVING, VALUE_WIND, TableGrid, save_table

__all__ = ["FINE", "BASE", "pair_values", "build_table", "main"]


# ---------------------------------------------------------------------------------------------------------------
# One pair's outputs on a grid of relative poses
# ---------------------------------------------------------------------------------------------------------------

def pair_values(wake, offsets_b: np.ndarray, roll_rad, *, airspeed_mps: float = 25.0,
                altitude_m: float = 1000.0) -> tuple[np.ndarray, float]:
    """(P, N_VALUES) outputs of the receiver of a pair, and the source's lift per unit rho V (m^3/s):
    the source at the origin, the receiver's CG at ``offsets_b`` (P, 3) spans NED and rolled by ``roll_rad``
    ((P,) or a scalar, rad), both at the trim (same attitude otherwise, still air), the ELL of ``wake`` (a
    :class:`~formation_env.sim.formation.WakeConfig`; its lift-matched wing, its sheet law and span
    correction as set, no residual table). Saving from the env's compiled path, winds from
    :func:`~formation_env.wake.coupling.coupled_wind` (NED = the pair frame here)."""
    import dataclasses

    from ..aircraft import AEROSONDE, trim
    from ..constants import AEROSONDE_SPAN_M
    from ..sim.formation import ell_state_from_aircraft, wake_model_for, wing_origin_body
    from ..wake.arrays import wake_arrays
    from ..wake.benefit import induced_drag_saving_one
    from ..wake.coupling import coupled_wind, coupling_arrays
    from ..wake.loads import isolated_model

    wake = dataclasses.replace(wake, coupling="load_weighted", residual_table=False)
    model = wake_model_for(wake, 2)
    origin = wing_origin_body()
    arrays = wake_arrays(model, origin)
    alone = wake_arrays(isolated_model(model.vehicles[0], model.core, model.eval_points, model.rotational,
                                       model.kinematic_viscosity, model.viscous_aic), origin)
    coupling = coupling_arrays(model, "load_weighted", AEROSONDE)
    off = np.asarray(offsets_b, float).reshape(-1, 3)
    roll = np.broadcast_to(np.asarray(roll_rad, float), (len(off),))
    tr = trim(airspeed_mps, altitude_m)
    st = np.repeat(np.asarray(tr.state, float).reshape(1, 1, -1), 2, axis=1).repeat(len(off), 0)
    st[:, 1, 10:13] += off * AEROSONDE_SPAN_M
    ell = ell_state_from_aircraft(st, np.zeros((len(off), 2, 3)), origin)
    euler = ell.euler_rad.copy()
    euler[:, 1, 0] += roll  # rolled about its wing origin (the pair frame's positions are the wing origins')
    n = model.n_panels
    out = np.empty((len(off), N_VALUES))
    gamma, vpts = np.empty(n), np.empty((n, 3))
    saving = np.empty(2)
    for i in range(len(off)):
        args = [np.ascontiguousarray(a[i]) for a in (ell.position_ned, euler, ell.airspeed_mps, ell.alpha_rad,
                                                     ell.beta_rad)]
        res = [np.empty((2, 3)) for _ in range(4)]
        coupled_wind(arrays, coupling, *args, gamma, vpts, *res)
        out[i, VALUE_WIND:VALUE_WIND + 3] = res[0][1]
        out[i, VALUE_WIND + 3:VALUE_WIND + 6] = res[3][1]
        induced_drag_saving_one(arrays, alone, *args, gamma, saving)
        out[i, VALUE_SAVING] = saving[1]
    from ..wake.benefit import isolated_circulation_one
    from ..wake.residual import lift_per_rho_v

    args = [np.ascontiguousarray(a[0]) for a in (ell.position_ned, ell.euler_rad, ell.airspeed_mps, ell.alpha_rad,
                                                 ell.beta_rad)]
    g_alone = np.empty(alone.n_panels)
    isolated_circulation_one(alone, 0, *args, g_alone)
    return out, float(lift_per_rho_v(alone, g_alone, 0))


FINE = {"nseg": 80}  # the reference: nseg 80, the thesis's legs, no span correction (kappa of 80 against 80 is 1)
BASE = {"sheet": True, "span_correction": True}  # what the table corrects (nseg 10)


def _slice(args):
    """One (x, roll) plane of the residual: fine minus base over y x z (worker of :func:`build_table`)."""
    from ..sim.formation import WakeConfig

    x, roll, y, z = args
    off = np.stack(np.meshgrid([x], y, z, indexing="ij"), -1).reshape(-1, 3)
    fine, _ = pair_values(WakeConfig(**FINE), off, roll)
    base, lift = pair_values(WakeConfig(**BASE), off, roll)
    return (fine - base).reshape(len(y), len(z), N_VALUES), lift


def build_table(grid: TableGrid = TableGrid(), processes: int = 2, progress=None) -> dict:
    """The residual on ``grid`` (fine minus base, :data:`FINE`, :data:`BASE`), computed in ``processes``
    worker processes; returns the arrays :func:`save_table` writes."""
    import multiprocessing as mp

    xs, ys, zs, rolls = grid.axes()
    jobs = [(float(x), float(r), ys, zs) for x in xs for r in rolls]
    values = np.empty((len(xs), len(ys), len(zs), len(rolls), N_VALUES))
    lift = None
    ctx = mp.get_context("spawn")
    with ctx.Pool(processes) as pool:
        for k, (res, lift) in enumerate(pool.imap(_slice, jobs)):
            values[k // len(rolls), :, :, k % len(rolls)] = res
            if progress is not None:
                progress(k + 1, len(jobs))
    from ..constants import AEROSONDE_SPAN_M

    return {"x_b": xs, "y_step_b": grid.y_step_b, "z_scale_b": grid.z_scale_b, "s_step": grid.s_step,
            "ns": grid.ns, "roll_step_rad": float(np.radians(grid.roll_step_deg)), "values": values,
            "span_m": AEROSONDE_SPAN_M, "source_lift_m3ps": float(lift)}


def main(argv=None) -> int:
    import argparse
    import subprocess
    import sys
    import time

    ap = argparse.ArgumentParser(prog="python -m formation_env.verification.residual_table",
                                 description="Build the ELL residual table of pairs (docs/ell.md).")
    ap.add_argument("--out", type=Path, default=TABLE_PATH)
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--force", action="store_true", help="replace an existing table")
    a = ap.parse_args(argv)
    if a.processes < 1:
        print(f"--processes must be >= 1, got {a.processes}", file=sys.stderr)
        return 2
    if a.out.exists() and not a.force:
        print(f"{a.out} exists; --force replaces it", file=sys.stderr)
        return 2
    t0 = time.time()
    d = build_table(processes=a.processes,
                    progress=lambda k, n: print(f"  {k}/{n} planes, {time.time() - t0:.0f} s", flush=True))
    try:
        rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                             cwd=Path(__file__).parent).stdout.strip()
    except OSError:
        rev = "unknown"
    prov = (f"python -m formation_env.verification.residual_table --processes {a.processes}; grid {TableGrid()}; fine {FINE}, "
            f"base {BASE}; built at {rev} in {time.time() - t0:.0f} s")
    print(save_table(d, a.out, overwrite=a.force, provenance=prov), prov)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
