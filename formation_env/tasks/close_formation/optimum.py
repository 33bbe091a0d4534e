"""Induced-drag map of a two-ship Aerosonde formation and the close-formation optimum.

The follower's induced-drag saving ``1 - D_i(formation) / D_i(alone)`` (ELL, Kutta-Joukowski
loads: :func:`formation_env.wake.formation_benefit`) is mapped over follower slots. The vehicle
model is the simulator's: :func:`formation_env.sim.formation.wake_model_for` builds the ELL model from
its :class:`~formation_env.sim.formation.WakeConfig` (default :data:`TASK_WAKE`: the Aerosonde's wing
lift-matched as the energy tasks' load-weighted coupling flies it, nseg 10, Kurylowich core, control points,
viscous AIC) and the wing origin from the aircraft data, and the
ELL poses come from :func:`~formation_env.sim.formation.ell_state_from_aircraft`, exactly as the
env's ``_saving`` does. Both aircraft fly the trim of ``trim(airspeed, altitude)`` (same attitude,
still air); the leader flies north, so the leader's track frame (x forward, y starboard, z down;
the scenarios' slot frame) is NED. Offsets are in spans (b = 2.9 m) between the aircraft's
reference points (CGs), as the scenarios' slots are; with both at the same attitude the wing
origins are offset by the same amount.

Artefact at z = 0: ELL's wake is a discrete sheet of straight trailing legs (one per panel edge,
0.1 b apart on the Aerosonde) in the leader's wing plane. When the follower's wing is in or near
that plane its control points pass close to single legs and its saving ripples with the leg
spacing (every 0.1 b; its peak passes 100 % on the plane, from a smooth 36 % at |z| = 0.1 b).
The ripple is measured by :func:`ripple_profile` (the excess variation of the lateral saving profile over a
single-peaked one) and :func:`exclusion_band` picks the smallest band |z| < z_ex outside which
every lateral profile is single-peaked; :func:`find_optimum` searches only outside it. Outside the
band the saving grows monotonically towards the sheet, so the optimum lies on the band's edge.

``formation-env data optimum close_formation`` rewrites the cached map
(``formation_env/data/close_formation_map.json``) and ``formation-env data saving-map PATH`` draws its figure.
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

#: the ELL the energy tasks fly (close_formation and the N-UAV close formations: the load-weighted coupling, whose
#: wing is lift-matched to the 6-DOF, formation_env.wake.coupling, at the "converged" wake fidelity: the sheet law,
#: span correction and residual table of pairs, within 0.2 % of an nseg-80 lattice's peak, issue 23): the map is the
#: saving those tasks report
TASK_WAKE = WakeConfig(coupling="load_weighted", sheet=True, span_correction=True, residual_table=True)
#: the thesis's nseg-10 lattice with the lift-matched wing (discrete trailing legs): what the energy tasks flew before
#: issue 23 part 7 (wake_surfing's lattice-era box kept out of the band LATTICE_Z_EXCLUSION_B where its saving ripples);
#: kept for comparisons and for ``--wake-fidelity lattice``
LATTICE_WAKE = WakeConfig(coupling="load_weighted", sheet=False, span_correction=False, residual_table=False)

__all__ = ["DEFAULT_X_B", "THESIS_SLOT_B", "DEFAULT_Z_EXCLUSION_B", "LATTICE_Z_EXCLUSION_B", "TASK_WAKE",
           "LATTICE_WAKE", "CACHE_PATH", "SavingMap", "Optimum",
           "slot_savings", "saving_map", "ripple_profile", "exclusion_band", "find_optimum", "sensitivity",
           "build_cache", "write_cache", "load_cache", "optimum_saving"]

DEFAULT_X_B = -2.0
NOMINAL_FUEL_KG = 2.0  # the trim's fuel (formation_env.aircraft.trim), kg: 10.5 kg in all
THESIS_SLOT_B = (-2.0, 1.0, 0.3)  # section 6.5's formation-keeping slot
# the band about the leader's wake plane outside which the task's slot is sought: exclusion_band() of TASK_WAKE at
# x = -2 b measures none (every lateral profile single-peaked down to z = 0; the cache's z_exclusion_measured_b), so
# the task keeps none: the band of the nseg-10 lattice (LATTICE_Z_EXCLUSION_B) was its discrete legs' artefact, and
# the physics that could justify one is small at 2 spans: the leader's wake descends ~0.01 b by then (its vortex pair's
# mutual induction, Gamma / (2 pi b'), b' = pi b / 4) and rolls up over ~10 b, not 2 (docs/close_formation.md)
DEFAULT_Z_EXCLUSION_B = 0.0
LATTICE_Z_EXCLUSION_B = 0.10  # exclusion_band() of LATTICE_WAKE at x = -2 b (the discrete legs' ripple)
RIPPLE_Y_B = np.round(np.arange(0.0, 1.5 + 1e-9, 0.005), 6)  # lateral profile the ripple is measured on
CACHE_PATH = Path(__file__).resolve().parents[2] / "data" / "close_formation_map.json"
_SIDES = ("starboard", "port")
_FD_STEP_B = 1e-6  # finite-difference step of the optimiser's gradient, spans


@lru_cache(maxsize=8)
def _model(wake: WakeConfig):
    from ...sim.formation import wake_model_for, wing_origin_body

    if not wake.enabled:
        raise ValueError("close_formation_map: the wake must be enabled")
    return wake_model_for(wake, 2), wing_origin_body()


@lru_cache(maxsize=512)
def _trim(airspeed_mps: float, altitude_m: float, fuel_kg: float):
    from ...aircraft import trim

    return trim(airspeed_mps, altitude_m, fuel_kg)


def _setup(wake: WakeConfig, airspeed_mps: float, altitude_m: float, leader_fuel_kg: float = NOMINAL_FUEL_KG,
           follower_fuel_kg: float = NOMINAL_FUEL_KG):
    """The simulator's two-ship ELL model and wing origin (built once), and the two trims (each kept)."""
    model, origin = _model(wake)
    return model, origin, _trim(airspeed_mps, altitude_m, leader_fuel_kg), _trim(airspeed_mps, altitude_m, follower_fuel_kg)


