"""Wake surfing in a crosswind: the follower's induced-drag optimum within the ``wake_surfing`` safe box.

Scenario (:data:`formation_env.scenarios.SCENARIOS` ``["wake_surfing"]``): a leader and one follower;
the follower's set-point stays at x = -2 b along the track and may move in y (starboard) and z (down)
within the safe box ``safe_box_b`` (spans, b = 2.9 m, relative to the leader, in its *track* frame: x
along the demanded ground track, y to starboard of it, z down). The reward pays the follower's ELL
induced-drag saving ``1 - D_i(formation) / D_i(alone)``; this module gives the reference the policy is
judged against: the best saving the follower could have at each instant.

Method. ELL's wake trails along each vehicle's air-relative velocity
(:func:`formation_env.wake.posing.posed_lattice`), and a steady, uniform wind moves the whole air mass:
seen from the air, a formation in a steady wind is the calm-air formation. Only the frame changes. The
leader flies its ground track chi with its air-relative velocity at heading psi = chi - c, where the
crab angle c (rad, positive when the wind blows toward starboard of the track) satisfies

    sin c = w_cross / V_air,   w_cross = -w_n sin chi + w_e cos chi   (m/s; V_air the airspeed, m/s).

(Wind toward the east, track north: the leader heads a little west of north, c > 0, and its wake
trails downwind, to starboard of the track.) A follower at track-frame offset o = (x, y, z) sits at

    R(c) o = (x cos c - y sin c,  x sin c + y cos c,  z)

in the leader's air-velocity ("heading") frame, so its saving is the calm-air saving there:
:func:`saving_in_crosswind` evaluates :func:`formation_env.tasks.close_formation.optimum.slot_savings`
(the simulator's own ELL model, both aircraft at ``trim(25 m/s, 1000 m)``) at R(c) o. To first order
the optimum's lateral offset moves to y = (y_calm + 2 sin c) / cos c for x = -2 b (the wake leaving the
leader at angle c reaches 2 b downstream 2 sin c spans downwind); the x change in the heading frame
(x cos c - y sin c) is taken into account exactly.

:func:`optimum_in_box` maximises the follower's saving over (y, z) in the box at fixed x: a coarse grid,
then a bounded L-BFGS-B (forward-difference gradients, each a batched ELL call), on the task's converged wake
(:data:`formation_env.tasks.close_formation.optimum.TASK_WAKE`: smooth and single-peaked, no excluded band; the
lattice-era search stopped 0.1 b below the wake plane, out of the nseg-10 lattice's artefact band). The optimum
lies on the leader's wake plane, inside the box (0.561 at y = 0.926 b, z = 0.002 b under crab 0; under
+-13 deg of crab the same saving to 1e-3 at y = 0.49 / 1.36 b). :func:`build_cache` tabulates
the optimum for crab angles -15..15 deg (1 deg steps; the scenario's crosswinds of up to 5 m/s at
23-27 m/s give |c| < 13 deg) and a saving map at c = 0; :func:`reference_optimum` interpolates it and
:func:`episode_reference` follows an episode's wind, demanded track and airspeed.

Assumptions: a steady, uniform wind (turbulence is ignored), both aircraft in steady level flight at
the trim attitude (the leader's turn and speed change enter only through its track and airspeed at
each instant; the bank in a turn and the curved wake are ignored), the ELL model's saving at 25 m/s.

``formation-env data optimum wake_surfing`` rewrites the cache
(``formation_env/data/wake_surfing_optimum.json``).
"""

from __future__ import annotations

import json
import math
from functools import lru_cache
from importlib import resources
from pathlib import Path

import numpy as np

from ...io import atomic_write_json
from ...scenarios.definitions import AEROSONDE_SPAN_M, get_scenario
from ..close_formation.optimum import NOMINAL_FUEL_KG, TASK_WAKE, slot_savings

__all__ = ["SAFE_BOX_B", "X_B", "CRAB_MAX_DEG", "CACHE_PATH", "crab_angle_rad", "rotate_track_to_heading",
           "saving_in_crosswind", "optimum_in_box", "build_cache", "write_cache", "load_cache",
           "reference_optimum", "episode_reference", "optimum_saving", "leader_factor"]

