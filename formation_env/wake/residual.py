"""The residual table of pairs: the energy tasks' ELL saving and winds converged at the cost of the coarse
lattice (issue 23 part 6; docs/ell.md, "Converged saving").

With 10 horseshoes per wing the follower's saving and induced wind near the leader's wake plane are lattice
artefacts; the sheet law (:func:`formation_env.wake.biot_savart.leg_sheet`) with the span-efficiency
correction (:mod:`formation_env.wake.converged`) removes the ripple but stays 12 % of the peak off a fine
(nseg 80) solve on the plane. What is left is smooth on the scale of the leader's viscous core and, measured,
*pairwise*: in a 3-UAV echelon the six ordered pairs' own residuals add up to the three together's within
0.5 % of the largest saving (``converged_saving.pairwise_residual_errors``). So the correction is a table of
one pair's residual

    r(x, y, z, phi) = (nseg 80, thesis legs) - (nseg 10, sheet law, span correction)

of the *receiving* aircraft, tabulated in its position relative to the *source* aircraft and their relative
roll, and a formation adds r over its ordered pairs (source j, receiver i).

The pair frame (where the table lives): the source's heading axes rolled with the source (x forward, y to
starboard, z down; the source's pitch is not applied: the table is built with both aircraft at the trim
pitch); the position is the receiver's wing origin relative to the source's, in spans; ``phi`` the receiver's
roll minus the source's, rad. The table holds y >= 0: the pair mirrored in y (y -> -y, phi -> -phi) has the
mirrored residual (sidewash and the rolling and yawing rotational wind change sign).

Values per pose (``VALUE_*`` indices): the receiver's induced-drag saving, and the ``load_weighted``
coupling's translational and rotational wind in the pair frame (m/s, rad/s; the energy tasks' coupling; the
thesis's effective wind is not corrected). Interpolation: cubic (Catmull-Rom) in y and z, where the residual
has the scale of the viscous core (z on an asinh-spaced grid: 0.02 b steps on the plane, coarser off it);
linear in x (it varies there only through the core's growth with the wake's age and near the source's wing)
and in phi. Outside the table: zero ahead of ``x_b[-1]`` (= 1 b; measured there <= 0.35 % of the peak
saving), beyond y = 2 b or |z| = 0.62 b (there <= 0.5 %: what is left is the coarse wing's 2 % stronger
wake, a far field); behind ``x_b[0]`` the last plane (semi-infinite legs), beyond +-6 deg of relative roll
the edge.

Scaling: the residual's winds are proportional to the source's circulation, so they are multiplied by the
source's lift per unit rho V (sum of Gamma times the bound vortex's spanwise extent, m^3/s) over that of the
table's source at the trim; the saving (a ratio of the receiver's drag change to its own drag) is not scaled.

The table is built once (``python -m formation_env.verification.residual_table``: 130,000 pair solves)
and shipped compressed in ``formation_env/data/residual_table.npz`` (float16, 1.6 MB) with its grids and
provenance; :func:`load_table` reads it, ``tests/wake/test_residual.py`` re-computes nodes of it.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path
from typing import NamedTuple

import numba as nb
import numpy as np

__all__ = ["ResidualTable", "TABLE_PATH", "VALUE_SAVING", "VALUE_WIND", "N_VALUES",
           "TableGrid", "load_table", "save_table", "table_from_arrays", "pair_residual", "add_wind_residual",
           "add_saving_residual", "lift_per_rho_v", "NO_TABLE", "table_on"]

VALUE_SAVING = 0
VALUE_WIND = 1  # 6 values: the load-weighted translational (3) m/s and rotational (3) rad/s wind, pair frame
N_VALUES = 7
TABLE_PATH = Path(__file__).resolve().parent.parent / "data" / "residual_table.npz"

_jit = nb.njit(cache=True, error_model="numpy")


class ResidualTable(NamedTuple):
    """The residual of one pair on its grid (see the module docstring); arrays C-contiguous float64."""

    x_b: np.ndarray  # (nx,) ascending, spans (receiver's x relative to the source; negative: behind)
    y0_b: float  # first y, spans (0)
    y_step_b: float
    z_scale_b: float  # z = z_scale sinh(s) on the uniform grid s0 + k s_step: fine near the wake plane, spans
    s0: float
    s_step: float
    roll0_rad: float
    roll_step_rad: float
    values: np.ndarray  # (nx, ny, nz, nroll, N_VALUES)
    span_m: float  # the span the positions are in units of, m
    source_lift_m3ps: float  # the table's source: sum of Gamma times spanwise bound extent at the trim, m^3/s


#: no residual table: an empty table of the same type, so that the kernels compile once for the lattice and the
#: converged wake (:func:`table_on` is False for it)
NO_TABLE = ResidualTable(np.zeros(0), 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, np.zeros((0, 0, 0, 0, N_VALUES)), 1.0, 1.0)


# ---------------------------------------------------------------------------------------------------------------
# Compiled: lookup and application
# ---------------------------------------------------------------------------------------------------------------

@_jit
def table_on(tab):
    """Whether ``tab`` is a residual table to apply: False for None and :data:`NO_TABLE`."""
    if tab is None:
        return False
    return tab.x_b.shape[0] > 0


@_jit
def lift_per_rho_v(wake, gamma, v):
    """Lift per unit rho V of vehicle ``v`` (m^3/s): sum over its panels of Gamma times the bound vortex's
    spanwise (body y) extent. ``wake`` a :class:`~formation_env.wake.arrays.WakeArrays`, ``gamma`` (N,)."""
    total = 0.0
    lat = wake.lattice
    x1 = lat.knot_x1_b
    for j in range(lat.vehicle_panel_start[v], lat.vehicle_panel_start[v + 1]):
        k = lat.panel_left_knot[j]
        total += gamma[j] * abs(x1[k + 1, 1] - x1[k, 1])
    return total


@_jit
def _catmull_rom(t):
    """Cubic convolution (Catmull-Rom) weights of the four nodes around fraction ``t`` in [0, 1] (a tuple:
    the lookup runs per pair and ELL solve, so nothing is allocated)."""
    t2 = t * t
    t3 = t2 * t
    return (-0.5 * t3 + t2 - 0.5 * t, 1.5 * t3 - 2.5 * t2 + 1.0, -1.5 * t3 + 2.0 * t2 + 0.5 * t, 0.5 * t3 - 0.5 * t2)


@_jit
def _linear_index(x0, step, n, x):
    """(i, f): the cell of ``x`` on the uniform grid x0 + step k (k < n), clamped to the grid."""
    u = (x - x0) / step
    if u <= 0.0:
        return 0, 0.0
    if u >= n - 1:
        return n - 2, 1.0
    i = int(math.floor(u))
    return i, u - i


@_jit
def pair_residual(tab, px, py, pz, roll, k0, nk, out):
    """The residual ``out[:nk]`` = values ``k0 .. k0 + nk`` of ``tab`` (a :class:`ResidualTable`) at the
    receiver's position (px, py, pz) spans and relative roll ``roll`` rad in the pair frame; the mirror for
    py < 0 applied to the values (for wind blocks: sidewash, rotational x and z negated). Returns False (and
    zeros) outside the table's reach (see the module docstring)."""
    for k in range(nk):
        out[k] = 0.0
    xs = tab.x_b
    nx = xs.shape[0]
    vals = tab.values
    ny, nz, nr = vals.shape[1], vals.shape[2], vals.shape[3]
    if px > xs[nx - 1]:
        return False
    mirror = py < 0.0
    ay = -py if mirror else py
    r = -roll if mirror else roll
    uy = (ay - tab.y0_b) / tab.y_step_b
    uz = (math.asinh(pz / tab.z_scale_b) - tab.s0) / tab.s_step
    if uy > ny - 1 or uz < 0.0 or uz > nz - 1:
        return False
    # x: linear on the (non-uniform) grid, clamped behind the first plane
    ix = 0
    fx = 0.0
    if px > xs[0]:
        while ix < nx - 2 and px > xs[ix + 1]:
            ix += 1
        fx = (px - xs[ix]) / (xs[ix + 1] - xs[ix])
    ir, fr = _linear_index(tab.roll0_rad, tab.roll_step_rad, nr, r)
    iy = min(int(math.floor(uy)), ny - 2)
    iz = min(int(math.floor(uz)), nz - 2)
    wy = _catmull_rom(uy - iy)
    wz = _catmull_rom(uz - iz)
    for a in range(2):
        wa = (1.0 - fx) if a == 0 else fx
        if wa == 0.0:
            continue
        for c in range(2):
            wc = wa * ((1.0 - fr) if c == 0 else fr)
            if wc == 0.0:
                continue
            for p in range(4):
                jy = min(max(iy - 1 + p, 0), ny - 1)  # the edge node repeated at the grid's ends
                for q in range(4):
                    jz = min(max(iz - 1 + q, 0), nz - 1)
                    w = wc * wy[p] * wz[q]
                    for k in range(nk):
                        out[k] += w * vals[ix + a, jy, jz, ir + c, k0 + k]
    if mirror and k0 == VALUE_WIND:  # the wind block: mirror y of a vector (the wind), x and z of a pseudo-vector
        out[1] = -out[1]
        out[3] = -out[3]
        out[5] = -out[5]
    return True


