"""Compiled Biot-Savart laws of the ELL (thesis sections 4.2.2 and 4.3.6): a straight vortex branch
(Eq. 4.35, h clipped at the cutoff of Eq. 4.31 as in Eq. 4.39), a semi-infinite trailing leg (Eqs. 4.56
and 4.62; plain, or with the viscous core factor 1 - exp(-1.26 (h / rc)^2) of Eq. 4.1), the core
radius rc = C sqrt(nu tau), and the shared point-to-knot vectors; and the overlap core of the other
vehicles' branches (:func:`branch_cored`, :func:`leg_cored`; not in the thesis, docs/ell.md). Unit
strength; metres, m/s."""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["branch", "branch_cored", "leg", "leg_cored", "core_radius", "point_to_knots", "point_to_knots3", "segment_velocity", "leg_velocity",
           "FOUR_PI", "CORE_NONE", "CORE_LAMB_OSEEN", "CORE_KURYLOWICH", "LAMB_OSEEN_C", "KURYLOWICH_C",
           "OVERLAP_CORE_CHORD_FRACTION", "CORE_PEAK", "leg_sheet", "leg_sheet_framed", "strip_frame", "strip_frames",
           "STRIP_COLUMNS", "sheet_strip_frames", "SHEET_BLEND_INNER", "SHEET_ON", "SHEET_OFF", "sheet_on",
           "SHEET_BLEND_OUTER"]

FOUR_PI = 4.0 * math.pi
CORE_NONE, CORE_LAMB_OSEEN, CORE_KURYLOWICH = 0, 1, 2
# Core-radius constants rc = C sqrt(nu tau): Lamb-Oseen 2.24 (Eq. 4.1), Kurylowich 36.2 / cos^2(sweep)
# (chapters 3 and 7); the viscous factor is 1 - exp(-1.26 (h / rc)^2).
LAMB_OSEEN_C = 2.24
KURYLOWICH_C = 36.2
# The overlap core (:func:`branch_cored`, :func:`leg_cored`): another vehicle's lifting surface is
# seen through a core of radius r_o = OVERLAP_CORE_CHORD_FRACTION x the largest mean chord b / AR of
# the make-up (``WakeModel.overlap_core_m``; 0.193 m for the Aerosonde) about its bound and chordwise
# segments and the starts of its trailing legs, and its trailing legs keep a viscous core of at
# least the Eq. 4.31 cutoff eps. Overlapping or coincident vehicles then stay physical (the joint
# solve stays well conditioned; |v| <= CORE_PEAK / (2 pi min(r_o, eps)) per unit strength and
# branch) while farther than ~3 r_o from the other's wing the law is the thesis's.
# A vehicle's own branches on its own points keep the thesis's plain law with the Eq. 4.31 cutoff.
OVERLAP_CORE_CHORD_FRACTION = 1.0
# The sheet law of the other vehicles' trailing legs (:func:`leg_sheet`; ``WakeModel(sheet=True)``, off by
# default: the thesis): within SHEET_BLEND_INNER strip widths of a leg's line its strength is spread over
# its strip (a continuous sheet), beyond SHEET_BLEND_OUTER it is the discrete leg; smooth blend between.
# A strip and a leg differ by O((w / rho)^2) ~ 1 % at 3 widths, and the discrete sheet's ripple decays
# as exp(-2 pi rho / w) (1e-8 at 3 widths), so nothing beyond is changed (docs/ell.md "Converged saving").
SHEET_BLEND_INNER = 4.0
SHEET_BLEND_OUTER = 6.0
# The kernels' switch for the sheet law, a float: SHEET_ON, or SHEET_OFF for the thesis's legs. A value rather than
# a type, so that one compiled kernel serves both (the vectorised lane loops take it as a mask, the scalar laws as a
# branch). None is the thesis's too (:func:`sheet_on`), for callers of the kernels that pass no switch.
SHEET_ON = 1.0
SHEET_OFF = 0.0
# max over x of (1 - exp(-1.26 x^2)) / x (at x ~ 1.0): the peak of the cored law is
# CORE_PEAK / (2 pi rc) per unit strength for a semi-infinite or a finite straight branch.
CORE_PEAK = 0.71635
_TINY_H = 1e-12  # below this distance a point lies on the branch line: no contribution
_MIN_CORE_M = 1e-9

