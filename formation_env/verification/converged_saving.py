"""The measurements of docs/ell.md "Converged saving" (issue 23 part 6): the follower's saving and effective
winds over the acceptance grid (x = -2 b, y 0.70..1.20 b, z -0.10..0.30 b, 0.02 b steps) for a lattice
configuration, and their errors against a reference map.

Both aircraft fly the trim (same attitude, still air; optionally the follower rolled or both at a higher
alpha), the ELL is the energy tasks' lift-matched wing (:class:`~formation_env.sim.formation.WakeConfig` with
``coupling="load_weighted"``), the saving comes from the env's compiled path
(:func:`formation_env.wake.benefit.induced_drag_saving_one`) and the winds from
:func:`formation_env.wake.coupling.coupled_wind` (both couplings, the follower's, NED).

``formation-env verify --converged-saving`` prints the table of docs/ell.md for the lattices
this checkout has (nseg 10 with and without the span correction, with the sheet law, with the residual table
of pairs, nseg 40 and 160 against
nseg 80); the residual table's :func:`residual_table_errors` with the sheet law as its base (e.g.
``residual_table_errors(WakeConfig(sheet=True, span_correction=True), conditions=({}, {"roll_deg": 2.0},
{"x_b": -2.5}))``).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from ..constants import AEROSONDE_SPAN_M

__all__ = ["GRID_Y_B", "GRID_Z_B", "follower_maps", "local_maxima", "lateral_maxima", "map_errors",
           "residual_table_errors", "echelon_savings", "pairwise_residual_errors", "print_table"]

GRID_Y_B = np.round(np.arange(0.70, 1.20 + 1e-9, 0.02), 6)
GRID_Z_B = np.round(np.arange(-0.10, 0.30 + 1e-9, 0.02), 6)


def follower_maps(wake=None, *, x_b: float = -2.0, y_b=GRID_Y_B, z_b=GRID_Z_B, roll_deg: float = 0.0,
                  dalpha_deg: float = 0.0, airspeed_mps: float = 25.0, altitude_m: float = 1000.0) -> dict:
    """The follower's saving (ny, nz) and winds (ny, nz, 3) m/s NED, ``load_weighted`` and
    ``effective_wind``, over ``y_b`` x ``z_b`` at ``x_b`` (spans). ``wake`` a WakeConfig (None: the energy
    tasks' nseg-10 lattice; its coupling is set to load_weighted, the lift-matched wing); ``roll_deg`` added
    to the follower's roll, ``dalpha_deg`` to both aircraft's pitch and alpha."""
    from ..aircraft import AEROSONDE, trim
    from ..sim.formation import WakeConfig, ell_state_from_aircraft, wake_model_for, wing_origin_body
    from ..wake.arrays import wake_arrays
    from ..wake.benefit import induced_drag_saving_one
    from ..wake.coupling import coupled_wind, coupling_arrays
    from ..wake.loads import isolated_model

    wake = dataclasses.replace(WakeConfig() if wake is None else wake, coupling="load_weighted")
    model = wake_model_for(wake, 2)
    origin = wing_origin_body()
    arrays = wake_arrays(model, origin)
    alone = wake_arrays(isolated_model(model.vehicles[0], model.core, model.eval_points, model.rotational,
                                       model.kinematic_viscosity, model.viscous_aic), origin)
    couplings = {name: coupling_arrays(model, name, AEROSONDE) for name in ("load_weighted", "effective_wind")}
    y, z = np.atleast_1d(np.asarray(y_b, float)), np.atleast_1d(np.asarray(z_b, float))
    yy, zz = np.meshgrid(y, z, indexing="ij")
    off = np.stack([np.full(yy.shape, float(x_b)), yy, zz], -1).reshape(-1, 3)
    tr = trim(airspeed_mps, altitude_m)
    st = np.repeat(np.asarray(tr.state, float).reshape(1, 1, -1), 2, axis=1).repeat(len(off), 0)
    st[:, 1, 10:13] += off * AEROSONDE_SPAN_M
    ell = ell_state_from_aircraft(st, np.zeros((len(off), 2, 3)), origin)
    euler, alpha = ell.euler_rad.copy(), ell.alpha_rad.copy()
    euler[:, 1, 0] += np.radians(roll_deg)
    euler[:, :, 1] += np.radians(dalpha_deg)
    alpha += np.radians(dalpha_deg)
    n = model.n_panels
    saving = np.empty((len(off), 2))
    winds = {name: np.empty((len(off), 3)) for name in couplings}
    gamma, vpts = np.empty(n), np.empty((n, 3))
    for i in range(len(off)):
        args = [np.ascontiguousarray(a[i]) for a in (ell.position_ned, euler, ell.airspeed_mps, alpha, ell.beta_rad)]
        for name, c in couplings.items():
            out = [np.empty((2, 3)) for _ in range(4)]
            coupled_wind(arrays, c, *args, gamma, vpts, *out)
            winds[name][i] = out[0][1]
        induced_drag_saving_one(arrays, alone, *args, gamma, saving[i])
    return {"y_b": y, "z_b": z, "saving": saving[:, 1].reshape(yy.shape),
            **{name: w.reshape(yy.shape + (3,)) for name, w in winds.items()}}


def local_maxima(a: np.ndarray) -> int:
    """Grid points above all their (up to 8) neighbours."""
    p = np.pad(np.asarray(a, float), 1, constant_values=-np.inf)
    count = 0
    for i in range(a.shape[0]):
        for j in range(a.shape[1]):
            nb = p[i:i + 3, j:j + 3].copy()
            nb[1, 1] = -np.inf
            count += int(a[i, j] > nb.max())
    return count


def lateral_maxima(a: np.ndarray) -> int:
    """The most interior local maxima on any lateral profile (a[:, j])."""
    return max(int(np.sum((a[1:-1, j] > a[:-2, j]) & (a[1:-1, j] > a[2:, j]))) for j in range(a.shape[1]))


def map_errors(maps: dict, reference: dict) -> dict:
    """Largest |maps - reference| in units of the reference's peak (saving) or largest |component| (winds,
    components y and z), local maxima, the peak and where, and the saving's error off the plane (|z| >= 0.1 b)."""
    s, r = maps["saving"], reference["saving"]
    err = np.abs(s - r) / r.max()
    off = np.abs(maps["z_b"]) >= 0.1 - 1e-9
    i, j = np.unravel_index(np.argmax(s), s.shape)
    out = {"saving": float(err.max()), "saving_off_plane": float(err[:, off].max()) if off.any() else float("nan"),
           "peak": float(s[i, j]), "peak_y_b": float(maps["y_b"][i]), "peak_z_b": float(maps["z_b"][j]),
           "local_maxima": local_maxima(s), "lateral_maxima": lateral_maxima(s)}
    for name in ("load_weighted", "effective_wind"):
        for c, axis in ((1, "y"), (2, "z")):
            out[f"{name}_{axis}"] = float(np.abs(maps[name][..., c] - reference[name][..., c]).max()
                                          / np.abs(reference[name][..., c]).max())
    return out