SAFE_BOX_B = get_scenario("wake_surfing").safe_box_b  # ((x_lo, x_hi), (y_lo, y_hi), (z_lo, z_hi)) spans
X_B = -2.0  # the follower's along-track set-point, spans
CRAB_MAX_DEG = 15.0  # the cache's crab grid: -15..15 deg
CRAB_STEP_DEG = 1.0
CACHE_PATH = Path(__file__).resolve().parents[2] / "data" / "wake_surfing_optimum.json"
MAP_Y_B = np.round(np.arange(0.0, 2.0 + 1e-9, 0.05), 6)  # the cached saving map's grid (crab 0)
MAP_Z_B = np.round(np.arange(-0.4, 0.8 + 1e-9, 0.025), 6)
_SIDES = ("starboard", "port")
_FD_STEP_B = 1e-6  # finite-difference step of the optimiser's gradient, spans


def crab_angle_rad(wind_ned, track_rad, airspeed_mps) -> np.ndarray:
    """Crab angle c (rad) of an aircraft holding ground track ``track_rad`` at ``airspeed_mps``.

    wind_ned (..., 3): steady wind, NED, m/s (the velocity of the air: (0, 4, 0) blows toward the
    east); track_rad (...): ground track, rad from north, positive toward east; airspeed_mps (...):
    airspeed, m/s. All broadcast together. ``sin c = w_cross / V_air`` with w_cross the wind component
    toward starboard of the track; c > 0 when the wind blows toward starboard (the aircraft then heads
    c to port of its track: heading = track - c). Raises ValueError for non-finite input, a
    non-positive airspeed or a crosswind at least as fast as the airspeed.
    """
    w = np.asarray(wind_ned, float)
    chi = np.asarray(track_rad, float)
    va = np.asarray(airspeed_mps, float)
    if w.ndim < 1 or w.shape[-1] != 3:
        raise ValueError(f"crab_angle_rad: wind_ned must have shape (..., 3), got {w.shape}")
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(chi)) and np.all(np.isfinite(va))):
        raise ValueError("crab_angle_rad: wind_ned, track_rad and airspeed_mps must be finite")
    if np.any(va <= 0.0):
        raise ValueError(f"crab_angle_rad: airspeed_mps must be positive, got min {float(np.min(va))}")
    cross = -w[..., 0] * np.sin(chi) + w[..., 1] * np.cos(chi)
    ratio = cross / va
    if np.any(np.abs(ratio) >= 1.0):
        raise ValueError(f"crab_angle_rad: crosswind {float(np.max(np.abs(cross)))} m/s at least the airspeed; "
                         "the track cannot be held")
    return np.arcsin(ratio)


def rotate_track_to_heading(offsets_b, crab_rad) -> np.ndarray:
    """Track-frame offsets (..., 3) (x along the track, y starboard, z down; any length unit) as
    components in the air-velocity (heading) frame of a leader crabbing by ``crab_rad`` (broadcast
    over the leading axes): ``(x cos c - y sin c, x sin c + y cos c, z)``."""
    o = np.asarray(offsets_b, float)
    c = np.asarray(crab_rad, float)
    cc, sc = np.cos(c), np.sin(c)
    x, y = o[..., 0], o[..., 1]
    return np.stack(np.broadcast_arrays(x * cc - y * sc, x * sc + y * cc, o[..., 2]), axis=-1)


def saving_in_crosswind(offsets_b, crab_rad, **model_kw) -> np.ndarray:
    """The follower's induced-drag saving (...) at track-frame offsets ``offsets_b`` (..., 3), spans,
    from the leader crabbing by ``crab_rad`` (rad; scalar or broadcast with the offsets' leading axes):
    the calm-air :func:`~formation_env.tasks.close_formation.optimum.slot_savings` of the rotated
    offsets (``model_kw`` go there: ``airspeed_mps``, ``altitude_m``, ``wake``)."""
    o = np.asarray(offsets_b, float)
    c = np.asarray(crab_rad, float)
    if o.ndim < 1 or o.shape[-1] != 3 or not np.all(np.isfinite(o)) or not np.all(np.isfinite(c)):
        raise ValueError(f"saving_in_crosswind: need finite offsets_b (..., 3) and crab_rad, got shape {o.shape}")
    model_kw.setdefault("wake", TASK_WAKE)  # the task's wake (formation_env.tasks.wake_surfing: converged)
    return slot_savings(rotate_track_to_heading(o, c), **model_kw)[..., 1]


