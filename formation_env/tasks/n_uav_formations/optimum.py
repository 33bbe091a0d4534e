"""The joint induced-drag optimum of an N-UAV close formation (echelon of 3, vee of 5, vee of 9; issue 25).

In a formation of more than two every follower flies in the wake of the UAVs ahead of it, and those fly in
the wake of the ones ahead of them: a follower's best position depends on where the others are, and the
formation's saving is a joint optimum. Here it is found with the simulator's own ELL, exactly as the 2-UAV
close-formation map is (:mod:`formation_env.tasks.close_formation.optimum`: the energy tasks' lift-matched wing,
nseg 10 at the converged wake fidelity, every UAV at the trim of 25 m/s and 1000 m, same attitude, still air, the Kutta-Joukowski induced drag
of each UAV against the same UAV alone).

Geometry. Followers fly in *ranks*: rank k (1, 2, ...) trails rank k - 1 (rank 0: the leader) by 2 spans along
the track, ``dy_k`` spans outboard and ``dz_k`` spans below it. An echelon has one follower per rank (starboard);
a vee has two, mirrored (starboard, then port, for each rank: the scenarios' follower order). The search is over
the per-rank steps (dy_k, dz_k), the vee's two sides mirrored (the formation is symmetric; a mirrored optimum
is the symmetric formation's), with ``0.5 <= dy_k <= 1.5`` b and ``-0.2 <= dz_k <= 0.5`` b (:data:`DZ_RANGE_B`).
The ELL is the energy tasks' converged wake (sheet law, span correction, residual table of pairs), which has no
artefact band about a wake plane (issue 23 part 7); with the nseg-10 lattice's discrete legs a follower had to
stay out of the band |z| < 0.1 b, where the saving was the lattice's artefact, and every optimum pressed against
the band's edge.

Objective: the formation's induced-drag saving, ``1 - sum_i D_i(formation) / sum_i D_i(alone)`` over every UAV
(the leader included). With every UAV at the same trim the lone drags are equal, so it is the mean of the
UAVs' own savings. A grid over uniform steps (every rank the same) starts a bounded L-BFGS-B over all ranks'
steps.

``formation-env data optimum n_uav_formations`` rewrites the cache
(``formation_env/data/close_formations_optimum.json``) the tasks read.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path

import numpy as np

from ...io import atomic_write_json
from ...scenarios.definitions import AEROSONDE_SPAN_M
from ...sim.formation import WakeConfig
from ..close_formation.optimum import DEFAULT_X_B, DEFAULT_Z_EXCLUSION_B, NOMINAL_FUEL_KG, TASK_WAKE

__all__ = ["FORMATIONS", "Z_EXCLUSION_B", "CACHE_PATH", "Layout", "layout_offsets", "formation_savings",
           "JointOptimum", "find_joint_optimum", "build_cache", "write_cache", "load_cache", "optimum"]

Z_EXCLUSION_B = DEFAULT_Z_EXCLUSION_B
DY_RANGE_B = (0.5, 1.5)
# each rank's vertical step: above or below the wake plane of the UAV it trails (the converged wake has no artefact
# band there, issue 23 part 7: its pair optimum lies on the plane, 0.002 b below it), up to half a span below
DZ_RANGE_B = (-0.2, 0.5)
CACHE_PATH = Path(__file__).resolve().parents[2] / "data" / "close_formations_optimum.json"
_FD_STEP_B = 1e-6


@dataclass(frozen=True)
class Layout:
    """A formation's shape: ``ranks`` behind the leader, ``sides`` ((+1,) an echelon to starboard; (+1, -1) a
    vee: each rank a starboard and a port follower, in that order)."""

    name: str
    ranks: int
    sides: tuple

    @property
    def n_vehicles(self) -> int:
        return 1 + self.ranks * len(self.sides)


#: the N-UAV close formations (task name -> layout)
FORMATIONS = {"echelon3": Layout("echelon3", 2, (1,)), "vee5": Layout("vee5", 2, (1, -1)),
              "vee9": Layout("vee9", 4, (1, -1))}


def layout_offsets(layout: Layout, steps_b, x_step_b: float = DEFAULT_X_B) -> np.ndarray:
    """Follower offsets from the leader, spans, leader's track frame: (..., F, 3) for per-rank steps
    ``steps_b`` (..., ranks, 2) = (dy_k, dz_k); followers ordered rank by rank, each rank's sides in order."""
    st = np.asarray(steps_b, float)
    if st.shape[-2:] != (layout.ranks, 2):
        raise ValueError(f"layout_offsets: steps_b must have shape (..., {layout.ranks}, 2), got {st.shape}")
    cum = np.cumsum(st, axis=-2)  # (..., R, 2): rank k's outboard and down offset
    out = []
    for k in range(layout.ranks):
        for side in layout.sides:
            x = np.full(st.shape[:-2], x_step_b * (k + 1))
            out.append(np.stack([x, side * cum[..., k, 0], cum[..., k, 1]], axis=-1))
    return np.stack(out, axis=-2)