@_jit
def _pair_frame(euler, pos, s, r, span_m):
    """The receiver ``r``'s wing origin relative to the source ``s``'s in the source's pair frame (heading,
    then the source's roll), spans; and the relative roll, rad."""
    dx = pos[r, 0] - pos[s, 0]
    dy = pos[r, 1] - pos[s, 1]
    dz = pos[r, 2] - pos[s, 2]
    cp, sp = math.cos(euler[s, 2]), math.sin(euler[s, 2])
    hx = cp * dx + sp * dy
    hy = -sp * dx + cp * dy
    cf, sf = math.cos(euler[s, 0]), math.sin(euler[s, 0])
    fy = cf * hy + sf * dz
    fz = -sf * hy + cf * dz
    return hx / span_m, fy / span_m, fz / span_m, euler[r, 0] - euler[s, 0]


@_jit
def add_wind_residual(wake, tab, pos, euler, gamma, rot, wind_ned, wind_b, omega_b, omega_ned):
    """Adds every ordered pair's wind residual (``tab``'s :data:`VALUE_WIND` block, scaled by the source's lift
    per rho V over the table's) to the load-weighted translational and rotational wind of each receiving vehicle,
    NED and body; ``tab`` None or :data:`NO_TABLE`: nothing. ``rot`` (V, 3, 3) NED -> body of each vehicle;
    the rest as :func:`formation_env.wake.coupling.coupled_wind`'s."""
    if tab is None:  # pruned when compiled
        return
    if not table_on(tab):
        return
    nv = pos.shape[0]
    res = np.empty(6)
    for s in range(nv):
        scale = lift_per_rho_v(wake, gamma, s) / tab.source_lift_m3ps
        cp, sp = math.cos(euler[s, 2]), math.sin(euler[s, 2])
        cf, sf = math.cos(euler[s, 0]), math.sin(euler[s, 0])
        for r in range(nv):
            if r == s:
                continue
            px, py, pz, dphi = _pair_frame(euler, pos, s, r, tab.span_m)
            if not pair_residual(tab, px, py, pz, dphi, VALUE_WIND, 6, res):
                continue
            for blk in range(2):
                # pair frame -> NED: undo the source's roll, then its heading
                vx = res[3 * blk] * scale
                vy = res[3 * blk + 1] * scale
                vz = res[3 * blk + 2] * scale
                hy = cf * vy - sf * vz
                nz_ = sf * vy + cf * vz
                nx_ = cp * vx - sp * hy
                ny_ = sp * vx + cp * hy
                target = wind_ned if blk == 0 else omega_ned
                target[r, 0] += nx_
                target[r, 1] += ny_
                target[r, 2] += nz_
    for v in range(nv):
        for a in range(3):
            wind_b[v, a] = rot[v, a, 0] * wind_ned[v, 0] + rot[v, a, 1] * wind_ned[v, 1] + rot[v, a, 2] * wind_ned[v, 2]
            omega_b[v, a] = (rot[v, a, 0] * omega_ned[v, 0] + rot[v, a, 1] * omega_ned[v, 1]
                             + rot[v, a, 2] * omega_ned[v, 2])