def optimum_in_box(crab_rad: float, *, box_b=SAFE_BOX_B, x_b: float = X_B, side: str = "starboard",
                   z_exclusion_b: float | None = None, grid_step_b: float = 0.1, **model_kw) -> dict:
    """The follower slot (x fixed at ``x_b``) with the largest saving under crab angle ``crab_rad``.

    box_b: ((x_lo, x_hi), (y_lo, y_hi), (z_lo, z_hi)) spans, track frame (default the scenario's
    safe box); the search covers y in (y_lo, y_hi) (mirrored to (-y_hi, -y_lo) for ``side="port"``)
    and z in (z_lo, z_hi) (z down, positive below the leader), or (max(z_lo, z_exclusion_b), z_hi) with an
    excluded band (None, the default: none; the lattice's artefact band was |z| < 0.1 b, which a lattice-wake
    search passes here). A grid of ``grid_step_b`` picks the start of a bounded L-BFGS-B.
    Returns ``{"offset_b": [x, y, z], "saving": s, "n_evaluations": slots evaluated}``.
    """
    from scipy.optimize import minimize

    if side not in _SIDES:
        raise ValueError(f"optimum_in_box: side must be one of {_SIDES}, got {side!r}")
    c = float(crab_rad)
    if not math.isfinite(c) or abs(c) >= math.pi / 2:
        raise ValueError(f"optimum_in_box: crab_rad must be finite and below pi/2 in size, got {crab_rad!r}")
    (xlo, xhi), (ylo, yhi), (zlo, zhi) = ((float(a), float(b)) for a, b in box_b)
    if not xlo <= x_b <= xhi:
        raise ValueError(f"optimum_in_box: x_b = {x_b} outside the box's x range ({xlo}, {xhi})")
    if z_exclusion_b is not None:
        zlo = max(zlo, float(z_exclusion_b))
    if not (ylo < yhi and zlo < zhi):
        raise ValueError(f"optimum_in_box: empty search box y ({ylo}, {yhi}), z ({zlo}, {zhi})")
    if side == "port":
        ylo, yhi = -yhi, -ylo
    n_eval = 0

    def savings(y, z):
        nonlocal n_eval
        y, z = np.broadcast_arrays(np.asarray(y, float), np.asarray(z, float))
        n_eval += y.size
        return saving_in_crosswind(np.stack([np.full(y.shape, float(x_b)), y, z], axis=-1), c, **model_kw)

    gy = np.linspace(ylo, yhi, max(2, int(round((yhi - ylo) / grid_step_b)) + 1))
    gz = np.linspace(zlo, zhi, max(2, int(round((zhi - zlo) / grid_step_b)) + 1))
    yy, zz = np.meshgrid(gy, gz, indexing="ij")
    s = savings(yy, zz)
    k = np.unravel_index(np.argmax(s), s.shape)

    def neg_and_grad(p):  # value and forward-difference gradient in one batched call
        hy = _FD_STEP_B if p[0] + _FD_STEP_B <= yhi else -_FD_STEP_B
        hz = _FD_STEP_B if p[1] + _FD_STEP_B <= zhi else -_FD_STEP_B
        f = savings([p[0], p[0] + hy, p[0]], [p[1], p[1], p[1] + hz])
        return -f[0], -np.array([(f[1] - f[0]) / hy, (f[2] - f[0]) / hz])

    res = minimize(neg_and_grad, np.array([yy[k], zz[k]]), jac=True, method="L-BFGS-B",
                   bounds=[(ylo, yhi), (zlo, zhi)], options={"ftol": 1e-12, "gtol": 1e-7})
    if -res.fun >= s[k]:
        y, z, best = float(res.x[0]), float(res.x[1]), float(-res.fun)
    else:
        y, z, best = float(yy[k]), float(zz[k]), float(s[k])
    return {"offset_b": [float(x_b), y, z], "saving": best, "n_evaluations": int(n_eval)}


def _r(v, d=5):
    return np.round(np.asarray(v, float), d).tolist()


