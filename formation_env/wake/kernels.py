"""Compiled ELL kernels: Biot-Savart branches, the joint AIC solve, field velocities and the
effective wind (thesis 4.2.2-4.3.7). Pure functions over arrays with a leading batch axis.

Unit conventions: metres, m/s, radians; positions and velocities in NED unless the name says
``_b`` (body axes of the vehicle concerned).

Horseshoe bookkeeping. Horseshoe k of a surface runs inf -> X3[k] -> X1[k] -> X1[k+1] -> X3[k+1]
-> inf. Writing L[i] for the "L-line" inf -> X3[i] -> X1[i] (trailing leg plus chordwise branch
at knot i), horseshoe k = L[k] + bound(X1[k] -> X1[k+1]) - L[k+1]. Each knot's L-line is
therefore evaluated once and shared by its two neighbouring horseshoes, which halves the work
and is exactly the thesis's 5-branch sum.

Circulation sign: positive circulation about the bound vortex directed port -> starboard lifts
(Kutta-Joukowski F = rho Gamma V_rel x l). The thesis prints the opposite sign (its G of Table 5.2
is negative for a lifting wing); only the sign convention differs.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

FOUR_PI = 4.0 * math.pi
CORE_NONE, CORE_LAMB_OSEEN, CORE_KURYLOWICH = 0, 1, 2
# Core-radius constants rc = C sqrt(nu tau): Lamb-Oseen 2.24 (Eq. 4.1), Kurylowich 36.2 / cos^2(sweep)
# (chapters 3 and 7); the viscous factor is 1 - exp(-1.26 (h / rc)^2).
LAMB_OSEEN_C = 2.24
KURYLOWICH_C = 36.2
_TINY_H = 1e-12  # below this distance a point lies on the branch line: no contribution
_MIN_CORE_M = 1e-9

_jit = nb.njit(cache=True, fastmath=False, error_model="numpy")


@_jit
def lu_solve_inplace(a, rhs):
    """Solve a x = rhs by Gaussian elimination with partial pivoting (a and rhs are overwritten;
    x is returned in rhs). The AIC is small and dense, so this beats a LAPACK call's overhead."""
    n = a.shape[0]
    for k in range(n):
        p = k
        best = abs(a[k, k])
        for i in range(k + 1, n):
            v = abs(a[i, k])
            if v > best:
                best = v
                p = i
        if p != k:
            for j in range(n):
                tmp = a[k, j]
                a[k, j] = a[p, j]
                a[p, j] = tmp
            tmp = rhs[k]
            rhs[k] = rhs[p]
            rhs[p] = tmp
        piv = a[k, k]
        if piv == 0.0:
            piv = 1e-300  # singular (degenerate geometry): stay finite rather than divide by zero
            a[k, k] = piv
        for i in range(k + 1, n):
            m = a[i, k] / piv
            if m != 0.0:
                for j in range(k + 1, n):
                    a[i, j] -= m * a[k, j]
                rhs[i] -= m * rhs[k]
    for k in range(n - 1, -1, -1):
        s = rhs[k]
        for j in range(k + 1, n):
            s -= a[k, j] * rhs[j]
        rhs[k] = s / a[k, k]


