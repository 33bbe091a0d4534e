"""Compiled posing of a formation's body-axis lattice in NED (the DCM of thesis Eq. 4.10, section
4.3.2): the NED->body DCM of each vehicle, its air-relative velocity and trailing-leg direction, the
knots and surface origins in NED, and the unit directions of every bound and chordwise branch. The
lattice itself is meshed in body axes by :mod:`formation_env.geometry.mesh` (Eqs. 4.11-4.22)."""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from .structs import PosedLattice

__all__ = ["dcm_ned_to_body_1", "place_lattice", "to_ned", "bound_length", "branch_directions", "posed_lattice",
           "PosedLattice"]

_jit = nb.njit(cache=True, fastmath=False, error_model="numpy")


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
def bound_length(x1, k):
    """Length (m) of the bound vortex X1[k] -> X1[k+1]: a receiving panel's width for the sheet law."""
    return np.sqrt((x1[k + 1, 0] - x1[k, 0]) ** 2 + (x1[k + 1, 1] - x1[k, 1]) ** 2 + (x1[k + 1, 2] - x1[k, 2]) ** 2)


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
def posed_lattice(lat, pos, euler, airspeed, alpha, beta):
    """One formation's lattice ``lat`` (a :class:`~formation_env.wake.structs.LatticeArrays`) posed in NED at the
    vehicles' poses and air data (see :func:`place_lattice`), with its branch directions and scratch arrays for
    the point-to-knot vectors: a :class:`PosedLattice`."""
    nv = pos.shape[0]
    n_knots = lat.knot_x1_b.shape[0]
    rot = np.empty((nv, 3, 3))
    vel = np.empty((nv, 3))
    trail = np.empty((nv, 3))
    x1 = np.empty((n_knots, 3))
    x3 = np.empty((n_knots, 3))
    origin = np.empty((lat.surface_origin_b.shape[0], 3))
    place_lattice(pos, euler, airspeed, alpha, beta, lat.knot_x1_b, lat.knot_x3_b, lat.knot_vehicle,
                  lat.surface_origin_b, lat.surface_vehicle, rot, vel, trail, x1, x3, origin)
    bound_dir = np.empty((n_knots, 3))
    chord_dir = np.empty((n_knots, 3))
    branch_directions(x1, x3, lat.knot_surface, lat.surface_knot_start, bound_dir, chord_dir)
    return PosedLattice(pos, airspeed, rot, vel, trail, x1, x3, origin, bound_dir, chord_dir,
                        np.empty((n_knots, 3)), np.empty(n_knots), np.empty((n_knots, 3)), np.empty(n_knots))