@lru_cache(maxsize=8)
def _model(wake: WakeConfig, n_vehicles: int):
    from ...sim.formation import wake_model_for, wing_origin_body

    return wake_model_for(wake, n_vehicles), wing_origin_body()


@lru_cache(maxsize=8)
def _trim(airspeed_mps: float, altitude_m: float, fuel_kg: float):
    from ...aircraft import trim

    return trim(airspeed_mps, altitude_m, fuel_kg)


def formation_savings(offsets_b, *, wake: WakeConfig = TASK_WAKE, airspeed_mps: float = 25.0,
                      altitude_m: float = 1000.0, span_m: float = AEROSONDE_SPAN_M, chunk: int = 512) -> np.ndarray:
    """Each UAV's induced-drag saving ``1 - D_i(formation) / D_i(alone)`` with the followers at ``offsets_b``
    (..., F, 3) (spans from the leader, its track frame): (..., F + 1), the leader first. Every UAV at the same
    trim (``airspeed_mps``, ``altitude_m``, the nominal fuel), still air; batched ELL evaluations."""
    off = np.asarray(offsets_b, dtype=float)
    if off.ndim < 2 or off.shape[-1] != 3 or not np.all(np.isfinite(off)):
        raise ValueError(f"formation_savings: offsets_b must be finite with shape (..., F, 3), got {off.shape}")
    from ...sim.formation import ell_state_from_aircraft
    from ...wake import formation_benefit

    nv = off.shape[-2] + 1
    model, wing_origin = _model(wake, nv)
    tr = _trim(float(airspeed_mps), float(altitude_m), NOMINAL_FUEL_KG)
    flat = off.reshape(-1, nv - 1, 3)
    out = np.empty((flat.shape[0], nv))
    for i in range(0, flat.shape[0], chunk):
        part = flat[i:i + chunk]
        state = np.repeat(np.repeat(tr.state, nv, axis=0)[None], part.shape[0], axis=0)  # (P, V, 16)
        state[:, 1:, 10:13] += part * span_m
        ell = ell_state_from_aircraft(state, np.zeros((part.shape[0], nv, 3)), wing_origin)
        out[i:i + chunk] = formation_benefit(model, ell)["induced_drag_saving"]
    return out.reshape(off.shape[:-2] + (nv,))


@dataclass(frozen=True)
class JointOptimum:
    """The best formation found: per-rank steps, follower offsets and the savings there."""

    name: str
    steps_b: tuple  # ((dy_k, dz_k), ...) spans
    offsets_b: tuple  # ((x, y, z), ...) per follower, spans from the leader
    savings: tuple  # each UAV's saving, the leader first
    formation_saving: float  # mean over every UAV (equal lone drags)
    follower_saving: float  # mean over the followers
    uniform_steps_b: tuple  # the grid's best uniform step (dy, dz)
    uniform_formation_saving: float
    on_band_edge: tuple  # per rank: dz_k at the band's edge
    n_evaluations: int

    def as_dict(self) -> dict:
        d = dataclasses.asdict(self)
        r = lambda v: round(float(v), 5)  # noqa: E731
        d["steps_b"] = [[r(a), r(b)] for a, b in self.steps_b]
        d["offsets_b"] = [[r(v) for v in o] for o in self.offsets_b]
        d["savings"] = [r(v) for v in self.savings]
        d["uniform_steps_b"] = [r(v) for v in self.uniform_steps_b]
        for k in ("formation_saving", "follower_saving", "uniform_formation_saving"):
            d[k] = r(d[k])
        return d