def build_cache(*, airspeed_mps: float = 25.0, altitude_m: float = 1000.0, grid_step_b: float = 0.1) -> dict:
    """The cached table: :func:`optimum_in_box` (starboard, the scenario's box, x = -2 b) for crab
    angles -15..15 deg in 1 deg steps, the first-order estimate (y_calm + 2 sin c) / cos c beside it,
    and the follower's saving map over the box at crab 0 (y 0..2 b step 0.05, z -0.4..0.8 b step
    0.025). Numbers rounded to 5 digits."""
    kw = dict(airspeed_mps=airspeed_mps, altitude_m=altitude_m)
    crab_deg = np.round(np.arange(-CRAB_MAX_DEG, CRAB_MAX_DEG + 1e-9, CRAB_STEP_DEG), 6)
    opts = [optimum_in_box(math.radians(d), grid_step_b=grid_step_b, **kw) for d in crab_deg]
    y0 = next(o["offset_b"][1] for o, d in zip(opts, crab_deg) if d == 0.0)
    sc = np.sin(np.radians(crab_deg))
    first_order = (y0 - X_B * sc) / np.cos(np.radians(crab_deg))
    yy, zz = np.meshgrid(MAP_Y_B, MAP_Z_B, indexing="ij")
    smap = saving_in_crosswind(np.stack([np.full_like(yy, X_B), yy, zz], axis=-1), 0.0, **kw)
    return {
        "_about": "Wake-surfing reference (formation_env.tasks.wake_surfing.optimum): the follower's best "
                  "induced-drag saving (ELL, 1 - D_i formation / D_i alone) in the wake_surfing safe box at "
                  "x = -2 spans behind the leader, as a function of the leader's crab angle c (deg, positive "
                  "when the wind blows toward starboard of the track; sin c = crosswind / airspeed). Offsets "
                  "in spans b of the follower from the leader, leader's track frame (x along the ground "
                  "track, y starboard, z down). Saving = calm-air saving at the offset rotated into the "
                  "leader's air-velocity frame by c. 'map': the follower's saving over the box at c = 0.",
        "parameters": {"x_b": X_B, "box_b": [list(b) for b in SAFE_BOX_B], "z_exclusion_b": None,
                       "wake_fidelity": "converged",
                       "span_m": AEROSONDE_SPAN_M, "airspeed_mps": airspeed_mps, "altitude_m": altitude_m,
                       "grid_step_b": grid_step_b, "side": "starboard",
                       "crab_deg": [-CRAB_MAX_DEG, CRAB_MAX_DEG, CRAB_STEP_DEG]},
        "crab_deg": crab_deg.tolist(),
        "optimum": {"y_b": _r([o["offset_b"][1] for o in opts]), "z_b": _r([o["offset_b"][2] for o in opts]),
                    "saving": _r([o["saving"] for o in opts]),
                    "n_evaluations": [o["n_evaluations"] for o in opts]},
        "first_order_y_b": _r(first_order),
        "map": {"crab_deg": 0.0, "x_b": X_B, "y_b": _r(MAP_Y_B), "z_b": _r(MAP_Z_B),
                "follower_saving": _r(smap)},
    }


def write_cache(path=CACHE_PATH, *, overwrite: bool = True, **build_kw) -> Path:
    """Build the cache (:func:`build_cache`) and write it atomically (``path`` default: the package's
    data file; an existing file is replaced only with ``overwrite``)."""
    return atomic_write_json(path, build_cache(**build_kw), overwrite=overwrite)


def load_cache(path=None) -> dict:
    """The cached table (the package's data file unless ``path``)."""
    if path is None:
        return _packaged_cache()
    return json.loads(Path(path).read_text())


@lru_cache(maxsize=1)
def _packaged_cache() -> dict:
    return json.loads(resources.files("formation_env.data").joinpath("wake_surfing_optimum.json").read_text())


def reference_optimum(crab_rad, *, cache: dict | None = None):
    """The follower's optimum under crab angle ``crab_rad`` (rad, scalar or array), linearly
    interpolated over the cache's 1-deg grid: ``(y_b, z_b, saving)`` arrays of ``crab_rad``'s shape
    (spans, track frame; x is -2 b). Raises ValueError, naming the value, for a non-finite crab angle or
    one beyond +-15 deg (the cache's range)."""
    c = np.asarray(crab_rad, float)
    d = np.degrees(c)
    bad = ~np.isfinite(d) | (np.abs(d) > CRAB_MAX_DEG + 1e-9)
    if np.any(bad):
        v = float(c[bad][0]) if c.ndim else float(c)
        raise ValueError(f"reference_optimum: crab angle {v!r} rad ({math.degrees(v) if math.isfinite(v) else v} "
                         f"deg) outside the cached range +-{CRAB_MAX_DEG} deg")
    t = load_cache() if cache is None else cache
    grid = np.asarray(t["crab_deg"], float)
    o = t["optimum"]
    return tuple(np.interp(d, grid, np.asarray(o[k], float)) for k in ("y_b", "z_b", "saving"))