@_jit
def add_saving_residual(tab, pos, euler, saving):
    """Adds every ordered pair's saving residual to each receiving vehicle's induced-drag saving (V,); ``tab``
    None or :data:`NO_TABLE`: nothing. ``pos`` (V, 3) wing origins NED, m; ``euler`` (V, 3) rad."""
    if tab is None:  # pruned when compiled
        return
    if not table_on(tab):
        return
    nv = pos.shape[0]
    res = np.empty(1)
    for s in range(nv):
        for r in range(nv):
            if r == s:
                continue
            px, py, pz, dphi = _pair_frame(euler, pos, s, r, tab.span_m)
            if pair_residual(tab, px, py, pz, dphi, VALUE_SAVING, 1, res):
                saving[r] += res[0]


# ---------------------------------------------------------------------------------------------------------------
# The table: its grid, building, storage
# ---------------------------------------------------------------------------------------------------------------

class TableGrid(NamedTuple):
    """Where the residual is tabulated (see the module docstring); defaults: the shipped table's."""

    x_b: tuple = (-6.0, -3.0, -2.0, -1.0, -0.5, 0.0, 0.5, 1.0)
    y_step_b: float = 0.02
    ny: int = 101  # y 0 .. 2 spans
    z_scale_b: float = 0.08
    s_step: float = 0.25
    ns: int = 23  # s -2.75 .. 2.75: z within +-0.62 spans, steps 0.02 spans on the plane, 0.08 at |z| = 0.3
    roll_step_deg: float = 2.0
    nroll: int = 7  # -6 .. 6 deg

    def axes(self):
        """(x_b, y_b, z_b, roll_rad) node arrays."""
        s = (np.arange(self.ns) - (self.ns - 1) / 2) * self.s_step
        roll = (np.arange(self.nroll) - (self.nroll - 1) / 2) * np.radians(self.roll_step_deg)
        return (np.asarray(self.x_b, float), np.arange(self.ny) * self.y_step_b, self.z_scale_b * np.sinh(s), roll)