def residual_table_errors(base, reference=None, *, step_b: float = 0.02, method: str = "cubic",
                          conditions=({},)) -> list[dict]:
    """A residual table measured, not built: reference (WakeConfig, default nseg 80) minus ``base`` (a
    WakeConfig) tabulated at x = -2 b on a grid offset by half a step from the acceptance grid (y 0.6-1.3 b,
    z -0.2-0.4 b, ``step_b``), interpolated (scipy ``method``) onto the acceptance grid and added to ``base``'s
    maps at each of ``conditions`` (:func:`follower_maps` keywords: x_b, roll_deg, dalpha_deg); returns
    :func:`map_errors` of the corrected maps against the reference at the same condition, per condition."""
    from scipy.interpolate import RegularGridInterpolator

    from ..sim.formation import WakeConfig

    reference = WakeConfig(nseg=80) if reference is None else reference
    ty = np.round(np.arange(0.6 + step_b / 2, 1.3, step_b), 6)
    tz = np.round(np.arange(-0.2 + step_b / 2, 0.4, step_b), 6)
    fine, coarse = follower_maps(reference, y_b=ty, z_b=tz), follower_maps(base, y_b=ty, z_b=tz)
    pts = np.stack(np.meshgrid(GRID_Y_B, GRID_Z_B, indexing="ij"), -1)
    out = []
    for cond in conditions:
        ref, maps = follower_maps(reference, **cond), follower_maps(base, **cond)
        for key in ("saving", "load_weighted", "effective_wind"):
            maps[key] = maps[key] + RegularGridInterpolator((ty, tz), fine[key] - coarse[key], method=method)(pts)
        out.append(map_errors(maps, ref))
    return out