# forceinline=False: a kernel compiled for one of the laws below must not inherit their forceinline
_jit = nb.njit(cache=True, fastmath=False, error_model="numpy", forceinline=False)
# The per-branch laws run ~2,000 times per formation solve: always inlined (LLVM's own cost model left the cored
# variants as calls in the field and AIC loops, which slowed a solve). Inlined by LLVM (``forceinline``: the
# alwaysinline attribute) rather than at numba IR level (``inline="always"``): numba's IR inliner reruns its front
# end at every call site, which was most of the wake's compile time; the operations and their order are the same.
_jit_inline = nb.njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)


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
def point_to_knots3(px, py, pz, x3, k0, k1, r3, inv3):
    """:func:`point_to_knots` for the 3/4-chord knots only (a vehicle's own trailing legs at its own control
    points need nothing else): the same values."""
    for k in range(k0, k1):
        bx, by, bz = px - x3[k, 0], py - x3[k, 1], pz - x3[k, 2]
        r3[k, 0], r3[k, 1], r3[k, 2] = bx, by, bz
        n = math.sqrt(bx * bx + by * by + bz * bz)
        inv3[k] = 1.0 / n if n > 0.0 else 0.0


@_jit_inline
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


@_jit_inline
def _overlap_factor(rho2, overlap_core):
    """1 - exp(-1.26 (rho / r_o)^2): the overlap core's factor at squared distance rho2. Beyond
    x = 1.26 rho^2 / r_o^2 = 40 it rounds to exactly 1.0: tested without a division (the usual case,
    every branch farther than ~5.6 r_o)."""
    r2 = overlap_core * overlap_core
    if 1.26 * rho2 > 40.0 * r2:
        return 1.0
    return -math.expm1(-(1.26 * rho2 / r2))


@_jit_inline
def branch_cored(dx, dy, dz, ax, ay, az, inv_a, bx, by, bz, inv_b, cutoff, overlap_core):
    """:func:`branch` as another vehicle's bound or chordwise branch: the Biot-Savart law (no cutoff)
    times the overlap core 1 - exp(-1.26 (rho / r_o)^2), rho the distance from P to the *segment*
    (its closest point: h beside it, the distance to the nearer end beyond its ends). So the law
    is the plain one (to exp(-1.26 (rho/r_o)^2)) farther than ~3 r_o from the segment itself, even
    on its line's extension, and |v| <= CORE_PEAK / (2 pi r_o) per unit strength anywhere.
    ``overlap_core`` <= 0: :func:`branch` (the thesis's law with the cutoff)."""
    if overlap_core <= 0.0:
        return branch(dx, dy, dz, ax, ay, az, inv_a, bx, by, bz, inv_b, cutoff)
    cx = dy * az - dz * ay
    cy = dz * ax - dx * az
    cz = dx * ay - dy * ax
    h2 = cx * cx + cy * cy + cz * cz
    if h2 < _TINY_H * _TINY_H:
        return 0.0, 0.0, 0.0
    sa = dx * ax + dy * ay + dz * az  # d . (P - A): > 0 downstream of A
    sb = dx * bx + dy * by + dz * bz  # d . (P - B): < 0 upstream of B
    # squared distance to the segment: h^2 beside it, |a|^2 = h^2 + sa^2 before A, |b|^2 = h^2 + sb^2
    # beyond B (d is a unit vector); min/max rather than branches, which mispredict in this hot loop
    ma = min(sa, 0.0)
    mb = max(sb, 0.0)
    rho2 = h2 + ma * ma + mb * mb
    core = _overlap_factor(rho2, overlap_core)
    if core == 1.0:
        f = (sa * inv_a - sb * inv_b) / (FOUR_PI * h2)
    else:
        f = (sa * inv_a - sb * inv_b) * core / (FOUR_PI * h2)
    return f * cx, f * cy, f * cz