def find_joint_optimum(name: str, *, grid_step_b: float = 0.05, **model_kw) -> JointOptimum:
    """The joint optimum of formation ``name`` (a key of :data:`FORMATIONS`): the grid's best uniform step,
    then a bounded L-BFGS-B over every rank's (dy, dz) (forward-difference gradient, one batched call each)."""
    from scipy.optimize import minimize

    if name not in FORMATIONS:
        raise ValueError(f"find_joint_optimum: unknown formation {name!r}; available: {list(FORMATIONS)}")
    lay = FORMATIONS[name]
    n_eval = 0

    def total(steps):  # (P, R, 2) -> (P,) formation saving, and the per-UAV savings
        nonlocal n_eval
        s = formation_savings(layout_offsets(lay, steps), **model_kw)
        n_eval += s.shape[0]
        return s.mean(axis=-1), s

    gy = np.arange(DY_RANGE_B[0], DY_RANGE_B[1] + 1e-9, grid_step_b)
    gz = np.arange(DZ_RANGE_B[0], DZ_RANGE_B[1] + 1e-9, grid_step_b)
    yy, zz = np.meshgrid(gy, gz, indexing="ij")
    uni = np.repeat(np.stack([yy.ravel(), zz.ravel()], axis=-1)[:, None, :], lay.ranks, axis=1)
    f, _ = total(uni)
    k = int(np.argmax(f))
    x0 = uni[k].ravel()
    bounds = [DY_RANGE_B, DZ_RANGE_B] * lay.ranks
    hi = np.array([b[1] for b in bounds])

    def neg_and_grad(p):
        h = np.where(p + _FD_STEP_B <= hi, _FD_STEP_B, -_FD_STEP_B)
        pts = np.repeat(p[None], p.size + 1, axis=0)
        pts[1:] += np.diag(h)
        v, _ = total(pts.reshape(-1, lay.ranks, 2))
        return -v[0], -(v[1:] - v[0]) / h

    res = minimize(neg_and_grad, x0, jac=True, method="L-BFGS-B", bounds=bounds, options={"ftol": 1e-12, "gtol": 1e-7})
    best = res.x if -res.fun >= f[k] else x0
    steps = best.reshape(lay.ranks, 2)
    v, s = total(steps[None])
    offs = layout_offsets(lay, steps)
    return JointOptimum(name, tuple(map(tuple, steps.tolist())), tuple(map(tuple, offs.tolist())),
                        tuple(s[0].tolist()), float(v[0]), float(s[0, 1:].mean()), tuple(uni[k, 0].tolist()),
                        float(f[k]), tuple(bool(Z_EXCLUSION_B > 0 and abs(dz - Z_EXCLUSION_B) < 1e-6) for _, dz in steps), n_eval)


def build_cache(slot_decimals: int = 2, **model_kw) -> dict:
    """Every formation's joint optimum, its slots rounded to ``slot_decimals`` spans (the scenarios') and the
    savings at the rounded slots (what the tasks are judged against)."""
    wake = model_kw.get("wake", TASK_WAKE)
    out = {"_about": "Joint induced-drag optima of the N-UAV close formations (formation_env.tasks.n_uav_formations."
                     "optimum): offsets in spans from the leader, its track frame (x forward, y starboard, z down); "
                     "savings 1 - D_i(formation) / D_i(alone) from the ELL, every UAV at the trim.",
           "parameters": {"x_step_b": DEFAULT_X_B, "dy_range_b": list(DY_RANGE_B), "dz_range_b": list(DZ_RANGE_B),
                          "span_m": AEROSONDE_SPAN_M, "airspeed_mps": model_kw.get("airspeed_mps", 25.0),
                          "altitude_m": model_kw.get("altitude_m", 1000.0), "wake": dataclasses.asdict(wake)},
           "formations": {}}
    for name, lay in FORMATIONS.items():
        opt = find_joint_optimum(name, **model_kw)
        slots = np.round(np.asarray(opt.offsets_b), slot_decimals) + 0.0  # + 0.0: no -0.0 in the cache
        s = formation_savings(slots, **model_kw)
        out["formations"][name] = {
            "optimum": opt.as_dict(),
            "slots_b": slots.tolist(),
            "slot_savings": np.round(s, 5).tolist(),
            "slot_formation_saving": round(float(s.mean()), 5),
            "slot_follower_saving": round(float(s[1:].mean()), 5),
        }
    return out


def write_cache(path=CACHE_PATH, *, overwrite: bool = True, **build_kw) -> Path:
    return atomic_write_json(path, build_cache(**build_kw), overwrite=overwrite)


@lru_cache(maxsize=1)
def _package_cache() -> str:
    return resources.files("formation_env.data").joinpath("close_formations_optimum.json").read_text()


def load_cache(path=None) -> dict:
    """The cached optima (the package's data file unless ``path``)."""
    return json.loads(_package_cache() if path is None else Path(path).read_text())


def optimum(name: str, cache: dict | None = None) -> dict:
    """Formation ``name``'s cached entry: ``slots_b`` (F, 3), ``slot_savings`` (the leader first), ..."""
    c = load_cache() if cache is None else cache
    if name not in c["formations"]:
        raise ValueError(f"n_uav_formations: no cached optimum for {name!r}; available: {list(c['formations'])}")
    return c["formations"][name]
