"""Reference frames and rotations: the one module that owns them.

Conventions used everywhere in formation-env:

* Earth frame: flat-earth **NED** (x north, y east, z down), metres.
* Body frame: x forward (nose), y starboard (right wing), z down.
* Euler angles: 3-2-1 (yaw psi, then pitch theta, then roll phi), radians, stored as
  ``(phi, theta, psi)`` along the last axis.
* ``dcm_ned_to_body(euler)`` is the thesis's DCM_be (Eq. 4.10): ``v_body = C @ v_ned``.
  Its transpose takes body vectors to NED.
* Quaternions are scalar-first ``(e0, ex, ey, ez)`` and rotate body to NED.
* Track frame: x forward along a ground track at angle chi from north (positive east), y to
  starboard, z down (slot offsets, the slot frame, the turbulence field's u, v, w). It is the NED
  frame turned by chi about the down axis: :func:`track_frame_offset_to_ned` /
  :func:`ned_to_track_frame` (numpy) and the compiled scalar forms :func:`track_to_ned_xy` /
  :func:`ned_to_track_xy` (the down component is the same in both frames).

Every function accepts arrays with any number of leading (batch) axes.
"""

from __future__ import annotations

import numba as nb
import numpy as np

__all__ = [
    "dcm_ned_to_body",
    "euler_from_dcm",
    "quaternion_from_euler",
    "euler_from_quaternion",
    "dcm_body_to_ned_from_quaternion",
    "wind_axes_velocity_body",
    "quaternion_dcm_terms",
    "track_frame_offset_to_ned",
    "ned_to_track_frame",
    "track_to_ned_xy",
    "ned_to_track_xy",
]


def dcm_ned_to_body(euler_rad: np.ndarray) -> np.ndarray:
    """Direction cosine matrix from NED to body axes (thesis Eq. 4.10).

    ``euler_rad[..., :] = (phi, theta, psi)``; returns an array of shape ``(..., 3, 3)``.
    """
    euler_rad = np.asarray(euler_rad, dtype=float)
    phi, theta, psi = euler_rad[..., 0], euler_rad[..., 1], euler_rad[..., 2]
    cph, sph = np.cos(phi), np.sin(phi)
    cth, sth = np.cos(theta), np.sin(theta)
    cps, sps = np.cos(psi), np.sin(psi)
    c = np.empty(euler_rad.shape[:-1] + (3, 3))
    c[..., 0, 0] = cth * cps
    c[..., 0, 1] = cth * sps
    c[..., 0, 2] = -sth
    c[..., 1, 0] = sph * sth * cps - cph * sps
    c[..., 1, 1] = sph * sth * sps + cph * cps
    c[..., 1, 2] = sph * cth
    c[..., 2, 0] = cph * sth * cps + sph * sps
    c[..., 2, 1] = cph * sth * sps - sph * cps
    c[..., 2, 2] = cph * cth
    return c


def euler_from_dcm(c: np.ndarray) -> np.ndarray:
    """Inverse of :func:`dcm_ned_to_body`: 3-2-1 Euler angles ``(phi, theta, psi)``.

    theta is in [-pi/2, pi/2]; phi and psi in (-pi, pi].
    """
    c = np.asarray(c, dtype=float)
    theta = -np.arcsin(np.clip(c[..., 0, 2], -1.0, 1.0))
    phi = np.arctan2(c[..., 1, 2], c[..., 2, 2])
    psi = np.arctan2(c[..., 0, 1], c[..., 0, 0])
    return np.stack([phi, theta, psi], axis=-1)


def quaternion_from_euler(euler_rad: np.ndarray) -> np.ndarray:
    """Scalar-first unit quaternion (body to NED) from 3-2-1 Euler angles."""
    euler_rad = np.asarray(euler_rad, dtype=float)
    h = 0.5 * euler_rad
    cph, sph = np.cos(h[..., 0]), np.sin(h[..., 0])
    cth, sth = np.cos(h[..., 1]), np.sin(h[..., 1])
    cps, sps = np.cos(h[..., 2]), np.sin(h[..., 2])
    return np.stack(
        [
            cph * cth * cps + sph * sth * sps,
            sph * cth * cps - cph * sth * sps,
            cph * sth * cps + sph * cth * sps,
            cph * cth * sps - sph * sth * cps,
        ],
        axis=-1,
    )


def euler_from_quaternion(q: np.ndarray) -> np.ndarray:
    """3-2-1 Euler angles ``(phi, theta, psi)`` from a scalar-first quaternion (need not be unit)."""
    q = np.asarray(q, dtype=float)
    e0, ex, ey, ez = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    n2 = e0 * e0 + ex * ex + ey * ey + ez * ez
    phi = np.arctan2(2.0 * (e0 * ex + ey * ez), e0 * e0 - ex * ex - ey * ey + ez * ez)
    theta = np.arcsin(np.clip(2.0 * (e0 * ey - ex * ez) / n2, -1.0, 1.0))
    psi = np.arctan2(2.0 * (ex * ey + e0 * ez), e0 * e0 + ex * ex - ey * ey - ez * ez)
    return np.stack([phi, theta, psi], axis=-1)