@_jit_inline
def leg_cored(tx, ty, tz, ax, ay, az, inv_a, cutoff, core_radius, overlap_core):
    """:func:`leg` as another vehicle's trailing leg: the viscous core of radius max(``core_radius``,
    ``cutoff``) (so never thinner than the Eq. 4.31 cutoff eps: |v| <= CORE_PEAK / (2 pi eps) per
    unit strength), times the overlap core 1 - exp(-1.26 (|P - A| / r_o)^2) about the leg's start A
    (the source's 3/4-chord knot), which is 1 farther than ~3 r_o from the source's lifting surface.
    ``overlap_core`` <= 0: :func:`leg` (the law without the overlap core)."""
    if overlap_core <= 0.0:
        return leg(tx, ty, tz, ax, ay, az, inv_a, cutoff, core_radius)
    vx, vy, vz = leg(tx, ty, tz, ax, ay, az, inv_a, cutoff, max(core_radius, cutoff))
    f = _overlap_factor(ax * ax + ay * ay + az * az, overlap_core)
    if f == 1.0:
        return vx, vy, vz
    return f * vx, f * vy, f * vz


@_jit_inline
def _strip_h(x, c):
    """The primitives at x of the panel-averaged strip law (:func:`leg_sheet`): H_n = (x ln(x^2 + c^2)
    + 2 c atan(x / c)) / 2 without its linear term (it cancels in the four-point sum), and H_e = (x / c)
    atan(x / c) - ln(x^2 + c^2) / 2 (c > 0)."""
    at = math.atan(x / c)
    lg = math.log(x * x + c * c)
    return 0.5 * x * lg + c * at, (x / c) * at - 0.5 * lg


@_jit_inline
def _strip_g(x, c):
    """The primitives at x of the point-sampled strip law: G_n = ln(x^2 + c^2) / 2, G_e = atan(x / c) / c."""
    return 0.5 * math.log(x * x + c * c), math.atan(x / c) / c


# The strip frame of a knot (:func:`strip_frame`): the columns of one row of ``strip_frames``.
STRIP_OK, STRIP_EX, STRIP_EY, STRIP_EZ, STRIP_NX, STRIP_NY, STRIP_NZ, STRIP_W_LO, STRIP_W_HI, STRIP_W, STRIP_SC = range(11)
STRIP_COLUMNS = 11


@_jit_inline
def strip_frame(tx, ty, tz, x3, k, has_lo, has_hi, out):
    """The strip of the trailing leg at knot k (unit direction t; x3 the posed 3/4-chord knots; ``has_lo`` /
    ``has_hi`` as :func:`leg_sheet`'s) into ``out`` (STRIP_COLUMNS,): the strip's unit direction e across the
    leg (perpendicular to t, from the neighbouring knots), n = t x e, the half-widths to the previous and next
    knot w_lo, w_hi, the width w and the centre's offset sc = (w_hi - w_lo) / 2 along e, m; out[STRIP_OK] 1.0
    where the strip exists (0.0: a degenerate strip, the leg takes :func:`leg_cored`). It depends on the knot
    alone, not on the point the leg is seen from: computed once per knot and solve (issue 26), every value
    the same operations in the same order as :func:`leg_sheet` made them per point."""
    lo_x = lo_y = lo_z = hi_x = hi_y = hi_z = 0.0
    if has_lo:
        lo_x, lo_y, lo_z = x3[k - 1, 0] - x3[k, 0], x3[k - 1, 1] - x3[k, 1], x3[k - 1, 2] - x3[k, 2]
    if has_hi:
        hi_x, hi_y, hi_z = x3[k + 1, 0] - x3[k, 0], x3[k + 1, 1] - x3[k, 1], x3[k + 1, 2] - x3[k, 2]
    ex, ey, ez = hi_x - lo_x, hi_y - lo_y, hi_z - lo_z
    et = ex * tx + ey * ty + ez * tz
    ex, ey, ez = ex - et * tx, ey - et * ty, ez - et * tz
    en = math.sqrt(ex * ex + ey * ey + ez * ez)
    if en < _TINY_H:
        out[STRIP_OK] = 0.0
        return
    ex, ey, ez = ex / en, ey / en, ez / en
    w_lo = -0.5 * (lo_x * ex + lo_y * ey + lo_z * ez)  # >= 0: half-way to the previous knot along -e
    w_hi = 0.5 * (hi_x * ex + hi_y * ey + hi_z * ez)
    w = w_lo + w_hi
    out[STRIP_OK] = 0.0 if w <= 0.0 else 1.0  # (a NaN width goes on, as the per-point law did)
    out[STRIP_EX], out[STRIP_EY], out[STRIP_EZ] = ex, ey, ez
    out[STRIP_NX], out[STRIP_NY], out[STRIP_NZ] = ty * ez - tz * ey, tz * ex - tx * ez, tx * ey - ty * ex
    out[STRIP_W_LO], out[STRIP_W_HI], out[STRIP_W] = w_lo, w_hi, w
    out[STRIP_SC] = 0.5 * (w_hi - w_lo)