def slot_savings(offsets_b, *, wake: WakeConfig = TASK_WAKE, airspeed_mps: float = 25.0,
                 altitude_m: float = 1000.0, span_m: float = AEROSONDE_SPAN_M, chunk: int = 2048,
                 leader_fuel_kg: float = NOMINAL_FUEL_KG, follower_fuel_kg: float = NOMINAL_FUEL_KG) -> np.ndarray:
    """Induced-drag saving of (leader, follower) with the follower at ``offsets_b``.

    offsets_b (..., 3): follower slot relative to the leader in its track frame, spans. Returns
    (..., 2): ``[..., 0]`` the leader's saving, ``[..., 1]`` the follower's. All slots are batched
    ELL evaluations (``chunk`` at a time). Each aircraft flies its own trim at ``airspeed_mps`` with its fuel
    (``leader_fuel_kg``, ``follower_fuel_kg``: its weight, AeroSim mass = 8.5 kg + fuel; default the trim's 2 kg).
    """
    off = np.asarray(offsets_b, dtype=float)
    if off.ndim < 1 or off.shape[-1] != 3 or not np.all(np.isfinite(off)):
        raise ValueError(f"slot_savings: offsets_b must be finite with shape (..., 3), got shape {off.shape}")
    from ...sim.formation import ell_state_from_aircraft
    from ...wake import formation_benefit

    model, wing_origin, tr_l, tr_f = _setup(wake, float(airspeed_mps), float(altitude_m), float(leader_fuel_kg),
                                            float(follower_fuel_kg))
    pair = np.concatenate([tr_l.state, tr_f.state])  # (2, 16)
    flat = off.reshape(-1, 3)
    out = np.empty((flat.shape[0], 2))
    for i in range(0, flat.shape[0], chunk):
        part = flat[i:i + chunk]
        state = np.repeat(pair[None], part.shape[0], axis=0)  # (P, 2, 16)
        state[:, 1, 10:13] += part * span_m
        ell = ell_state_from_aircraft(state, np.zeros((part.shape[0], 2, 3)), wing_origin)
        out[i:i + chunk] = formation_benefit(model, ell)["induced_drag_saving"]
    return out.reshape(off.shape[:-1] + (2,))


