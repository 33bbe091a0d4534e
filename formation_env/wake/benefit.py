"""Compiled induced drag and the formation benefit (induced-drag saving) of ONE formation.

The same Kutta-Joukowski loads as :func:`formation_env.wake.loads.vehicle_loads` /
:func:`~formation_env.wake.loads.formation_benefit`, for one formation at a time inside compiled
code (the env's decision step calls it in its ``nogil`` loop): F_k = rho Gamma_k (V_rel,k x l_k)
at each bound vortex's midpoint, V_rel = -V_vehicle + (own horseshoes, plain Biot-Savart with the
Eq. 4.31 cutoff) + (other vehicles' horseshoes, field law with the viscous core); the induced drag
is minus the wind-axis x component of the vehicle's summed force. The saving is
``1 - D_i(formation) / D_i(alone)`` (0 where ``D_i(alone)`` is 0), the isolated drag coming from a
single-vehicle solve at the same pose and air data.

It composes the existing kernels (:func:`~formation_env.wake.kernels.posed_lattice`,
:func:`~formation_env.wake.kernels.field_velocity`, :func:`~formation_env.wake.kernels.evaluate_one`);
no Biot-Savart law is repeated here.

The lattice comes as a ``WakeArrays`` NamedTuple (:func:`formation_env.wake.arrays.wake_arrays`, which
re-exports :mod:`formation_env.wake.arrays`); ``wake_alone`` is that of ``WakeModel([vehicle])``
with the formation model's options (``core``, ``eval_points``, ``rotational``,
``kinematic_viscosity``, ``viscous_aic``), as ``loads.isolated_model`` builds it. Poses are the
ELL inputs of :func:`formation_env.sim.kernels.ell_inputs`: ``pos`` (V, 3) NED wing origins,
``euler`` (V, 3) rad, ``speed``/``alpha``/``beta`` (V,) m/s, rad.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from . import lanes
from .arrays import evaluate_formation
from .aic import assemble_and_solve, lu_solve_inplace
from .biot_savart import branch, leg, point_to_knots, sheet_on, sheet_strip_frames
from .kernels import CORE_NONE, field_velocity, posed_lattice
from .residual import add_saving_residual

__all__ = ["induced_drag_one", "isolated_induced_drag_one", "induced_drags_one", "induced_drag_saving_one",
           "saving_from_drags", "induced_drag_saving", "AIR_DENSITY_SL"]

AIR_DENSITY_SL = 1.225  # kg/m^3 (as formation_env.wake.loads.AIR_DENSITY_SL)

_jit = nb.njit(cache=True, error_model="numpy")


@_jit
def _bound_segment(x1, k):
    """The bound vortex from knot k to k + 1 (NED, m): its vector l and its midpoint, where the
    Kutta-Joukowski force acts."""
    return (x1[k + 1, 0] - x1[k, 0], x1[k + 1, 1] - x1[k, 1], x1[k + 1, 2] - x1[k, 2],
            0.5 * (x1[k, 0] + x1[k + 1, 0]), 0.5 * (x1[k, 1] + x1[k + 1, 1]), 0.5 * (x1[k, 2] + x1[k + 1, 2]))


@_jit
def _add_kutta_joukowski(f, v, g, wx, wy, wz, ox, oy, oz, ex, ey, ez, lx, ly, lz):
    """Adds the Kutta-Joukowski force rho Gamma (V_rel x l) (``g`` = rho Gamma) to ``f[v]``, with V_rel =
    -V_vehicle + o + e (``wx, wy, wz`` = V_vehicle, o the own horseshoes' velocity, e the others')."""
    vx = -wx + ox + ex
    vy = -wy + oy + ey
    vz = -wz + oz + ez
    f[v, 0] += g * (vy * lz - vz * ly)
    f[v, 1] += g * (vz * lx - vx * lz)
    f[v, 2] += g * (vx * ly - vy * lx)


@_jit
def induced_drag_one(wake, gamma, pos, euler, speed, alpha, beta, out_drag, air_density=AIR_DENSITY_SL):
    """Induced drag (N, wind axes, positive rearwards) of each of the V vehicles of one formation
    into ``out_drag`` (V,), for the circulation ``gamma`` (N,) solved at these poses
    (:func:`~formation_env.wake.kernels.evaluate_one`); equal to ``vehicle_loads(...).drag_n``."""
    nv = pos.shape[0]
    lat = wake.lattice
    n_panels = lat.panel_left_knot.shape[0]
    posed = posed_lattice(lat, pos, euler, speed, alpha, beta)
    rot, vel, x1 = posed.rot, posed.vel, posed.x1
    frames = sheet_strip_frames(wake.sheet, posed.trail, posed.x3, lat.knot_vehicle, lat.knot_surface)
    f = np.zeros((nv, 3))  # summed Kutta-Joukowski force per vehicle, NED
    for j in range(n_panels):
        v = lat.panel_vehicle[j]
        k = lat.panel_left_knot[j]
        lx, ly, lz, mx, my, mz = _bound_segment(x1, k)
        # Own horseshoes: the solve's law (plain, cutoff); the others': the field law (viscous core).
        ox, oy, oz = field_velocity(mx, my, mz, v, True, lat, posed, gamma, CORE_NONE, 0.0)
        ex, ey, ez = field_velocity(mx, my, mz, v, False, lat, posed, gamma, lat.core_mode, lat.overlap_core_m,
                                    wake.sheet, 0.0 if not sheet_on(wake.sheet) else np.sqrt(lx * lx + ly * ly + lz * lz),
                                    frames)
        _add_kutta_joukowski(f, v, air_density * gamma[j], vel[v, 0], vel[v, 1], vel[v, 2], ox, oy, oz, ex, ey, ez,
                             lx, ly, lz)
    for v in range(nv):
        out_drag[v] = _wind_axis_drag(rot[v], f[v], alpha[v], beta[v])


@_jit
def isolated_circulation_one(wake_alone, v, pos, euler, speed, alpha, beta, gamma_out):
    """Circulation ``gamma_out`` (n,) of vehicle ``v`` of the formation flying alone at its pose and air
    data: the single-vehicle lattice ``wake_alone`` posed and solved (the joint solve of ``evaluate_one``
    without its effective-wind part, which a lone vehicle does not need: the same arithmetic, so the same
    circulation)."""
    pos1 = np.empty((1, 3))
    eul1 = np.empty((1, 3))
    sp1 = np.empty(1)
    al1 = np.empty(1)
    be1 = np.empty(1)
    for i in range(3):
        pos1[0, i] = pos[v, i]
        eul1[0, i] = euler[v, i]
    sp1[0] = speed[v]
    al1[0] = alpha[v]
    be1[0] = beta[v]
    lat = wake_alone.lattice
    n = lat.panel_left_knot.shape[0]
    posed = posed_lattice(lat, pos1, eul1, sp1, al1, be1)
    assemble_and_solve(lat, posed, np.empty((n, n)), gamma_out, np.empty((0, 0, 3)), wake_alone.sheet)
    return pos1, eul1, sp1, al1, be1


@_jit
def isolated_induced_drag_one(wake_alone, v, pos, euler, speed, alpha, beta, air_density=AIR_DENSITY_SL):
    """Induced drag (N) vehicle ``v`` of the formation would have alone at its pose and air data:
    the single-vehicle lattice ``wake_alone`` solved (:func:`isolated_circulation_one`), then
    :func:`induced_drag_one`."""
    gamma = np.empty(wake_alone.n_panels)
    pos1, eul1, sp1, al1, be1 = isolated_circulation_one(wake_alone, v, pos, euler, speed, alpha, beta, gamma)
    d = np.empty(1)
    induced_drag_one(wake_alone, gamma, pos1, eul1, sp1, al1, be1, d, air_density)
    return d[0]


@_jit
def _own_field_pair(px, py, pz, v, lat, posed, gamma, gamma2):
    """Velocity (NED) induced at P by vehicle ``v``'s own horseshoes for two circulations at once (the
    formation's ``gamma`` and the lone vehicle's ``gamma2``, both indexed by the formation's panels): the
    own-horseshoe part of :func:`~formation_env.wake.field.field_velocity` (``keep_only``, the solve's law:
    plain Biot-Savart with the ``cutoff``, no core), each branch evaluated once and added to both sums in
    the same order and form as there, so each sum is bit for bit what a separate call gives. The lone
    vehicle's drag needs nothing else (no other vehicle), so the saving takes it from the formation's pass
    (issue 26)."""
    x1, x3, bound_dir, chord_dir, trail = posed.x1, posed.x3, posed.bound_dir, posed.chord_dir, posed.trail
    r1, inv1, r3, inv3 = posed.r1, posed.inv1, posed.r3, posed.inv3
    surface_knot_start, surface_panel_start, surface_vehicle = (lat.surface_knot_start, lat.surface_panel_start,
                                                                lat.surface_vehicle)
    cutoff = lat.cutoff_m
    vx = 0.0
    vy = 0.0
    vz = 0.0
    ux = 0.0
    uy = 0.0
    uz = 0.0
    t = trail[v]
    for s in range(surface_vehicle.shape[0]):
        if surface_vehicle[s] != v:
            continue
        k0 = surface_knot_start[s]
        k1 = surface_knot_start[s + 1]
        p0 = surface_panel_start[s]
        point_to_knots(px, py, pz, x1, x3, k0, k1, r1, inv1, r3, inv3)
        for k in range(k0, k1):
            g = 0.0
            g2 = 0.0
            if k < k1 - 1:
                g += gamma[p0 + (k - k0)]
                g2 += gamma2[p0 + (k - k0)]
            if k > k0:
                g -= gamma[p0 + (k - k0) - 1]
                g2 -= gamma2[p0 + (k - k0) - 1]
            if g != 0.0 or g2 != 0.0:
                lx, ly, lz = leg(t[0], t[1], t[2], r3[k, 0], r3[k, 1], r3[k, 2], inv3[k], cutoff, 0.0)
                sx, sy, sz = branch(chord_dir[k, 0], chord_dir[k, 1], chord_dir[k, 2], r3[k, 0], r3[k, 1], r3[k, 2],
                                    inv3[k], r1[k, 0], r1[k, 1], r1[k, 2], inv1[k], cutoff)
                if g != 0.0:
                    vx += g * (sx - lx)
                    vy += g * (sy - ly)
                    vz += g * (sz - lz)
                if g2 != 0.0:
                    ux += g2 * (sx - lx)
                    uy += g2 * (sy - ly)
                    uz += g2 * (sz - lz)
            if k < k1 - 1:
                bx, by, bz = branch(bound_dir[k, 0], bound_dir[k, 1], bound_dir[k, 2], r1[k, 0], r1[k, 1], r1[k, 2],
                                    inv1[k], r1[k + 1, 0], r1[k + 1, 1], r1[k + 1, 2], inv1[k + 1], cutoff)
                gp = gamma[p0 + (k - k0)]
                vx += gp * bx
                vy += gp * by
                vz += gp * bz
                gp2 = gamma2[p0 + (k - k0)]
                ux += gp2 * bx
                uy += gp2 * by
                uz += gp2 * bz
    return vx, vy, vz, ux, uy, uz


@_jit
def _own_pair_sum(s, v, gamma, gamma2, surface_vehicle, surface_knot_start, surface_panel_start):
    """:func:`_own_field_pair` from the lanes of :func:`formation_env.wake.lanes.own_field_lanes` and
    :func:`~formation_env.wake.lanes.own_field_bounds` (the same branch vectors): the same sums in the same order."""
    vx = 0.0
    vy = 0.0
    vz = 0.0
    ux = 0.0
    uy = 0.0
    uz = 0.0
    for srf in range(surface_vehicle.shape[0]):
        if surface_vehicle[srf] != v:
            continue
        k0 = surface_knot_start[srf]
        k1 = surface_knot_start[srf + 1]
        p0 = surface_panel_start[srf]
        for k in range(k0, k1):
            g = 0.0
            g2 = 0.0
            if k < k1 - 1:
                g += gamma[p0 + (k - k0)]
                g2 += gamma2[p0 + (k - k0)]
            if k > k0:
                g -= gamma[p0 + (k - k0) - 1]
                g2 -= gamma2[p0 + (k - k0) - 1]
            if g != 0.0 or g2 != 0.0:
                dx, dy, dz = s[lanes.OLX + k], s[lanes.OLY + k], s[lanes.OLZ + k]
                if g != 0.0:
                    vx += g * dx
                    vy += g * dy
                    vz += g * dz
                if g2 != 0.0:
                    ux += g2 * dx
                    uy += g2 * dy
                    uz += g2 * dz
            if k < k1 - 1:
                bx, by, bz = s[lanes.OBX + k], s[lanes.OBY + k], s[lanes.OBZ + k]
                gp = gamma[p0 + (k - k0)]
                vx += gp * bx
                vy += gp * by
                vz += gp * bz
                gp2 = gamma2[p0 + (k - k0)]
                ux += gp2 * bx
                uy += gp2 * by
                uz += gp2 * bz
    return vx, vy, vz, ux, uy, uz


@_jit
def _other_field_sum(s, v, gamma, surface_vehicle, surface_knot_start, surface_panel_start):
    """The other vehicles' field at a point (:func:`~formation_env.wake.field.field_velocity` without ``keep_only``)
    from the lanes of :func:`formation_env.wake.lanes.other_llines` and :func:`~formation_env.wake.lanes.other_bounds`
    (fixed where flagged): the same sum in the same order."""
    vx = 0.0
    vy = 0.0
    vz = 0.0
    for srf in range(surface_vehicle.shape[0]):
        if surface_vehicle[srf] == v:
            continue
        k0 = surface_knot_start[srf]
        k1 = surface_knot_start[srf + 1]
        p0 = surface_panel_start[srf]
        for k in range(k0, k1):
            g = 0.0
            if k < k1 - 1:
                g += gamma[p0 + (k - k0)]
            if k > k0:
                g -= gamma[p0 + (k - k0) - 1]
            if g != 0.0:
                vx += g * s[lanes.LCX + k]
                vy += g * s[lanes.LCY + k]
                vz += g * s[lanes.LCZ + k]
            if k < k1 - 1:
                gp = gamma[p0 + (k - k0)]
                vx += gp * s[lanes.BX + k]
                vy += gp * s[lanes.BY + k]
                vz += gp * s[lanes.BZ + k]
    return vx, vy, vz


@_jit
def _wind_axis_drag(rot, f, alpha, beta):
    """Induced drag (N): minus the body-axis force ``f`` (NED, 3) along the air-relative direction."""
    ca, sa = np.cos(alpha), np.sin(alpha)
    cb, sb = np.cos(beta), np.sin(beta)
    fb0 = rot[0, 0] * f[0] + rot[0, 1] * f[1] + rot[0, 2] * f[2]
    fb1 = rot[1, 0] * f[0] + rot[1, 1] * f[1] + rot[1, 2] * f[2]
    fb2 = rot[2, 0] * f[0] + rot[2, 1] * f[1] + rot[2, 2] * f[2]
    return -(fb0 * (ca * cb) + fb1 * sb + fb2 * (sa * cb))


@_jit
def induced_drags_one(wake, wake_alone, pos, euler, speed, alpha, beta, gamma_formation, out_formation, out_alone,
                      air_density=AIR_DENSITY_SL, keep=None):
    """Induced drag (N, wind axes) of each of the V vehicles of one formation in formation (``out_formation``
    (V,), for the circulation ``gamma_formation`` (N,) solved at these poses by ``evaluate_one``) and alone at
    the same pose and air data (``out_alone`` (V,): each vehicle's circulation from ``wake_alone`` solved
    alone, :func:`isolated_circulation_one`; every vehicle must be of the make-up ``wake_alone`` describes: its
    panels those of each vehicle of ``wake``, in order, else a ValueError). Bit for bit :func:`induced_drag_one`
    and :func:`isolated_induced_drag_one` (tested), from one pass over the bound vortices: the own horseshoes'
    branches evaluated once for both circulations (:func:`_own_field_pair`). ``keep`` (N, N + 1), not None: the AIC and
    right-hand side of the solve that gave ``gamma_formation``, before elimination
    (:func:`formation_env.wake.aic.assemble_and_solve`); each vehicle's isolated circulation is then its diagonal
    block solved, bit for bit what posing and solving it alone gives (the same entries, tested), without the posing
    and assembly (issue 26)."""
    nv = pos.shape[0]
    lat = wake.lattice
    n_panels = lat.panel_left_knot.shape[0]
    n_alone = wake_alone.lattice.panel_left_knot.shape[0]
    for v in range(nv):
        if lat.vehicle_panel_start[v + 1] - lat.vehicle_panel_start[v] != n_alone:
            raise ValueError("induced_drags_one: wake_alone's panel count differs from a vehicle's of the formation "
                             "(every vehicle must be of the make-up wake_alone describes)")
    gamma_alone = np.empty(n_panels)
    g1 = np.empty(n_alone)
    reuse = keep is not None and keep.shape[0] == n_panels
    blk = np.empty((n_alone, n_alone) if reuse else (0, 0))
    for v in range(nv):
        p0 = lat.vehicle_panel_start[v]
        if reuse:
            for i in range(n_alone):
                for c in range(n_alone):
                    blk[i, c] = keep[p0 + i, p0 + c]
                g1[i] = keep[p0 + i, n_panels]
            lu_solve_inplace(blk, g1)
        else:
            isolated_circulation_one(wake_alone, v, pos, euler, speed, alpha, beta, g1)
        for i in range(n_alone):
            gamma_alone[p0 + i] = g1[i]
    posed = posed_lattice(lat, pos, euler, speed, alpha, beta)
    rot, vel, trail, x1, x3 = posed.rot, posed.vel, posed.trail, posed.x1, posed.x3
    origin, bound_dir, chord_dir = posed.origin, posed.bound_dir, posed.chord_dir
    frames = sheet_strip_frames(wake.sheet, trail, x3, lat.knot_vehicle, lat.knot_surface)
    f = np.zeros((nv, 3))  # summed Kutta-Joukowski force per vehicle, NED: in formation
    fa = np.zeros((nv, 3))  # and alone
    n_knots = x1.shape[0]
    if n_knots <= lanes.KMAX:
        # the branches at each bound midpoint as vector lanes (issue 26; bit for bit the scalar pass below)
        s = lanes.lane_scratch()
        lanes.load_knots(s, x1, x3, chord_dir, bound_dir, trail, lat.knot_vehicle, frames, wake.sheet)
        vk0, vk1 = lanes.vehicle_knot_ranges(lat.knot_vehicle, nv)
        ro2 = lat.overlap_core_m * lat.overlap_core_m if lat.overlap_core_m > 0.0 else np.inf
        cutoff = lat.cutoff_m
        for j in range(n_panels):
            v = lat.panel_vehicle[j]
            k = lat.panel_left_knot[j]
            lx, ly, lz, mx, my, mz = _bound_segment(x1, k)
            a, b = vk0[v], vk1[v]
            lanes.own_field_lanes(s, a, b, mx, my, mz, cutoff)
            lanes.own_field_bounds(s, a, b - 1, mx, my, mz, cutoff)
            ox, oy, oz, ax, ay, az = _own_pair_sum(s, v, gamma_formation, gamma_alone, lat.surface_vehicle,
                                                   lat.surface_knot_start, lat.surface_panel_start)
            recv_w = 0.0 if not sheet_on(wake.sheet) else np.sqrt(lx * lx + ly * ly + lz * lz)
            lanes.fill_core_radius(s, mx, my, mz, v, origin, speed, lat.knot_vehicle, lat.surface_knot_start,
                                   lat.surface_core_scale, lat.core_mode, lat.kinematic_viscosity)
            for rng in range(2):
                lo = 0 if rng == 0 else b
                hi = a if rng == 0 else n_knots
                lanes.other_llines(s, lo, hi, mx, my, mz, 0.0, 0.0, 0.0, cutoff, ro2, recv_w, sheet_on(wake.sheet))
                lanes.fix_llines(s, lo, hi, mx, my, mz, 0.0, 0.0, 0.0, x1, x3, chord_dir, trail, lat.knot_vehicle,
                                 cutoff, lat.overlap_core_m, frames, recv_w, wake.sheet)
                if hi - lo > 1:
                    lanes.other_bounds(s, lo, hi - 1, mx, my, mz, ro2)
                    lanes.fix_bounds(s, lo, hi - 1, mx, my, mz, x1, bound_dir, cutoff, lat.overlap_core_m)
            ex, ey, ez = _other_field_sum(s, v, gamma_formation, lat.surface_vehicle, lat.surface_knot_start,
                                          lat.surface_panel_start)
            _add_kutta_joukowski(f, v, air_density * gamma_formation[j], vel[v, 0], vel[v, 1], vel[v, 2], ox, oy,
                                 oz, ex, ey, ez, lx, ly, lz)
            _add_kutta_joukowski(fa, v, air_density * gamma_alone[j], vel[v, 0], vel[v, 1], vel[v, 2], ax, ay, az,
                                 0.0, 0.0, 0.0, lx, ly, lz)
        for v in range(nv):
            out_formation[v] = _wind_axis_drag(rot[v], f[v], alpha[v], beta[v])
            out_alone[v] = _wind_axis_drag(rot[v], fa[v], alpha[v], beta[v])
        return
    for j in range(n_panels):
        v = lat.panel_vehicle[j]
        k = lat.panel_left_knot[j]
        lx, ly, lz, mx, my, mz = _bound_segment(x1, k)
        ox, oy, oz, ax, ay, az = _own_field_pair(mx, my, mz, v, lat, posed, gamma_formation, gamma_alone)
        ex, ey, ez = field_velocity(mx, my, mz, v, False, lat, posed, gamma_formation, lat.core_mode,
                                    lat.overlap_core_m, wake.sheet,
                                    np.sqrt(lx * lx + ly * ly + lz * lz) if sheet_on(wake.sheet) else 0.0, frames)
        _add_kutta_joukowski(f, v, air_density * gamma_formation[j], vel[v, 0], vel[v, 1], vel[v, 2], ox, oy, oz,
                             ex, ey, ez, lx, ly, lz)
        # alone: no other vehicle (the separate solve adds the empty others' field, 0.0, as here)
        _add_kutta_joukowski(fa, v, air_density * gamma_alone[j], vel[v, 0], vel[v, 1], vel[v, 2], ax, ay, az,
                             0.0, 0.0, 0.0, lx, ly, lz)
    for v in range(nv):
        out_formation[v] = _wind_axis_drag(rot[v], f[v], alpha[v], beta[v])
        out_alone[v] = _wind_axis_drag(rot[v], fa[v], alpha[v], beta[v])


@_jit
def induced_drag_saving_one(wake, wake_alone, pos, euler, speed, alpha, beta, gamma_formation, out_saving,
                            air_density=AIR_DENSITY_SL, keep=None):
    """Induced-drag saving 1 - D_i(formation) / D_i(alone) of each vehicle of one formation into
    ``out_saving`` (V,) (0 where D_i(alone) is 0), the drags from :func:`induced_drags_one` (nothing is
    solved for the formation here: ``gamma_formation`` (N,) is its circulation at these poses, from
    ``evaluate_one``); times ``wake.saving_scale`` (the span-efficiency correction, 1.0: none). Equal to
    ``formation_benefit(...)["induced_drag_saving"]``."""
    nv = pos.shape[0]
    d_form = np.empty(nv)
    d_alone = np.empty(nv)
    induced_drags_one(wake, wake_alone, pos, euler, speed, alpha, beta, gamma_formation, d_form, d_alone, air_density,
                      keep)
    saving_from_drags(wake, pos, euler, d_form, d_alone, out_saving)


@_jit
def saving_from_drags(wake, pos, euler, d_form, d_alone, out_saving):
    """Induced-drag saving 1 - D_i(formation) / D_i(alone) (V,) into ``out_saving`` from the drags ``d_form`` and
    ``d_alone`` (V,) of one formation at the poses ``pos``, ``euler`` (V, 3) (0 where D_i(alone) is 0), times
    ``wake.saving_scale``, plus the residual table's correction (:func:`induced_drag_saving_one`'s last part)."""
    for v in range(d_form.shape[0]):
        out_saving[v] = 1.0 - d_form[v] / d_alone[v] if abs(d_alone[v]) > 0.0 else 0.0
        if wake.saving_scale != 1.0:  # the span-efficiency correction (WakeModel saving_scale)
            out_saving[v] *= wake.saving_scale
    add_saving_residual(wake.residual, pos, euler, out_saving)  # the residual table of pairs (None: nothing)


def induced_drag_saving(model, state, air_density: float = AIR_DENSITY_SL) -> np.ndarray:
    """The compiled path for a batch: (B, V) induced-drag saving of ``model`` (a
    :class:`~formation_env.wake.WakeModel`) at ``state`` (a :class:`~formation_env.wake.FormationState`).

    Each formation is solved with ``evaluate_one`` and its saving taken with
    :func:`induced_drag_saving_one`, as the env's compiled step does (a formation of different
    vehicles takes each one's isolated drag from its own single-vehicle lattice). For tests and
    offline use; the batched numpy reference is :func:`formation_env.wake.loads.formation_benefit`.
    """
    from .arrays import wake_arrays
    from .loads import isolated_model

    if not (np.isfinite(air_density) and air_density > 0):
        raise ValueError(f"induced_drag_saving: air_density must be finite and > 0, got {air_density!r}")
    state = model._check_state(state)
    origin = np.zeros(3)
    wake = wake_arrays(model, origin)
    alone = [wake_arrays(isolated_model(v, model.core, model.eval_points, model.rotational, model.kinematic_viscosity,
                                      model.viscous_aic), origin) for v in model.vehicles]
    same = all(v == model.vehicles[0] for v in model.vehicles)
    nb_, nv, n = state.batch_size, model.n_vehicles, model.n_panels
    out = np.empty((nb_, nv))
    gamma = np.empty(n)
    vpts = np.empty((n, 3))
    scratch = [np.empty((nv, 3)) for _ in range(4)]
    w = wake
    for b in range(nb_):
        pos = np.ascontiguousarray(state.position_ned[b], dtype=float)
        euler = np.ascontiguousarray(state.euler_rad[b], dtype=float)
        speed = np.ascontiguousarray(state.airspeed_mps[b], dtype=float)
        alpha = np.ascontiguousarray(state.alpha_rad[b], dtype=float)
        beta = np.ascontiguousarray(state.beta_rad[b], dtype=float)
        evaluate_formation(w, pos, euler, speed, alpha, beta, gamma, vpts, *scratch)
        if same:
            induced_drag_saving_one(wake, alone[0], pos, euler, speed, alpha, beta, gamma, out[b], air_density)
        else:
            d_form = np.empty(nv)
            induced_drag_one(wake, gamma, pos, euler, speed, alpha, beta, d_form, air_density)
            for v in range(nv):
                d_alone = isolated_induced_drag_one(alone[v], v, pos, euler, speed, alpha, beta, air_density)
                out[b, v] = 1.0 - d_form[v] / d_alone if abs(d_alone) > 0.0 else 0.0
                if model.saving_scale != 1.0:
                    out[b, v] *= model.saving_scale
            add_saving_residual(model.residual, pos, euler, out[b])
    return out
