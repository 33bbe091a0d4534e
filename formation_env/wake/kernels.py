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
def segment_velocity(px, py, pz, ax, ay, az, bx, by, bz, cutoff):
    """Velocity at P induced by a unit-strength straight vortex A -> B (Biot-Savart, Eq. 4.35),
    the distance to the branch line clipped from below at ``cutoff`` (Eq. 4.39; 0 = plain)."""
    dx, dy, dz = bx - ax, by - ay, bz - az
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    if length <= 0.0:  # zero-length branch (pointed tip): contributes nothing
        return 0.0, 0.0, 0.0
    dx /= length
    dy /= length
    dz /= length
    r1x, r1y, r1z = px - ax, py - ay, pz - az
    r2x, r2y, r2z = px - bx, py - by, pz - bz
    cx = dy * r1z - dz * r1y
    cy = dz * r1x - dx * r1z
    cz = dx * r1y - dy * r1x
    h = math.sqrt(cx * cx + cy * cy + cz * cz)
    if h < _TINY_H:
        return 0.0, 0.0, 0.0
    n1 = math.sqrt(r1x * r1x + r1y * r1y + r1z * r1z)
    n2 = math.sqrt(r2x * r2x + r2y * r2y + r2z * r2z)
    cos_g = (dx * r1x + dy * r1y + dz * r1z) / n1
    cos_d = (dx * r2x + dy * r2y + dz * r2z) / n2
    f = (cos_g - cos_d) / (FOUR_PI * h * max(h, cutoff))
    return f * cx, f * cy, f * cz


@_jit
def leg_velocity(px, py, pz, ax, ay, az, tx, ty, tz, cutoff, core_radius):
    """Velocity at P induced by a unit-strength semi-infinite vortex starting at A and running to
    infinity along the unit vector t (Eqs. 4.62, 4.75).

    ``core_radius > 0`` applies the viscous core factor 1 - exp(-1.26 (h/rc)^2) (Lamb-Oseen /
    Kurylowich profile); otherwise the plain law with h clipped at ``cutoff``.
    """
    r1x, r1y, r1z = px - ax, py - ay, pz - az
    cx = ty * r1z - tz * r1y
    cy = tz * r1x - tx * r1z
    cz = tx * r1y - ty * r1x
    h2 = cx * cx + cy * cy + cz * cz
    h = math.sqrt(h2)
    if h < _TINY_H:
        return 0.0, 0.0, 0.0
    n1 = math.sqrt(r1x * r1x + r1y * r1y + r1z * r1z)
    cos_g = (tx * r1x + ty * r1y + tz * r1z) / n1
    if core_radius > 0.0:
        f = (cos_g + 1.0) * (-math.expm1(-1.26 * h2 / (core_radius * core_radius))) / (FOUR_PI * h2)
    else:
        f = (cos_g + 1.0) / (FOUR_PI * h * max(h, cutoff))
    return f * cx, f * cy, f * cz


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
def assemble_and_solve(
    x1, x3, trail, vel, rot, pos,
    knot_vehicle, knot_surface, surface_knot_start, panel_left_knot, panel_vehicle,
    control_b, normal_b, cutoff, aic, gamma,
):
    """Build the AIC over every panel of every vehicle and solve for the circulations (4.25-4.69).

    Boundary condition (V_induced + V_inf) . n = 0 with V_inf = -V_vehicle: A G = V_vehicle . n.
    All branches use the plain Biot-Savart law with the Eq. 4.31 cutoff.
    """
    n_panels = panel_left_knot.shape[0]
    n_knots = x1.shape[0]
    cp = np.empty(3)
    nrm = np.empty(3)
    wl = np.empty(n_knots)
    for j in range(n_panels):
        vj = panel_vehicle[j]
        to_ned(rot[vj], pos[vj], control_b[j], cp)
        for i in range(3):
            nrm[i] = rot[vj, 0, i] * normal_b[j, 0] + rot[vj, 1, i] * normal_b[j, 1] + rot[vj, 2, i] * normal_b[j, 2]
        # L-lines of every knot, projected on the normal.
        for k in range(n_knots):
            t = trail[knot_vehicle[k]]
            lx, ly, lz = leg_velocity(cp[0], cp[1], cp[2], x3[k, 0], x3[k, 1], x3[k, 2], t[0], t[1], t[2], cutoff, 0.0)
            sx, sy, sz = segment_velocity(cp[0], cp[1], cp[2], x3[k, 0], x3[k, 1], x3[k, 2], x1[k, 0], x1[k, 1], x1[k, 2], cutoff)
            wl[k] = (sx - lx) * nrm[0] + (sy - ly) * nrm[1] + (sz - lz) * nrm[2]
        for p in range(n_panels):
            k = panel_left_knot[p]
            bx, by, bz = segment_velocity(cp[0], cp[1], cp[2], x1[k, 0], x1[k, 1], x1[k, 2], x1[k + 1, 0], x1[k + 1, 1], x1[k + 1, 2], cutoff)
            aic[j, p] = wl[k] + bx * nrm[0] + by * nrm[1] + bz * nrm[2] - wl[k + 1]
        gamma[j] = vel[vj, 0] * nrm[0] + vel[vj, 1] * nrm[1] + vel[vj, 2] * nrm[2]
    lu_solve_inplace(aic, gamma)