@dataclass(frozen=True)
class SavingMap:
    """Savings over a (y, z) grid of follower slots at one x; arrays (ny, nz)."""

    x_b: float
    y_b: np.ndarray
    z_b: np.ndarray
    follower: np.ndarray
    leader: np.ndarray

    def as_dict(self, decimals: int = 4) -> dict:
        r = lambda a: np.round(np.asarray(a), decimals).tolist()  # noqa: E731
        return {"x_b": self.x_b, "y_b": r(self.y_b), "z_b": r(self.z_b),
                "follower_saving": r(self.follower), "leader_saving": r(self.leader)}

    @classmethod
    def from_dict(cls, d: dict) -> "SavingMap":
        return cls(float(d["x_b"]), np.asarray(d["y_b"], float), np.asarray(d["z_b"], float),
                   np.asarray(d["follower_saving"], float), np.asarray(d["leader_saving"], float))


def saving_map(x_b: float = DEFAULT_X_B, y_b=None, z_b=None, **model_kw) -> SavingMap:
    """Leader's and follower's saving with the follower over the grid ``y_b`` x ``z_b`` at ``x_b``
    (spans; defaults: y -1.5..1.5 b and z -0.5..0.5 b, 0.1 b and 0.05 b steps). ``model_kw`` go to
    :func:`slot_savings` (``wake``, ``airspeed_mps``, ``altitude_m``)."""
    y = np.round(np.linspace(-1.5, 1.5, 31), 6) if y_b is None else np.atleast_1d(np.asarray(y_b, float))
    z = np.round(np.linspace(-0.5, 0.5, 21), 6) if z_b is None else np.atleast_1d(np.asarray(z_b, float))
    yy, zz = np.meshgrid(y, z, indexing="ij")
    s = slot_savings(np.stack([np.full_like(yy, x_b), yy, zz], axis=-1), **model_kw)
    return SavingMap(float(x_b), y, z, s[..., 1], s[..., 0])


def ripple_profile(z_b, *, x_b: float = DEFAULT_X_B, y_b=RIPPLE_Y_B, **model_kw) -> dict:
    """How far the follower's lateral saving profile at each height is from single-peaked.

    For each z the saving s(y) over ``y_b`` gives ``excess_variation`` = total variation - (2 max
    - s(first) - s(last)): zero when s rises to one peak and falls, the ripple's added up-and-down
    otherwise; and ``n_local_maxima``. Returns arrays over ``z_b`` and the profiles' peaks.
    """
    z = np.atleast_1d(np.asarray(z_b, float))
    m = saving_map(x_b, y_b, z, **model_kw)
    s = m.follower  # (ny, nz)
    tv = np.abs(np.diff(s, axis=0)).sum(axis=0)
    excess = tv - (2 * s.max(axis=0) - s[0] - s[-1])
    nmax = np.sum((s[1:-1] > s[:-2]) & (s[1:-1] > s[2:]), axis=0)
    return {"z_b": z, "excess_variation": excess, "n_local_maxima": nmax,
            "peak_saving": s.max(axis=0), "peak_y_b": m.y_b[np.argmax(s, axis=0)]}


def exclusion_band(x_b: float = DEFAULT_X_B, *, z_step_b: float = 0.01, z_max_b: float = 0.3, tol: float = 1e-4,
                   **ripple_kw) -> tuple[float, dict]:
    """Smallest z_ex (a multiple of ``z_step_b``) such that the lateral profiles at every grid height
    with z_ex <= |z| <= z_max_b, above and below the leader, ripple by at most ``tol``.
    Returns ``(z_ex, ripple table over the signed heights)``."""
    mags = np.round(np.arange(0.0, z_max_b + 1e-9, z_step_b), 6)
    z = np.concatenate([-mags[::-1], mags[1:]])
    rp = ripple_profile(z, x_b=x_b, **ripple_kw)
    ex = rp["excess_variation"]
    worst = np.maximum(ex[:mags.size][::-1], ex[mags.size - 1:])  # the worse side, by |z|
    bad = np.nonzero(worst > tol)[0]
    if bad.size and bad[-1] == mags.size - 1:
        raise ValueError(f"exclusion_band: the profile still ripples at |z| = {z_max_b} b; raise z_max_b")
    z_ex = float(mags[bad[-1] + 1]) if bad.size else 0.0
    return z_ex, rp