@_jit
def strip_frames(trail, x3, knot_vehicle, knot_surface, out):
    """:func:`strip_frame` of every knot of a posed lattice into ``out`` (K, STRIP_COLUMNS); trail (V, 3) the
    vehicles' unit trailing-leg directions, x3 (K, 3) the posed 3/4-chord knots, NED."""
    n_knots = x3.shape[0]
    for k in range(n_knots):
        t = trail[knot_vehicle[k]]
        strip_frame(t[0], t[1], t[2], x3, k, k > 0 and knot_surface[k - 1] == knot_surface[k],
                    k < n_knots - 1 and knot_surface[k + 1] == knot_surface[k], out[k])


@_jit_inline
def sheet_on(sheet):
    """Whether the kernels' ``sheet`` switch (:data:`SHEET_ON`, :data:`SHEET_OFF` or None) turns the sheet law
    on: None compiles to a constant False."""
    if sheet is None:
        return False
    return sheet != SHEET_OFF


@_jit
def sheet_strip_frames(sheet, trail, x3, knot_vehicle, knot_surface):
    """The strips of a posed lattice's knots for the kernels' ``sheet`` switch: :func:`strip_frames` in a new (K,
    STRIP_COLUMNS) array with the sheet law on (:func:`sheet_on`), an empty (0, STRIP_COLUMNS) one without it."""
    on = sheet_on(sheet)
    out = np.empty((x3.shape[0] if on else 0, STRIP_COLUMNS))
    if on:
        strip_frames(trail, x3, knot_vehicle, knot_surface, out)
    return out


@_jit_inline
def leg_sheet(tx, ty, tz, ax, ay, az, inv_a, cutoff, core_radius, overlap_core, x3, k, has_lo, has_hi, recv_w):
    """The sheet law of another vehicle's trailing leg at knot k, seen from P (x3 the posed 3/4-chord
    knots, a = P - x3[k]; ``has_lo`` / ``has_hi``: knot k - 1 / k + 1 is of the same surface), averaged
    over the receiving bound segment through P of width ``recv_w`` (m, along the source's span; 0: at P).

    Near the wake plane (within SHEET_BLEND_INNER widths of the leg's line) the leg's strength is spread
    uniformly over its strip, from half-way to the previous knot to half-way to the next (a tip knot: to
    half-way to its neighbour only), i.e. the discrete sheet becomes the continuous one of the circulation
    interpolated linearly between the panel midpoints (and to zero at the tips); and
    the field is averaged over the receiving segment (what its Kutta-Joukowski force, its effective
    wind and a flow-tangency condition over its span see), so a coarse receiving lattice does not
    point-sample the sheet's sharp tip. Both in the 2-D law of the plane normal to t with the algebraic
    core delta (1 / rho^2 -> 1 / (rho^2 + delta^2), delta = max(``core_radius``, ``cutoff``)), closed form
    (:func:`_strip_h`), times the 3-D factor (1 + cos gamma) / (4 pi) of the strip's centre; the
    receiving segment is taken parallel to the strip. Beyond SHEET_BLEND_OUTER widths it is
    :func:`leg_cored` (they differ by O((width / distance)^2) there), with a smooth blend between.
    Times the overlap core about the knot as :func:`leg_cored`. Unit strength.

    The strip (:func:`strip_frame`) depends on the knot only: the solve and the field compute it once per knot
    (:func:`strip_frames`) and call :func:`leg_sheet_framed`, bit for bit this law."""
    fr = np.empty(STRIP_COLUMNS)
    strip_frame(tx, ty, tz, x3, k, has_lo, has_hi, fr)
    return leg_sheet_framed(tx, ty, tz, ax, ay, az, inv_a, cutoff, core_radius, overlap_core, fr, recv_w)


