"""The body-axis lattice template of a formation make-up: every surface of every vehicle
flattened into the index arrays the compiled kernels consume. Built once per make-up."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry import Vehicle, mesh_vehicle

__all__ = ["LatticeTemplate", "build_template", "gradient_weights", "EVAL_POINTS", "ROTATIONAL_METHODS"]

EVAL_POINTS = ("control", "quarter_chord")
ROTATIONAL_METHODS = ("lstsq", "eq4_82", "eq5_10", "eq6_1")
# Body directions whose derivatives each finite-difference variant keeps (x=0, y=1, z=2):
# Eq. 4.82 all of them, Eq. 5.10 drops d/dz, Eq. 6.1 drops d/dx and d/dz.
_FD_DIRECTIONS = {"eq4_82": (0, 1, 2), "eq5_10": (0, 1), "eq6_1": (1,)}


@dataclass(frozen=True)
class LatticeTemplate:
    vehicles: tuple[Vehicle, ...]
    knot_x1_b: np.ndarray  # (K, 3)
    knot_x3_b: np.ndarray  # (K, 3)
    knot_vehicle: np.ndarray  # (K,)
    knot_surface: np.ndarray  # (K,)
    surface_origin_b: np.ndarray  # (S, 3)
    surface_vehicle: np.ndarray  # (S,)
    surface_knot_start: np.ndarray  # (S+1,)
    surface_panel_start: np.ndarray  # (S+1,)
    surface_core_scale: np.ndarray  # (S,) 1 / cos^2(sweep) for the Kurylowich radius
    panel_left_knot: np.ndarray  # (N,)
    panel_vehicle: np.ndarray  # (N,)
    panel_surface: np.ndarray  # (N,)
    control_b: np.ndarray  # (N, 3) 3/4-chord control points
    quarter_chord_b: np.ndarray  # (N, 3) 1/4-chord panel midpoints
    normal_b: np.ndarray  # (N, 3)
    vehicle_panel_start: np.ndarray  # (V+1,)
    cutoff_m: float  # Eq. 4.31: max_i 0.1 b_i / nseg_i

    @property
    def n_panels(self) -> int:
        return self.panel_left_knot.shape[0]

    @property
    def n_vehicles(self) -> int:
        return len(self.vehicles)


def build_template(vehicles: tuple[Vehicle, ...]) -> LatticeTemplate:
    x1, x3, kveh, ksurf = [], [], [], []
    origins, sveh, score, kstart, pstart = [], [], [], [0], [0]
    left, pveh, psurf, ctrl, qc, nrm, vstart = [], [], [], [], [], [], [0]
    cutoff = 0.0
    s_index = 0
    for v_index, vehicle in enumerate(vehicles):
        vm = mesh_vehicle(vehicle)
        for surface, sm in zip(vehicle.surfaces, vm.surfaces):
            n = surface.nseg
            k0 = kstart[-1]
            x1.append(sm.x1)
            x3.append(sm.x3)
            kveh += [v_index] * (n + 1)
            ksurf += [s_index] * (n + 1)
            origins.append(sm.origin)
            sveh.append(v_index)
            score.append(1.0 / np.cos(surface.sweep_rad) ** 2)
            left += list(range(k0, k0 + n))
            pveh += [v_index] * n
            psurf += [s_index] * n
            ctrl.append(sm.control)
            qc.append(sm.quarter_chord)
            nrm.append(sm.normal)
            kstart.append(k0 + n + 1)
            pstart.append(pstart[-1] + n)
            cutoff = max(cutoff, 0.1 * surface.span_m / n)
            s_index += 1
        vstart.append(pstart[-1])
    i64 = np.int64
    return LatticeTemplate(
        vehicles=tuple(vehicles),
        knot_x1_b=np.ascontiguousarray(np.concatenate(x1)),
        knot_x3_b=np.ascontiguousarray(np.concatenate(x3)),
        knot_vehicle=np.asarray(kveh, dtype=i64),
        knot_surface=np.asarray(ksurf, dtype=i64),
        surface_origin_b=np.ascontiguousarray(np.array(origins, dtype=float)),
        surface_vehicle=np.asarray(sveh, dtype=i64),
        surface_knot_start=np.asarray(kstart, dtype=i64),
        surface_panel_start=np.asarray(pstart, dtype=i64),
        surface_core_scale=np.asarray(score, dtype=float),
        panel_left_knot=np.asarray(left, dtype=i64),
        panel_vehicle=np.asarray(pveh, dtype=i64),
        panel_surface=np.asarray(psurf, dtype=i64),
        control_b=np.ascontiguousarray(np.concatenate(ctrl)),
        quarter_chord_b=np.ascontiguousarray(np.concatenate(qc)),
        normal_b=np.ascontiguousarray(np.concatenate(nrm)),
        vehicle_panel_start=np.asarray(vstart, dtype=i64),
        cutoff_m=float(cutoff),
    )


def gradient_weights(template: LatticeTemplate, eval_b: np.ndarray, method: str, span_tol: float) -> np.ndarray:
    """Weights w (N, 3) such that, for each vehicle, dV_a/dx_c = sum_i w[i, c] V_a(point i).

    ``lstsq``: least-squares linear fit of the point velocities over the directions the points
    actually span (principal extents >= span_tol times the largest); unspanned directions get a
    zero derivative, so nothing is ever divided by zero. For a flat unswept wing this keeps d/dy
    only; for a swept wing d/dx and d/dy (the thesis's Eq. 6.1 and 5.10 reductions respectively).

    ``eq4_82`` / ``eq5_10`` / ``eq6_1``: the thesis's averaged neighbour differences (Eq. 4.82) over
    consecutive points of each surface, keeping the derivative directions of that equation; pairs
    whose coordinate difference vanishes (e.g. across the root of a swept wing) are skipped.
    """
    weights = np.zeros((template.n_panels, 3))
    vs = template.vehicle_panel_start
    for v in range(template.n_vehicles):
        j0, j1 = vs[v], vs[v + 1]
        pts = eval_b[j0:j1]
        scale = max(np.ptp(pts, axis=0).max(), 1e-12)
        if method == "lstsq":
            d = pts - pts.mean(axis=0)
            m = d.T @ d
            lam, q = np.linalg.eigh(m)
            keep = lam > (span_tol**2) * lam.max() if lam.max() > 0 else np.zeros(3, bool)
            pinv = (q[:, keep] / lam[keep]) @ q[:, keep].T
            weights[j0:j1] = d @ pinv
        else:
            directions = _FD_DIRECTIONS[method]
            pairs = []
            for s in np.unique(template.panel_surface[j0:j1]):
                idx = np.nonzero(template.panel_surface == s)[0]
                pairs += list(zip(idx[:-1], idx[1:]))
            for c in directions:
                valid = [(a, b) for a, b in pairs if abs(eval_b[b, c] - eval_b[a, c]) > 1e-9 * scale]
                for a, b in valid:
                    w = 1.0 / ((eval_b[b, c] - eval_b[a, c]) * len(valid))
                    weights[b, c] += w
                    weights[a, c] -= w
    return np.ascontiguousarray(weights)