@dataclass(frozen=True)
class Optimum:
    """The best follower slot found outside the excluded band."""

    offset_b: tuple  # (x, y, z) spans, leader's track frame
    saving: float  # follower's induced-drag saving there
    leader_saving: float
    side: str
    z_exclusion_b: float
    on_band_edge: bool  # the optimum presses against |z| = z_exclusion_b
    candidates: tuple  # ((offset_b, saving), ...): the refined best below and above the leader
    n_evaluations: int  # follower slots evaluated
    n_calls: int  # batched ELL calls

    def as_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["offset_b"] = [round(v, 5) for v in self.offset_b]
        d["saving"], d["leader_saving"] = round(self.saving, 5), round(self.leader_saving, 5)
        d["candidates"] = [{"offset_b": [round(v, 5) for v in o], "saving": round(s, 5)} for o, s in self.candidates]
        return d


def find_optimum(x_b: float = DEFAULT_X_B, *, z_exclusion_b: float = DEFAULT_Z_EXCLUSION_B, side: str = "starboard",
                 y_range_b: tuple = (0.5, 1.5), z_max_b: float = 0.5, grid_step_b: float = 0.05,
                 **model_kw) -> Optimum:
    """The follower slot at ``x_b`` with the largest induced-drag saving, |z| >= ``z_exclusion_b``.

    ``y_range_b`` is the starboard lateral range (mirrored for ``side="port"``), ``z_max_b`` the
    largest |z| searched. A grid (``grid_step_b``) over both half-planes (below and above the
    leader) gives each half's best point, refined with a bounded L-BFGS-B; the better one wins.
    """
    from scipy.optimize import minimize

    if side not in _SIDES:
        raise ValueError(f"find_optimum: side must be one of {_SIDES}, got {side!r}")
    if not 0.0 <= z_exclusion_b < z_max_b:
        raise ValueError(f"find_optimum: need 0 <= z_exclusion_b < z_max_b, got {z_exclusion_b}, {z_max_b}")
    lo, hi = sorted(float(v) for v in y_range_b)
    if side == "port":
        lo, hi = -hi, -lo
    n_eval = n_calls = 0

    def savings(y, z):
        nonlocal n_eval, n_calls
        y, z = np.broadcast_arrays(np.asarray(y, float), np.asarray(z, float))
        n_eval += y.size
        n_calls += 1
        return slot_savings(np.stack([np.full(y.shape, float(x_b)), y, z], axis=-1), **model_kw)

    ny = max(2, int(round((hi - lo) / grid_step_b)) + 1)
    nz = max(2, int(round((z_max_b - z_exclusion_b) / grid_step_b)) + 1)
    gy = np.linspace(lo, hi, ny)
    found = []
    for sign in (1.0, -1.0):  # below, above the leader
        gz = sign * np.linspace(z_exclusion_b, z_max_b, nz)
        yy, zz = np.meshgrid(gy, gz, indexing="ij")
        s = savings(yy, zz)[..., 1]
        k = np.unravel_index(np.argmax(s), s.shape)
        zb = sorted((sign * z_exclusion_b, sign * z_max_b))

        def neg_and_grad(p, zb=zb):  # value and forward-difference gradient in one batched call
            hy, hz = (_FD_STEP_B if p[0] + _FD_STEP_B <= hi else -_FD_STEP_B,
                      _FD_STEP_B if p[1] + _FD_STEP_B <= zb[1] else -_FD_STEP_B)
            f = savings([p[0], p[0] + hy, p[0]], [p[1], p[1], p[1] + hz])[:, 1]
            return -f[0], -np.array([(f[1] - f[0]) / hy, (f[2] - f[0]) / hz])

        res = minimize(neg_and_grad, np.array([yy[k], zz[k]]), jac=True, method="L-BFGS-B",
                       bounds=[(lo, hi), tuple(zb)], options={"ftol": 1e-10, "gtol": 1e-6})
        best = (res.x, -res.fun) if -res.fun >= s[k] else (np.array([yy[k], zz[k]]), s[k])
        found.append(((float(x_b), float(best[0][0]), float(best[0][1])), float(best[1])))
    offset, saving = max(found, key=lambda c: c[1])
    leader = float(savings(offset[1], offset[2])[0])
    return Optimum(offset, saving, leader, side, float(z_exclusion_b),
                   bool(abs(abs(offset[2]) - z_exclusion_b) < 1e-6), tuple(found), n_eval, n_calls)