@_jit
def dcm_ned_to_body_1(phi, theta, psi, out):
    """Thesis Eq. 4.10 for one vehicle, written into ``out`` (3, 3)."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth, sth = math.cos(theta), math.sin(theta)
    cps, sps = math.cos(psi), math.sin(psi)
    out[0, 0] = cth * cps
    out[0, 1] = cth * sps
    out[0, 2] = -sth
    out[1, 0] = sph * sth * cps - cph * sps
    out[1, 1] = sph * sth * sps + cph * cps
    out[1, 2] = sph * cth
    out[2, 0] = cph * sth * cps + sph * sps
    out[2, 1] = cph * sth * sps - sph * cps
    out[2, 2] = cph * cth


@_jit
def place_lattice(
    pos, euler, airspeed, alpha, beta,
    knot_x1_b, knot_x3_b, knot_vehicle, surface_origin_b, surface_vehicle,
    rot, vel, trail, x1, x3, origin,
):
    """Pose the body-axis lattice in NED for one formation.

    Writes rot (V,3,3) NED->body DCMs, vel (V,3) NED air-relative velocities of the vehicles,
    trail (V,3) unit downstream direction of their trailing legs, x1/x3 (K,3) knots and
    origin (S,3) surface origins, all NED.
    """
    nv = pos.shape[0]
    for v in range(nv):
        dcm_ned_to_body_1(euler[v, 0], euler[v, 1], euler[v, 2], rot[v])
        ca, sa = math.cos(alpha[v]), math.sin(alpha[v])
        cb, sb = math.cos(beta[v]), math.sin(beta[v])
        ub0, ub1, ub2 = ca * cb, sb, sa * cb  # body-axis direction of the air-relative velocity
        for i in range(3):
            d = rot[v, 0, i] * ub0 + rot[v, 1, i] * ub1 + rot[v, 2, i] * ub2
            vel[v, i] = airspeed[v] * d
            trail[v, i] = -d
    for k in range(knot_x1_b.shape[0]):
        v = knot_vehicle[k]
        for i in range(3):
            x1[k, i] = pos[v, i] + rot[v, 0, i] * knot_x1_b[k, 0] + rot[v, 1, i] * knot_x1_b[k, 1] + rot[v, 2, i] * knot_x1_b[k, 2]
            x3[k, i] = pos[v, i] + rot[v, 0, i] * knot_x3_b[k, 0] + rot[v, 1, i] * knot_x3_b[k, 1] + rot[v, 2, i] * knot_x3_b[k, 2]
    for s in range(surface_origin_b.shape[0]):
        v = surface_vehicle[s]
        for i in range(3):
            origin[s, i] = pos[v, i] + rot[v, 0, i] * surface_origin_b[s, 0] + rot[v, 1, i] * surface_origin_b[s, 1] + rot[v, 2, i] * surface_origin_b[s, 2]


@_jit
def to_ned(rot_v, pos_v, pb, out):
    """out = pos_v + rot_v^T pb (a body-axis point of vehicle v to NED)."""
    for i in range(3):
        out[i] = pos_v[i] + rot_v[0, i] * pb[0] + rot_v[1, i] * pb[1] + rot_v[2, i] * pb[2]


@_jit
def branch_directions(x1, x3, knot_surface, surface_knot_start, bound_dir, chord_dir):
    """Unit directions of every bound vortex X1[k] -> X1[k+1] (zero for a surface's last knot)
    and chordwise branch X3[k] -> X1[k] (zero where the chord vanishes, e.g. a pointed tip)."""
    n_knots = x1.shape[0]
    for k in range(n_knots):
        s = knot_surface[k]
        for i in range(3):
            bound_dir[k, i] = 0.0
            chord_dir[k, i] = 0.0
        if k + 1 < surface_knot_start[s + 1]:
            dx, dy, dz = x1[k + 1, 0] - x1[k, 0], x1[k + 1, 1] - x1[k, 1], x1[k + 1, 2] - x1[k, 2]
            ln = math.sqrt(dx * dx + dy * dy + dz * dz)
            if ln > 0.0:
                bound_dir[k, 0], bound_dir[k, 1], bound_dir[k, 2] = dx / ln, dy / ln, dz / ln
        dx, dy, dz = x1[k, 0] - x3[k, 0], x1[k, 1] - x3[k, 1], x1[k, 2] - x3[k, 2]
        ln = math.sqrt(dx * dx + dy * dy + dz * dz)
        if ln > 0.0:
            chord_dir[k, 0], chord_dir[k, 1], chord_dir[k, 2] = dx / ln, dy / ln, dz / ln


@_jit
def point_to_knots(px, py, pz, x1, x3, k0, k1, r1, inv1, r3, inv3):
    """Vectors from the knots k0..k1-1 to P and their inverse lengths (shared by the up to five
    branches meeting at each knot)."""
    for k in range(k0, k1):
        ax, ay, az = px - x1[k, 0], py - x1[k, 1], pz - x1[k, 2]
        r1[k, 0], r1[k, 1], r1[k, 2] = ax, ay, az
        n = math.sqrt(ax * ax + ay * ay + az * az)
        inv1[k] = 1.0 / n if n > 0.0 else 0.0
        bx, by, bz = px - x3[k, 0], py - x3[k, 1], pz - x3[k, 2]
        r3[k, 0], r3[k, 1], r3[k, 2] = bx, by, bz
        n = math.sqrt(bx * bx + by * by + bz * bz)
        inv3[k] = 1.0 / n if n > 0.0 else 0.0


@_jit
def branch(dx, dy, dz, ax, ay, az, inv_a, bx, by, bz, inv_b, cutoff):
    """Unit-strength straight branch A -> B of unit direction d, seen from P with a = P - A and
    b = P - B: Gamma/(4 pi h) (cos gamma - cos delta) along d x a / h (Eq. 4.35), h clipped at
    ``cutoff`` (Eq. 4.39). A zero direction (zero-length branch) or a point on the line gives 0."""
    cx = dy * az - dz * ay
    cy = dz * ax - dx * az
    cz = dx * ay - dy * ax
    h2 = cx * cx + cy * cy + cz * cz
    if h2 < _TINY_H * _TINY_H:
        return 0.0, 0.0, 0.0
    cos_g = (dx * ax + dy * ay + dz * az) * inv_a
    cos_d = (dx * bx + dy * by + dz * bz) * inv_b
    denom = h2 if h2 >= cutoff * cutoff else math.sqrt(h2) * cutoff
    f = (cos_g - cos_d) / (FOUR_PI * denom)
    return f * cx, f * cy, f * cz


@_jit
def leg(tx, ty, tz, ax, ay, az, inv_a, cutoff, core_radius):
    """Unit-strength semi-infinite trailing leg from A to infinity along t, seen from P (a = P - A);
    viscous core factor 1 - exp(-1.26 (h/rc)^2) when ``core_radius`` > 0, else h clipped at cutoff."""
    cx = ty * az - tz * ay
    cy = tz * ax - tx * az
    cz = tx * ay - ty * ax
    h2 = cx * cx + cy * cy + cz * cz
    if h2 < _TINY_H * _TINY_H:
        return 0.0, 0.0, 0.0
    cos_g = (tx * ax + ty * ay + tz * az) * inv_a
    if core_radius > 0.0:
        x = 1.26 * h2 / (core_radius * core_radius)
        # Beyond x = 40 the factor 1 - exp(-x) rounds to exactly 1.0: skip the exponential.
        core = 1.0 if x > 40.0 else -math.expm1(-x)
        f = (cos_g + 1.0) * core / (FOUR_PI * h2)
    else:
        denom = h2 if h2 >= cutoff * cutoff else math.sqrt(h2) * cutoff
        f = (cos_g + 1.0) / (FOUR_PI * denom)
    return f * cx, f * cy, f * cz


@_jit
def core_radius(px, py, pz, origin, s, airspeed_src, surface_core_scale, core_mode, nu):
    """Viscous core radius of surface s's trailing legs at P: rc = C sqrt(nu tau), vortex age
    tau = |P - surface origin| / V_source; C = 2.24 (Lamb-Oseen, Eq. 4.1) or 36.2 / cos^2 sweep
    (Kurylowich)."""
    ox, oy, oz = px - origin[s, 0], py - origin[s, 1], pz - origin[s, 2]
    tau = math.sqrt(ox * ox + oy * oy + oz * oz) / airspeed_src
    c = LAMB_OSEEN_C if core_mode == CORE_LAMB_OSEEN else KURYLOWICH_C * surface_core_scale[s]
    return max(c * math.sqrt(nu * tau), _MIN_CORE_M)


@_jit
def static_aic(knot_x1_b, knot_x3_b, knot_vehicle, knot_surface, surface_knot_start, panel_left_knot, panel_vehicle,
               control_b, normal_b, cutoff):
    """The part of the AIC that a rigid vehicle's own bound and chordwise branches contribute to its
    own control points: constant in body axes (only the trailing legs follow alpha and beta), so
    it is computed once per make-up. Entries between different vehicles are zero."""
    n_panels = panel_left_knot.shape[0]
    n_knots = knot_x1_b.shape[0]
    out = np.zeros((n_panels, n_panels))
    bound_dir = np.empty((n_knots, 3))
    chord_dir = np.empty((n_knots, 3))
    branch_directions(knot_x1_b, knot_x3_b, knot_surface, surface_knot_start, bound_dir, chord_dir)
    r1 = np.empty((n_knots, 3))
    r3 = np.empty((n_knots, 3))
    inv1 = np.empty(n_knots)
    inv3 = np.empty(n_knots)
    cw = np.empty(n_knots)
    for j in range(n_panels):
        vj = panel_vehicle[j]
        c = control_b[j]
        n = normal_b[j]
        point_to_knots(c[0], c[1], c[2], knot_x1_b, knot_x3_b, 0, n_knots, r1, inv1, r3, inv3)
        for k in range(n_knots):
            sx, sy, sz = branch(chord_dir[k, 0], chord_dir[k, 1], chord_dir[k, 2], r3[k, 0], r3[k, 1], r3[k, 2], inv3[k],
                                r1[k, 0], r1[k, 1], r1[k, 2], inv1[k], cutoff)
            cw[k] = sx * n[0] + sy * n[1] + sz * n[2]
        for p in range(n_panels):
            if panel_vehicle[p] != vj:
                continue
            k = panel_left_knot[p]
            bx, by, bz = branch(bound_dir[k, 0], bound_dir[k, 1], bound_dir[k, 2], r1[k, 0], r1[k, 1], r1[k, 2], inv1[k],
                                r1[k + 1, 0], r1[k + 1, 1], r1[k + 1, 2], inv1[k + 1], cutoff)
            out[j, p] = cw[k] + bx * n[0] + by * n[1] + bz * n[2] - cw[k + 1]
    return out


@_jit
def assemble_and_solve(
    x1, x3, bound_dir, chord_dir, trail, vel, rot, pos, origin, airspeed,
    knot_vehicle, knot_surface, surface_core_scale, panel_left_knot, panel_vehicle,
    control_b, normal_b, aic_static, cutoff, aic_core_mode, nu, aic, gamma, r1, inv1, r3, inv3,
):
    """Build the AIC over every panel of every vehicle and solve for the circulations (4.25-4.69).

    Boundary condition (V_induced + V_inf) . n = 0 with V_inf = -V_vehicle: A G = V_vehicle . n.
    All branches use the plain Biot-Savart law with the Eq. 4.31 cutoff (the thesis), except that
    ``aic_core_mode`` != CORE_NONE gives the *other* vehicles' trailing legs the viscous core of the
    field law, so that a leg passing a control point does not produce a near-singular response.
    A vehicle's own bound and chordwise branches come from ``aic_static`` (see :func:`static_aic`).
    """
    n_panels = panel_left_knot.shape[0]
    n_knots = x1.shape[0]
    cp = np.empty(3)
    nrm = np.empty(3)
    lw = np.empty(n_knots)  # trailing leg . n
    cw = np.empty(n_knots)  # chordwise branch . n (other vehicles' knots only)
    for j in range(n_panels):
        vj = panel_vehicle[j]
        to_ned(rot[vj], pos[vj], control_b[j], cp)
        for i in range(3):
            nrm[i] = rot[vj, 0, i] * normal_b[j, 0] + rot[vj, 1, i] * normal_b[j, 1] + rot[vj, 2, i] * normal_b[j, 2]
        point_to_knots(cp[0], cp[1], cp[2], x1, x3, 0, n_knots, r1, inv1, r3, inv3)
        for k in range(n_knots):
            src = knot_vehicle[k]
            t = trail[src]
            rc = 0.0
            if aic_core_mode != CORE_NONE and src != vj:
                rc = core_radius(cp[0], cp[1], cp[2], origin, knot_surface[k], airspeed[src], surface_core_scale, aic_core_mode, nu)
            lx, ly, lz = leg(t[0], t[1], t[2], r3[k, 0], r3[k, 1], r3[k, 2], inv3[k], cutoff, rc)
            lw[k] = lx * nrm[0] + ly * nrm[1] + lz * nrm[2]
            if src != vj:
                sx, sy, sz = branch(chord_dir[k, 0], chord_dir[k, 1], chord_dir[k, 2], r3[k, 0], r3[k, 1], r3[k, 2],
                                    inv3[k], r1[k, 0], r1[k, 1], r1[k, 2], inv1[k], cutoff)
                cw[k] = sx * nrm[0] + sy * nrm[1] + sz * nrm[2]
        for p in range(n_panels):
            k = panel_left_knot[p]
            if panel_vehicle[p] == vj:
                aic[j, p] = aic_static[j, p] - lw[k] + lw[k + 1]
            else:
                bx, by, bz = branch(bound_dir[k, 0], bound_dir[k, 1], bound_dir[k, 2], r1[k, 0], r1[k, 1], r1[k, 2],
                                    inv1[k], r1[k + 1, 0], r1[k + 1, 1], r1[k + 1, 2], inv1[k + 1], cutoff)
                aic[j, p] = (cw[k] - lw[k]) + bx * nrm[0] + by * nrm[1] + bz * nrm[2] - (cw[k + 1] - lw[k + 1])
        gamma[j] = vel[vj, 0] * nrm[0] + vel[vj, 1] * nrm[1] + vel[vj, 2] * nrm[2]
    lu_solve_inplace(aic, gamma)


@_jit
def field_velocity(
    px, py, pz, vehicle_filter, keep_only,
    x1, x3, bound_dir, chord_dir, trail, origin, airspeed, gamma,
    surface_knot_start, surface_panel_start, surface_vehicle, surface_core_scale,
    cutoff, core_mode, nu, r1, inv1, r3, inv3,
):
    """Velocity induced at one field point by the horseshoes of every vehicle except
    ``vehicle_filter`` (-1 excludes none) or, with ``keep_only``, of that vehicle alone
    (Eqs. 4.70-4.75): bound and chordwise branches plain Biot-Savart (clipped at ``cutoff`` so
    that overlapping vehicles stay finite), trailing legs with the viscous core of age
    tau = |P - source surface origin| / V_source (``core_mode`` 0 plain, 1 Lamb-Oseen,
    2 Kurylowich)."""
    vx = 0.0
    vy = 0.0
    vz = 0.0
    n_surf = surface_vehicle.shape[0]
    for s in range(n_surf):
        src = surface_vehicle[s]
        if (src == vehicle_filter) != keep_only:
            continue
        rc = 0.0
        if core_mode != CORE_NONE:
            rc = core_radius(px, py, pz, origin, s, airspeed[src], surface_core_scale, core_mode, nu)
        t = trail[src]
        k0 = surface_knot_start[s]
        k1 = surface_knot_start[s + 1]
        p0 = surface_panel_start[s]
        point_to_knots(px, py, pz, x1, x3, k0, k1, r1, inv1, r3, inv3)
        for k in range(k0, k1):
            # Net strength of knot k's L-line: +Gamma of the panel on its right, -Gamma of the left one.
            g = 0.0
            if k < k1 - 1:
                g += gamma[p0 + (k - k0)]
            if k > k0:
                g -= gamma[p0 + (k - k0) - 1]
            if g != 0.0:
                lx, ly, lz = leg(t[0], t[1], t[2], r3[k, 0], r3[k, 1], r3[k, 2], inv3[k], cutoff, rc)
                sx, sy, sz = branch(chord_dir[k, 0], chord_dir[k, 1], chord_dir[k, 2], r3[k, 0], r3[k, 1], r3[k, 2],
                                    inv3[k], r1[k, 0], r1[k, 1], r1[k, 2], inv1[k], cutoff)
                vx += g * (sx - lx)
                vy += g * (sy - ly)
                vz += g * (sz - lz)
            if k < k1 - 1:
                gp = gamma[p0 + (k - k0)]
                bx, by, bz = branch(bound_dir[k, 0], bound_dir[k, 1], bound_dir[k, 2], r1[k, 0], r1[k, 1], r1[k, 2],
                                    inv1[k], r1[k + 1, 0], r1[k + 1, 1], r1[k + 1, 2], inv1[k + 1], cutoff)
                vx += gp * bx
                vy += gp * by
                vz += gp * bz
    return vx, vy, vz


@_jit
def posed_lattice(pos, euler, airspeed, alpha, beta, knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
                  surface_origin_b, surface_vehicle, surface_knot_start):
    """Pose one formation's lattice in NED (see :func:`place_lattice`), its branch directions, and
    scratch arrays for the point-to-knot vectors."""
    nv = pos.shape[0]
    n_knots = knot_x1_b.shape[0]
    rot = np.empty((nv, 3, 3))
    vel = np.empty((nv, 3))
    trail = np.empty((nv, 3))
    x1 = np.empty((n_knots, 3))
    x3 = np.empty((n_knots, 3))
    origin = np.empty((surface_origin_b.shape[0], 3))
    place_lattice(pos, euler, airspeed, alpha, beta, knot_x1_b, knot_x3_b, knot_vehicle,
                  surface_origin_b, surface_vehicle, rot, vel, trail, x1, x3, origin)
    bound_dir = np.empty((n_knots, 3))
    chord_dir = np.empty((n_knots, 3))
    branch_directions(x1, x3, knot_surface, surface_knot_start, bound_dir, chord_dir)
    return (rot, vel, trail, x1, x3, origin, bound_dir, chord_dir,
            np.empty((n_knots, 3)), np.empty(n_knots), np.empty((n_knots, 3)), np.empty(n_knots))


@_jit
def evaluate_one(
    pos, euler, airspeed, alpha, beta,
    knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
    surface_origin_b, surface_vehicle, surface_knot_start, surface_panel_start, surface_core_scale,
    panel_left_knot, panel_vehicle, control_b, normal_b, aic_static, eval_b, grad_w, vehicle_panel_start,
    cutoff, core_mode, aic_core_mode, nu,
    gamma_out, vpts_out, wind_ned_out, wind_b_out, omega_b_out, omega_ned_out,
):
    """One formation: pose, joint solve, induced velocity at the evaluation points (other
    vehicles only) and the effective translational and rotational wind per vehicle."""
    nv = pos.shape[0]
    n_panels = panel_left_knot.shape[0]
    rot, vel, trail, x1, x3, origin, bound_dir, chord_dir, r1, inv1, r3, inv3 = posed_lattice(
        pos, euler, airspeed, alpha, beta, knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
        surface_origin_b, surface_vehicle, surface_knot_start)
    aic = np.empty((n_panels, n_panels))
    assemble_and_solve(x1, x3, bound_dir, chord_dir, trail, vel, rot, pos, origin, airspeed, knot_vehicle, knot_surface,
                       surface_core_scale, panel_left_knot, panel_vehicle, control_b, normal_b, aic_static, cutoff,
                       aic_core_mode, nu, aic, gamma_out, r1, inv1, r3, inv3)
    pt = np.empty(3)
    for j in range(n_panels):
        v = panel_vehicle[j]
        to_ned(rot[v], pos[v], eval_b[j], pt)
        wx, wy, wz = field_velocity(pt[0], pt[1], pt[2], v, False, x1, x3, bound_dir, chord_dir, trail, origin,
                                    airspeed, gamma_out, surface_knot_start, surface_panel_start,
                                    surface_vehicle, surface_core_scale, cutoff, core_mode, nu, r1, inv1, r3, inv3)
        vpts_out[j, 0] = wx
        vpts_out[j, 1] = wy
        vpts_out[j, 2] = wz
    # Effective wind (Dogan method, Eqs. 4.4-4.7): mean, and the curl of a linear fit whose
    # weights (least squares or the thesis's finite differences) were precomputed per vehicle.
    grad = np.empty((3, 3))
    for v in range(nv):
        j0 = vehicle_panel_start[v]
        j1 = vehicle_panel_start[v + 1]
        m0 = 0.0
        m1 = 0.0
        m2 = 0.0
        for a in range(3):
            for c in range(3):
                grad[a, c] = 0.0
        for j in range(j0, j1):
            m0 += vpts_out[j, 0]
            m1 += vpts_out[j, 1]
            m2 += vpts_out[j, 2]
            for a in range(3):
                vb = rot[v, a, 0] * vpts_out[j, 0] + rot[v, a, 1] * vpts_out[j, 1] + rot[v, a, 2] * vpts_out[j, 2]
                for c in range(3):
                    grad[a, c] += grad_w[j, c] * vb
        inv = 1.0 / (j1 - j0)
        wind_ned_out[v, 0] = m0 * inv
        wind_ned_out[v, 1] = m1 * inv
        wind_ned_out[v, 2] = m2 * inv
        for a in range(3):
            wind_b_out[v, a] = rot[v, a, 0] * wind_ned_out[v, 0] + rot[v, a, 1] * wind_ned_out[v, 1] + rot[v, a, 2] * wind_ned_out[v, 2]
        # Eq. 4.7 with grad[a, c] = d V_a / d x_c in body axes.
        omega_b_out[v, 0] = grad[2, 1] - grad[1, 2]
        omega_b_out[v, 1] = grad[0, 2] - grad[2, 0]
        omega_b_out[v, 2] = grad[1, 0] - grad[0, 1]
        for i in range(3):
            omega_ned_out[v, i] = rot[v, 0, i] * omega_b_out[v, 0] + rot[v, 1, i] * omega_b_out[v, 1] + rot[v, 2, i] * omega_b_out[v, 2]


def _make_batch(parallel: bool):
    @nb.njit(cache=True, parallel=parallel, error_model="numpy")
    def evaluate_batch(
        pos, euler, airspeed, alpha, beta,
        knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
        surface_origin_b, surface_vehicle, surface_knot_start, surface_panel_start, surface_core_scale,
        panel_left_knot, panel_vehicle, control_b, normal_b, aic_static, eval_b, grad_w, vehicle_panel_start,
        cutoff, core_mode, aic_core_mode, nu,
        gamma_out, vpts_out, wind_ned_out, wind_b_out, omega_b_out, omega_ned_out,
    ):
        for b in nb.prange(pos.shape[0]):
            evaluate_one(
                pos[b], euler[b], airspeed[b], alpha[b], beta[b],
                knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
                surface_origin_b, surface_vehicle, surface_knot_start, surface_panel_start, surface_core_scale,
                panel_left_knot, panel_vehicle, control_b, normal_b, aic_static, eval_b, grad_w, vehicle_panel_start,
                cutoff, core_mode, aic_core_mode, nu,
                gamma_out[b], vpts_out[b], wind_ned_out[b], wind_b_out[b], omega_b_out[b], omega_ned_out[b],
            )

    return evaluate_batch


evaluate_batch_serial = _make_batch(False)
evaluate_batch_parallel = _make_batch(True)


@nb.njit(cache=True, parallel=True, error_model="numpy")
def field_velocity_batch(
    points, vehicle_filter, keep_only, pos, euler, airspeed, alpha, beta, gamma,
    knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
    surface_origin_b, surface_vehicle, surface_knot_start, surface_panel_start, surface_core_scale,
    cutoff, core_mode, nu, out,
):
    """Induced velocity (NED) at arbitrary points (B, P, 3) for solved circulations (B, N);
    ``vehicle_filter`` (P,) and ``keep_only`` as in :func:`field_velocity`."""
    for b in nb.prange(pos.shape[0]):
        rot, vel, trail, x1, x3, origin, bound_dir, chord_dir, r1, inv1, r3, inv3 = posed_lattice(
            pos[b], euler[b], airspeed[b], alpha[b], beta[b], knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
            surface_origin_b, surface_vehicle, surface_knot_start)
        for p in range(points.shape[1]):
            wx, wy, wz = field_velocity(points[b, p, 0], points[b, p, 1], points[b, p, 2], vehicle_filter[p], keep_only,
                                        x1, x3, bound_dir, chord_dir, trail, origin, airspeed[b], gamma[b],
                                        surface_knot_start, surface_panel_start,
                                        surface_vehicle, surface_core_scale, cutoff, core_mode, nu, r1, inv1, r3, inv3)
            out[b, p, 0] = wx
            out[b, p, 1] = wy
            out[b, p, 2] = wz


@_jit
def segment_velocity(p, a, b, cutoff):
    """Velocity (3,) at point p induced by a unit-strength straight vortex a -> b (plain
    Biot-Savart, h clipped at ``cutoff``); a convenience wrapper of :func:`branch` for tests/plots."""
    d = b - a
    ln = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    out = np.zeros(3)
    if ln == 0.0:
        return out
    d = d / ln
    ra = p - a
    rb = p - b
    na = math.sqrt(ra[0] * ra[0] + ra[1] * ra[1] + ra[2] * ra[2])
    nb_ = math.sqrt(rb[0] * rb[0] + rb[1] * rb[1] + rb[2] * rb[2])
    if na == 0.0 or nb_ == 0.0:
        return out
    out[0], out[1], out[2] = branch(d[0], d[1], d[2], ra[0], ra[1], ra[2], 1.0 / na, rb[0], rb[1], rb[2], 1.0 / nb_, cutoff)
    return out


@_jit
def leg_velocity(p, a, t, cutoff, core_radius):
    """Velocity (3,) at p induced by a unit-strength semi-infinite vortex from a along the unit
    vector t; wrapper of :func:`leg` for tests and plots."""
    ra = p - a
    na = math.sqrt(ra[0] * ra[0] + ra[1] * ra[1] + ra[2] * ra[2])
    out = np.zeros(3)
    if na == 0.0:
        return out
    out[0], out[1], out[2] = leg(t[0], t[1], t[2], ra[0], ra[1], ra[2], 1.0 / na, cutoff, core_radius)
    return out