def echelon_savings(wake, offsets_b, airspeed_mps: float = 25.0, altitude_m: float = 1000.0) -> np.ndarray:
    """Induced-drag saving (V,) of each aircraft of a formation at ``offsets_b`` ((V, 3) spans, NED, from the
    first aircraft's CG), every aircraft at the trim (same attitude, still air), the lift-matched ELL of ``wake``
    (a WakeConfig; its span correction applied): :func:`formation_env.wake.loads.formation_benefit`."""
    from ..aircraft import AEROSONDE, trim
    from ..sim.formation import ell_state_from_aircraft, wing_origin_body
    from ..wake.loads import formation_benefit

    wake = dataclasses.replace(wake, coupling="load_weighted")
    offs = np.asarray(offsets_b, float).reshape(-1, 3)
    st = np.repeat(np.asarray(trim(airspeed_mps, altitude_m).state, float).reshape(1, 1, -1), len(offs), axis=1)
    st[0, :, 10:13] += offs * AEROSONDE_SPAN_M
    state = ell_state_from_aircraft(st, np.zeros((1, len(offs), 3)), wing_origin_body(AEROSONDE))
    return formation_benefit(_model(wake, len(offs)), state)["induced_drag_saving"][0]


@functools.lru_cache(maxsize=16)
def _model(wake, n_vehicles: int):
    """The ELL of ``n_vehicles`` as ``wake`` configures it, built once per configuration (the nseg-80 lattice's
    static AIC is the costly part)."""
    from ..sim.formation import wake_model_for

    return wake_model_for(wake, n_vehicles)


def pairwise_residual_errors(base=None, reference=None, *, trials: int = 12, seed: int = 5) -> list[dict]:
    """Whether a residual table of *pairs* can correct a formation of more: a 3-UAV echelon near the wake plane
    (followers at (-2, 0.92, 0) and (-4, 1.84, 0) b from the leader, each step jittered by U(-0.06, 0.06) b
    laterally and U(-0.04, 0.06) b vertically), its savings with ``base`` (default: nseg 10, sheet law and span
    correction) corrected by the sum over ordered pairs (source j, receiver i) of the pair's residual
    (``reference`` minus ``base``, each pair alone at its relative position), against ``reference`` (default
    nseg 80, the thesis law) for the three together. Per trial: the largest error in units of the reference's
    largest saving, ``pairwise`` (corrected), ``base`` (uncorrected) and ``thesis`` (nseg 10, thesis legs)."""
    import itertools

    from ..sim.formation import WakeConfig

    base = WakeConfig(sheet=True, span_correction=True) if base is None else base
    reference = WakeConfig(nseg=80) if reference is None else reference
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(trials):
        dy = rng.uniform(-0.06, 0.06, 2)
        dz = rng.uniform(-0.04, 0.06, 2)
        offs = np.array([[0.0, 0.0, 0.0], [-2.0, 0.92 + dy[0], dz[0]], [-4.0, 1.84 + dy[0] + dy[1], dz[0] + dz[1]]])
        ref, b = echelon_savings(reference, offs), echelon_savings(base, offs)
        corrected = b.copy()
        for i, j in itertools.permutations(range(len(offs)), 2):
            pair = offs[[j, i]]  # the source first, the receiver second
            corrected[i] += echelon_savings(reference, pair)[1] - echelon_savings(base, pair)[1]
        peak = ref.max()
        out.append({"offsets_b": offs, "reference": ref, "pairwise": float(np.abs(corrected - ref).max() / peak),
                    "base": float(np.abs(b - ref).max() / peak),
                    "thesis": float(np.abs(echelon_savings(WakeConfig(), offs) - ref).max() / peak)})
    return out


def print_table(log=print) -> None:
    """``formation-env verify --converged-saving``: the table of docs/model/ell.md, one ``log`` line per lattice
    configuration as it is measured."""
    from ..sim.formation import WakeConfig

    reference = follower_maps(WakeConfig(nseg=80))
    cases = {"nseg 10": WakeConfig(), "nseg 10 + span correction": WakeConfig(span_correction=True),
             "nseg 10, sheet law": WakeConfig(sheet=True),
             "nseg 10, sheet law + span corr.": WakeConfig(sheet=True, span_correction=True),
             "nseg 10, sheet + span + residual table": WakeConfig(sheet=True, span_correction=True, residual_table=True),
             "nseg 40": WakeConfig(nseg=40), "nseg 160": WakeConfig(nseg=160)}
    log("against nseg 80; % of the reference's peak (saving) or largest |component| (winds y / z)")
    for label, cfg in cases.items():
        e = map_errors(follower_maps(cfg), reference)
        log(f"{label:38s} saving {100 * e['saving']:5.1f} % (|z| >= 0.1 b {100 * e['saving_off_plane']:4.1f} %), "
            f"peak {e['peak']:.3f} at ({e['peak_y_b']:.2f}, {e['peak_z_b']:.2f}) b, maxima {e['local_maxima']} / "
            f"{e['lateral_maxima']}; load_weighted {100 * e['load_weighted_y']:.1f} / {100 * e['load_weighted_z']:.1f} %, "
            f"effective_wind {100 * e['effective_wind_y']:.1f} / {100 * e['effective_wind_z']:.1f} %")