@_jit
def field_velocity(
    px, py, pz, vehicle_filter, keep_only,
    x1, x3, trail, origin, airspeed, gamma,
    knot_vehicle, knot_surface, surface_knot_start, surface_panel_start, surface_vehicle, surface_core_scale,
    cutoff, core_mode, nu,
):
    """Velocity induced at one field point by the horseshoes of every vehicle except
    ``vehicle_filter`` (-1 excludes none) or, with ``keep_only``, of that vehicle alone
    (Eqs. 4.70-4.75): bound and chordwise branches plain Biot-Savart (clipped at
    ``cutoff`` so that overlapping vehicles stay finite), trailing legs with the viscous core of
    age tau = |P - source surface origin| / V_source (``core_mode`` 0 plain, 1 Lamb-Oseen,
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
            ox, oy, oz = px - origin[s, 0], py - origin[s, 1], pz - origin[s, 2]
            tau = math.sqrt(ox * ox + oy * oy + oz * oz) / airspeed[src]
            c = LAMB_OSEEN_C if core_mode == CORE_LAMB_OSEEN else KURYLOWICH_C * surface_core_scale[s]
            rc = max(c * math.sqrt(nu * tau), _MIN_CORE_M)
        t = trail[src]
        k0 = surface_knot_start[s]
        k1 = surface_knot_start[s + 1]
        p0 = surface_panel_start[s]
        for k in range(k0, k1):
            # Net strength of knot k's L-line: +Gamma of the panel on its right, -Gamma of the left one.
            g = 0.0
            if k < k1 - 1:
                g += gamma[p0 + (k - k0)]
            if k > k0:
                g -= gamma[p0 + (k - k0) - 1]
            if g != 0.0:
                lx, ly, lz = leg_velocity(px, py, pz, x3[k, 0], x3[k, 1], x3[k, 2], t[0], t[1], t[2], cutoff, rc)
                sx, sy, sz = segment_velocity(px, py, pz, x3[k, 0], x3[k, 1], x3[k, 2], x1[k, 0], x1[k, 1], x1[k, 2], cutoff)
                vx += g * (sx - lx)
                vy += g * (sy - ly)
                vz += g * (sz - lz)
            if k < k1 - 1:
                gp = gamma[p0 + (k - k0)]
                bx, by, bz = segment_velocity(px, py, pz, x1[k, 0], x1[k, 1], x1[k, 2], x1[k + 1, 0], x1[k + 1, 1], x1[k + 1, 2], cutoff)
                vx += gp * bx
                vy += gp * by
                vz += gp * bz
    return vx, vy, vz


@_jit
def evaluate_one(
    pos, euler, airspeed, alpha, beta,
    knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
    surface_origin_b, surface_vehicle, surface_knot_start, surface_panel_start, surface_core_scale,
    panel_left_knot, panel_vehicle, control_b, normal_b, eval_b, grad_w, vehicle_panel_start,
    cutoff, core_mode, nu,
    gamma_out, vpts_out, wind_ned_out, wind_b_out, omega_b_out, omega_ned_out,
):
    """One formation: pose, joint solve, induced velocity at the evaluation points (other
    vehicles only) and the effective translational and rotational wind per vehicle."""
    nv = pos.shape[0]
    n_knots = knot_x1_b.shape[0]
    n_panels = panel_left_knot.shape[0]
    n_surf = surface_origin_b.shape[0]
    rot = np.empty((nv, 3, 3))
    vel = np.empty((nv, 3))
    trail = np.empty((nv, 3))
    x1 = np.empty((n_knots, 3))
    x3 = np.empty((n_knots, 3))
    origin = np.empty((n_surf, 3))
    place_lattice(pos, euler, airspeed, alpha, beta, knot_x1_b, knot_x3_b, knot_vehicle,
                  surface_origin_b, surface_vehicle, rot, vel, trail, x1, x3, origin)
    aic = np.empty((n_panels, n_panels))
    assemble_and_solve(x1, x3, trail, vel, rot, pos, knot_vehicle, knot_surface, surface_knot_start,
                       panel_left_knot, panel_vehicle, control_b, normal_b, cutoff, aic, gamma_out)
    pt = np.empty(3)
    for j in range(n_panels):
        v = panel_vehicle[j]
        to_ned(rot[v], pos[v], eval_b[j], pt)
        wx, wy, wz = field_velocity(pt[0], pt[1], pt[2], v, False, x1, x3, trail, origin, airspeed, gamma_out,
                                    knot_vehicle, knot_surface, surface_knot_start, surface_panel_start,
                                    surface_vehicle, surface_core_scale, cutoff, core_mode, nu)
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
        panel_left_knot, panel_vehicle, control_b, normal_b, eval_b, grad_w, vehicle_panel_start,
        cutoff, core_mode, nu,
        gamma_out, vpts_out, wind_ned_out, wind_b_out, omega_b_out, omega_ned_out,
    ):
        for b in nb.prange(pos.shape[0]):
            evaluate_one(
                pos[b], euler[b], airspeed[b], alpha[b], beta[b],
                knot_x1_b, knot_x3_b, knot_vehicle, knot_surface,
                surface_origin_b, surface_vehicle, surface_knot_start, surface_panel_start, surface_core_scale,
                panel_left_knot, panel_vehicle, control_b, normal_b, eval_b, grad_w, vehicle_panel_start,
                cutoff, core_mode, nu,
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
    nb_ = pos.shape[0]
    nv = pos.shape[1]
    n_knots = knot_x1_b.shape[0]
    n_surf = surface_origin_b.shape[0]
    for b in nb.prange(nb_):
        rot = np.empty((nv, 3, 3))
        vel = np.empty((nv, 3))
        trail = np.empty((nv, 3))
        x1 = np.empty((n_knots, 3))
        x3 = np.empty((n_knots, 3))
        origin = np.empty((n_surf, 3))
        place_lattice(pos[b], euler[b], airspeed[b], alpha[b], beta[b], knot_x1_b, knot_x3_b, knot_vehicle,
                      surface_origin_b, surface_vehicle, rot, vel, trail, x1, x3, origin)
        for p in range(points.shape[1]):
            wx, wy, wz = field_velocity(points[b, p, 0], points[b, p, 1], points[b, p, 2], vehicle_filter[p], keep_only,
                                        x1, x3, trail, origin, airspeed[b], gamma[b],
                                        knot_vehicle, knot_surface, surface_knot_start, surface_panel_start,
                                        surface_vehicle, surface_core_scale, cutoff, core_mode, nu)
            out[b, p, 0] = wx
            out[b, p, 1] = wy
            out[b, p, 2] = wz