def sensitivity(offset_b, *, delta_b: float = 0.1, z_exclusion_b: float = DEFAULT_Z_EXCLUSION_B, **model_kw) -> dict:
    """Follower saving with the slot moved by -/+ ``delta_b`` along x, y and z (each axis alone):
    ``{axis: {"minus": s, "plus": s, "loss_minus": s0 - s, "loss_plus": ..., "minus_in_band": ...}}``
    (a move into |z| < z_exclusion_b lands in the artefact band: its number is not trustworthy)."""
    o = np.asarray(offset_b, float)
    pts = [o]
    for ax in range(3):
        for sgn in (-1.0, 1.0):
            p = o.copy()
            p[ax] += sgn * delta_b
            pts.append(p)
    s = slot_savings(np.array(pts), **model_kw)[:, 1]
    out = {"delta_b": delta_b, "saving": float(s[0])}
    for ax, name in enumerate("xyz"):
        sm, sp = float(s[1 + 2 * ax]), float(s[2 + 2 * ax])
        out[name] = {"minus": sm, "plus": sp, "loss_minus": float(s[0] - sm), "loss_plus": float(s[0] - sp),
                     "minus_in_band": bool(abs(pts[1 + 2 * ax][2]) < z_exclusion_b - 1e-9),
                     "plus_in_band": bool(abs(pts[2 + 2 * ax][2]) < z_exclusion_b - 1e-9)}
    return out


def _r(v, d=5):
    return np.round(np.asarray(v, float), d).tolist()


def _round_tree(d, digits=5):
    if isinstance(d, dict):
        return {k: _round_tree(v, digits) for k, v in d.items()}
    return round(d, digits) if isinstance(d, float) else d