def dcm_body_to_ned_from_quaternion(q: np.ndarray) -> np.ndarray:
    """Body-to-NED rotation matrix built from a scalar-first quaternion as stored (not renormalised)."""
    q = np.asarray(q, dtype=float)
    e0, ex, ey, ez = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    r = np.empty(q.shape[:-1] + (3, 3))
    r[..., 0, 0] = e0 * e0 + ex * ex - ey * ey - ez * ez
    r[..., 0, 1] = 2.0 * (ex * ey - e0 * ez)
    r[..., 0, 2] = 2.0 * (ex * ez + e0 * ey)
    r[..., 1, 0] = 2.0 * (ex * ey + e0 * ez)
    r[..., 1, 1] = e0 * e0 - ex * ex + ey * ey - ez * ez
    r[..., 1, 2] = 2.0 * (ey * ez - e0 * ex)
    r[..., 2, 0] = 2.0 * (ex * ez - e0 * ey)
    r[..., 2, 1] = 2.0 * (ey * ez + e0 * ex)
    r[..., 2, 2] = e0 * e0 - ex * ex - ey * ey + ez * ez
    return r


def wind_axes_velocity_body(airspeed: np.ndarray, alpha_rad: np.ndarray, beta_rad: np.ndarray) -> np.ndarray:
    """Air-relative velocity of the vehicle in body axes: ``V (cos a cos b, sin b, sin a cos b)``."""
    airspeed = np.asarray(airspeed, dtype=float)
    a = np.asarray(alpha_rad, dtype=float)
    b = np.asarray(beta_rad, dtype=float)
    return np.stack(
        [airspeed * np.cos(a) * np.cos(b), airspeed * np.sin(b), airspeed * np.sin(a) * np.cos(b)],
        axis=-1,
    )


@nb.njit(cache=True, inline="always")
def quaternion_dcm_terms(e0, ex, ey, ez):
    """Compiled scalar form of :func:`dcm_body_to_ned_from_quaternion` for the kernels: the nine
    entries r00, r01, r02, r10, ..., r22 of the body-to-NED matrix (quaternion as stored)."""
    return (e0 * e0 + ex * ex - ey * ey - ez * ez, 2.0 * (ex * ey - e0 * ez), 2.0 * (ex * ez + e0 * ey),
            2.0 * (ex * ey + e0 * ez), e0 * e0 - ex * ex + ey * ey - ez * ez, 2.0 * (ey * ez - e0 * ex),
            2.0 * (ex * ez - e0 * ey), 2.0 * (ey * ez + e0 * ex), e0 * e0 - ex * ex - ey * ey + ez * ez)


def track_frame_offset_to_ned(offset_track, track_angle_rad) -> np.ndarray:
    """A slot offset (x forward along the track, y to starboard, z down; m) -> NED offset (m).
    ``offset_track`` (..., 3), ``track_angle_rad`` broadcastable to its leading axes."""
    off = np.asarray(offset_track, dtype=float)
    chi = np.asarray(track_angle_rad, dtype=float)
    c, s = np.cos(chi), np.sin(chi)
    return np.stack([c * off[..., 0] - s * off[..., 1], s * off[..., 0] + c * off[..., 1], off[..., 2]], axis=-1)


def ned_to_track_frame(vector_ned, track_angle_rad) -> np.ndarray:
    """An NED vector (m or m/s) -> track frame (x forward along the track at ``track_angle_rad`` from north,
    y to starboard, z down): the inverse of :func:`track_frame_offset_to_ned`."""
    v = np.asarray(vector_ned, dtype=float)
    chi = np.asarray(track_angle_rad, dtype=float)
    c, s = np.cos(chi), np.sin(chi)
    return np.stack([c * v[..., 0] + s * v[..., 1], -s * v[..., 0] + c * v[..., 1], v[..., 2]], axis=-1)


@nb.njit(cache=True, inline="always")
def track_to_ned_xy(c, s, dx, dy):
    """Compiled scalar form of :func:`track_frame_offset_to_ned`, horizontal part: the (north, east)
    components of a track-frame vector (dx along the track, dy to starboard) for a track at angle chi
    with c = cos chi, s = sin chi. Returns ``(c dx - s dy, s dx + c dy)``."""
    return c * dx - s * dy, s * dx + c * dy


@nb.njit(cache=True, inline="always")
def ned_to_track_xy(c, s, dn, de):
    """Compiled scalar form of :func:`ned_to_track_frame`, horizontal part: the (along-track,
    starboard) components of an NED vector (dn north, de east) for a track at angle chi with
    c = cos chi, s = sin chi. Returns ``(c dn + s de, -s dn + c de)``."""
    return c * dn + s * de, -s * dn + c * de