@_jit_inline
def leg_sheet_framed(tx, ty, tz, ax, ay, az, inv_a, cutoff, core_radius, overlap_core, fr, recv_w):
    """:func:`leg_sheet` with the knot's strip ``fr`` (a row of :func:`strip_frames`) computed beforehand."""
    if fr[STRIP_OK] == 0.0:
        return leg_cored(tx, ty, tz, ax, ay, az, inv_a, cutoff, core_radius, overlap_core)
    w = fr[STRIP_W]
    scale = max(w, recv_w)
    outer = SHEET_BLEND_OUTER * scale
    ta = tx * ax + ty * ay + tz * az
    rp2 = max(ax * ax + ay * ay + az * az - ta * ta, 0.0)  # squared distance to the leg's line
    if rp2 >= outer * outer:
        return leg_cored(tx, ty, tz, ax, ay, az, inv_a, cutoff, core_radius, overlap_core)
    ex, ey, ez = fr[STRIP_EX], fr[STRIP_EY], fr[STRIP_EZ]
    nx, ny, nz = fr[STRIP_NX], fr[STRIP_NY], fr[STRIP_NZ]
    w_lo, w_hi = fr[STRIP_W_LO], fr[STRIP_W_HI]
    eta = ax * ex + ay * ey + az * ez
    zeta = ax * nx + ay * ny + az * nz
    dc = max(core_radius, cutoff)
    c = math.sqrt(zeta * zeta + dc * dc)
    if recv_w > 1e-9 * w:
        h = 0.5 * recv_w
        n1, e1 = _strip_h(eta + w_lo + h, c)
        n2, e2 = _strip_h(eta + w_lo - h, c)
        n3, e3 = _strip_h(eta - w_hi + h, c)
        n4, e4 = _strip_h(eta - w_hi - h, c)
        i_n = (n1 - n2 - n3 + n4) / recv_w
        i_e = (e1 - e2 - e3 + e4) / recv_w
    else:
        n1, e1 = _strip_g(eta + w_lo, c)
        n2, e2 = _strip_g(eta - w_hi, c)
        i_n = n1 - n2
        i_e = e1 - e2
    # 3-D factor (1 + cos gamma) / (4 pi) of the strip's centre, per unit strength (density 1 / w)
    sc = fr[STRIP_SC]
    cx, cy, cz = ax - sc * ex, ay - sc * ey, az - sc * ez
    rc2 = cx * cx + cy * cy + cz * cz
    cos_g = (tx * cx + ty * cy + tz * cz) / math.sqrt(rc2) if rc2 > 0.0 else 0.0
    f = (1.0 + cos_g) / (FOUR_PI * w)
    vx = f * (i_n * nx - zeta * i_e * ex)
    vy = f * (i_n * ny - zeta * i_e * ey)
    vz = f * (i_n * nz - zeta * i_e * ez)
    if overlap_core > 0.0:
        o = _overlap_factor(ax * ax + ay * ay + az * az, overlap_core)
        vx, vy, vz = o * vx, o * vy, o * vz
    inner = SHEET_BLEND_INNER * scale
    if rp2 <= inner * inner:
        return vx, vy, vz
    u = (math.sqrt(rp2) - inner) / (outer - inner)
    lam = 1.0 - u * u * (3.0 - 2.0 * u)  # smoothstep from the sheet (inner) to the leg (outer)
    lx, ly, lz = leg_cored(tx, ty, tz, ax, ay, az, inv_a, cutoff, core_radius, overlap_core)
    return lam * vx + (1.0 - lam) * lx, lam * vy + (1.0 - lam) * ly, lam * vz + (1.0 - lam) * lz


@_jit_inline
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