def build_cache(x_b: float = DEFAULT_X_B, *, y_b=None, z_b=None, wake: WakeConfig = TASK_WAKE,
                airspeed_mps: float = 25.0, altitude_m: float = 1000.0, slot_decimals: int = 2) -> dict:
    """Everything the docs and tests read: the band (from the ripple), the optimum (both sides),
    the thesis slot's saving, the sensitivity and a coarse map."""
    kw = dict(wake=wake, airspeed_mps=airspeed_mps, altitude_m=altitude_m)
    # the ripple the band excludes: 1e-4 of saving for the lattice (its legs' ripple reaches 0.5 near the plane);
    # 1e-3 for the converged wake, whose residual table is within 0.2 % of the nseg-80 peak (1.1e-3): a smaller
    # wiggle is below what the model resolves (measured: a 4e-4 dip between the table's lateral nodes 0.90 and
    # 0.92 b at z = -0.01 and -0.02 b, the fine lattice's own 0.0125 b legs sampled at 0.02 b)
    from ...sim.formation import resolve_wake

    converged = bool(resolve_wake(wake).residual_table)  # by what the wake is, not by which constant it equals
    tol = 1e-3 if converged else 1e-4
    z_measured, rp = exclusion_band(x_b, tol=tol, **kw)
    # the task's band is the measured one: none for the converged wake (DEFAULT_Z_EXCLUSION_B); with the nseg-10
    # lattice the ripple measured 0.09 b and the task kept 0.1 b (LATTICE_Z_EXCLUSION_B; issue 23 part 6)
    z_ex = max(z_measured, DEFAULT_Z_EXCLUSION_B if converged else LATTICE_Z_EXCLUSION_B)
    search = dict(y_range_b=[0.5, 1.5], z_max_b=0.5, grid_step_b=0.05)
    opt = find_optimum(x_b, z_exclusion_b=z_ex, **search, **kw)
    port = find_optimum(x_b, z_exclusion_b=z_ex, side="port", **search, **kw)
    slot = tuple(round(v, slot_decimals) for v in opt.offset_b)
    thesis = slot_savings(np.array(THESIS_SLOT_B), **kw)
    slot_s = slot_savings(np.array(slot), **kw)
    _, wing_origin, tr, _ = _setup(wake, float(airspeed_mps), float(altitude_m))
    return {
        "_about": "Close-formation induced-drag map (formation_env.tasks.close_formation.optimum). Offsets "
                  "in spans b of the follower from the leader, leader's track frame (x forward, y starboard, "
                  "z down); saving = 1 - D_i(formation)/D_i(alone) from ELL (Kutta-Joukowski loads).",
        "parameters": {
            "x_b": x_b, "span_m": AEROSONDE_SPAN_M, "airspeed_mps": airspeed_mps, "altitude_m": altitude_m,
            "trim": {"alpha_rad": round(tr.alpha, 6), "theta_rad": round(tr.theta, 6), "psi_rad": round(tr.psi, 6)},
            "wake": dataclasses.asdict(wake), "wing_origin_body_m": _r(wing_origin, 6),
            "search": search, "ripple": {"y_b": [float(RIPPLE_Y_B[0]), float(RIPPLE_Y_B[-1]), 0.005],
                                         "tol": tol, "z_step_b": 0.01},
        },
        "z_exclusion_b": z_ex,
        "z_exclusion_measured_b": z_measured,
        "ripple": {"z_b": _r(rp["z_b"], 3), "excess_variation": _r(rp["excess_variation"]),
                   "n_local_maxima": np.asarray(rp["n_local_maxima"]).tolist(),
                   "peak_saving": _r(rp["peak_saving"], 4), "peak_y_b": _r(rp["peak_y_b"], 3)},
        "optimum": opt.as_dict(),
        "optimum_port": port.as_dict(),
        "scenario_slot_b": list(slot),
        "scenario_slot_saving": round(float(slot_s[1]), 5),
        "thesis_slot_b": list(THESIS_SLOT_B),
        "thesis_slot_saving": round(float(thesis[1]), 5),
        "thesis_slot_leader_saving": round(float(thesis[0]), 5),
        "sensitivity": _round_tree(sensitivity(opt.offset_b, delta_b=0.1, z_exclusion_b=z_ex, **kw)),
        "sensitivity_0p05": _round_tree(sensitivity(opt.offset_b, delta_b=0.05, z_exclusion_b=z_ex, **kw)),
        "map": saving_map(x_b, y_b, z_b, **kw).as_dict(),
    }


def write_cache(path=CACHE_PATH, *, overwrite: bool = True, **build_kw) -> Path:
    """Build the cache and write it atomically (``path`` default: the package's data file)."""
    return atomic_write_json(path, build_cache(**build_kw), overwrite=overwrite)


def load_cache(path=None) -> dict:
    """The cached map (the package's data file unless ``path``)."""
    if path is None:
        return json.loads(resources.files("formation_env.data").joinpath("close_formation_map.json").read_text())
    return json.loads(Path(path).read_text())


def optimum_saving(cache: dict | None = None) -> float:
    """The follower's induced-drag saving 1 - D_i(formation) / D_i(alone) at the optimum of the task's
    allowed region (the best slot at x = -2 b outside the excluded band, both sides) in calm air, from the
    cached map (``cache["optimum"]["saving"]``; the package's cache unless ``cache``): the denominator of a
    harvest ratio (a follower's mean saving over this). With today's cache (nseg 10, discrete legs,
    band |z| < 0.1 b, the lift-matched wing of the load-weighted coupling) 0.36657 at (-2, 0.9635, 0.1) b."""
    c = load_cache() if cache is None else cache
    return float(c["optimum"]["saving"])