def leader_factor(crab_rad: float, airspeed_mps: float, leader_fuel_kg: float,
                  follower_fuel_kg: float = NOMINAL_FUEL_KG) -> float:
    """The follower's saving at the reference optimum of crab angle ``crab_rad`` with the pair trimmed at
    ``airspeed_mps`` (m/s) and the leader carrying ``leader_fuel_kg``, the follower ``follower_fuel_kg`` of fuel (kg;
    AeroSim mass = 8.5 kg + fuel), over the same with the cache's pair (25 m/s, the trim's 2 kg each): the factor on
    the cached saving for a leader of another weight and speed.

    Why a factor at the cached position: the leader's weight scales its circulation (its lift is its weight), hence
    the upwash it leaves, and on the converged wake it moves the optimum only a little inboard, where the saving is
    flat across the track (measured at crab 0: 0.045 b with a 13.5 kg leader, 0.002 b with 9.0 kg; the saving at the
    cached position 0.729 against the fresh optimum's 0.732 and 0.4800 against 0.4801), so the factor's reference
    is at most 0.4 % below the drawn pair's optimum (the nseg-10 lattice's optimum stayed within 0.002 b). The factor
    is not the weight ratio: the follower's induced drag in formation has a term in the square of the leader's
    circulation (its own loads respond to the upwash), so a 13.5 kg leader gives 1.300 x the saving of a 10.5 kg
    one, not 1.286 x, a 9.0 kg one 0.856 x (converged wake at 25 m/s, crab 0). The airspeed enters through the trims'
    attitudes (~1e-3 over 22-28 m/s). Two ELL evaluations (plus the two trims the first time)."""
    c = float(crab_rad)
    y, z, _ = reference_optimum(c)
    o = np.array([X_B, float(y), float(z)])
    num = saving_in_crosswind(o, c, airspeed_mps=float(airspeed_mps), leader_fuel_kg=float(leader_fuel_kg),
                              follower_fuel_kg=float(follower_fuel_kg))
    den = saving_in_crosswind(o, c)
    return float(num / den)


def episode_reference(wind_ned, track_rad, airspeed_mps, *, leader_fuel_kg: float | None = None,
                      follower_fuel_kg: float = NOMINAL_FUEL_KG, cache: dict | None = None) -> dict:
    """The reference optimum along an episode.

    wind_ned (3,) (or (T, 3)): the steady wind, NED, m/s; track_rad (T,): the leader's demanded
    ground track, rad from north; airspeed_mps (T,): its airspeed, m/s. Returns ``crab_rad``, ``y_b``,
    ``z_b``, ``saving`` (T,) (each instant's crab angle and the optimum under it, spans, track frame)
    and ``mean_saving`` (their mean over the samples). With ``leader_fuel_kg`` (a leader of drawn weight
    and speed, the randomised-leader variant) the savings are multiplied by :func:`leader_factor` at the
    episode's mean crab angle and mean airspeed (None: the cache's pair, factor 1); ``factor`` says which."""
    chi = np.atleast_1d(np.asarray(track_rad, float))
    va = np.broadcast_to(np.asarray(airspeed_mps, float), chi.shape)
    c = crab_angle_rad(np.asarray(wind_ned, float), chi, va)
    y, z, s = reference_optimum(c, cache=cache)
    k = 1.0
    if leader_fuel_kg is not None:
        k = leader_factor(float(np.mean(c)), float(np.mean(va)), leader_fuel_kg, follower_fuel_kg)
        s = s * k
    return {"crab_rad": c, "y_b": y, "z_b": z, "saving": s, "mean_saving": float(np.mean(s)), "factor": k}


def optimum_saving(cache: dict | None = None) -> float:
    """The follower's induced-drag saving at the optimum of the safe box (x = -2 b) in calm air (crab
    angle 0), from the cached table (the package's cache unless ``cache``): the denominator of a harvest
    ratio. With today's cache (the converged wake) 0.5608 at (-2, 0.926, 0.002) b, on the leader's wake plane."""
    t = load_cache() if cache is None else cache
    grid = [float(d) for d in t["crab_deg"]]
    if 0.0 not in grid:
        raise ValueError(f"optimum_saving: the cache's crab grid {grid[0]}..{grid[-1]} deg has no 0 deg entry")
    return float(t["optimum"]["saving"][grid.index(0.0)])