def table_from_arrays(d) -> ResidualTable:
    """The compiled kernels' :class:`ResidualTable` of the arrays of :func:`build_table` (or a loaded file)."""
    values = np.ascontiguousarray(np.asarray(d["values"], dtype=np.float64))
    ns = int(d["ns"])
    nroll = values.shape[3]
    s_step = float(d["s_step"])
    roll_step = float(d["roll_step_rad"])
    return ResidualTable(x_b=np.ascontiguousarray(np.asarray(d["x_b"], float)), y0_b=0.0,
                         y_step_b=float(d["y_step_b"]), z_scale_b=float(d["z_scale_b"]), s0=-(ns - 1) / 2 * s_step,
                         s_step=s_step, roll0_rad=-(nroll - 1) / 2 * roll_step, roll_step_rad=roll_step, values=values,
                         span_m=float(d["span_m"]), source_lift_m3ps=float(d["source_lift_m3ps"]))


def save_table(d: dict, path: Path = TABLE_PATH, *, overwrite: bool = False, provenance: str = "") -> Path:
    """Writes the table (values as float16: residuals <= 0.2 in saving and <= 0.1 m/s, so ~1e-4 of them;
    compressed) atomically; refuses an existing file unless ``overwrite``."""
    import os
    import tempfile

    path = Path(path)
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True (--force) to replace it")
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".npz")
    os.close(fd)
    try:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, **{k: v for k, v in d.items() if k != "values"},
                                values=np.asarray(d["values"], np.float16), provenance=np.array(provenance))
        os.chmod(tmp, 0o644)  # mkstemp's 0600 would keep the shipped file from other users
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    return path


@functools.lru_cache(maxsize=2)
def load_table(path: Path = TABLE_PATH) -> ResidualTable:
    """The shipped table (read once)."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"the residual table {path} is missing: build it with "
                                "`python -m formation_env.verification.residual_table`")
    with np.load(path) as d:
        return table_from_arrays(d)
