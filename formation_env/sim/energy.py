"""The energy account of a formation, from the wake to the drag (docs/ell.md, "Energy account"): what the
ELL predicts a follower saves and what the 6-DOF actually applies, at one flown state, compiled per formation.

Per UAV (columns of :data:`ENERGY_COLUMNS`), at its current state x and controls u (the last physics
step's), in the ambient air (steady wind, gusts, turbulence; rotational gusts included):

* ``drag_alone_n``: the drag along the flight path the 6-DOF applies to the UAV alone, D_alone = -F_aero .
  u_air, with F_aero the AeroSim aerodynamic force at (x, u) without induced wind and u_air the unit
  air-relative velocity in the ambient air (quasi-steady: alpha-dot 0);
* ``drag_formation_n``: the same with the coupling's induced wind and rotational wind at this state
  (:func:`formation_env.wake.coupling.coupled_wind`, the solve the physics step makes), projected on the
  same u_air: the lift tilted by the upwash is the saving;
* ``ell_saving_n``: the ELL's predicted reduction of the induced drag, D_i(alone) - D_i(formation), both
  near-field Kutta-Joukowski at this pose and air data (:mod:`formation_env.wake.benefit`), at the
  UAV's local air density;
* ``ell_induced_alone_n``: the ELL's induced drag of the UAV alone;
* ``drag_saving_pct_ell`` = 100 ell_saving_n / drag_alone_n: the ELL's predicted reduction of the UAV's total
  drag, in % of its total drag alone (the ELL predicts no change of the profile drag);
* ``drag_saving_pct_6dof`` = 100 (drag_alone_n - drag_formation_n) / drag_alone_n.

Both savings are at the same state and controls (fixed angle of attack): the formation's extra lift is in
both (its induced-drag cost in the ELL's, its polar cost in the 6-DOF's). A formation with a non-finite UAV,
or without wake, reads 0. Frames: NED earth, body x forward / y starboard / z down; units SI.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..aircraft.kernels import aero_force_at, air_density_at
from ..frames import quaternion_dcm_terms
from ..wake.benefit import induced_drags_one
from ..wake.coupling import coupled_wind
from .dispatch import run_chunks
from .kernels import ell_inputs

__all__ = ["ENERGY_COLUMNS", "N_ENERGY", "energy_account_one", "energy_account_range", "energy_account"]

#: the columns of the account (last axis), in order
ENERGY_COLUMNS = ("drag_alone_n", "drag_formation_n", "ell_saving_n", "ell_induced_alone_n", "drag_saving_pct_ell",
                  "drag_saving_pct_6dof")
N_ENERGY = len(ENERGY_COLUMNS)

_jit = nb.njit(cache=True, error_model="numpy")


@_jit
def _path_drag(x, c, wind, v_air_b, ac):
    """Drag along the flight path (N): minus the aerodynamic force (body) on the unit air-relative
    velocity v_air_b (body, ambient air)."""
    fx, fy, fz = aero_force_at(x, c, wind, ac.scalars, ac.atm_T, ac.atm_P, ac.atm_rho, ac.atm_a)
    return -(fx * v_air_b[0] + fy * v_air_b[1] + fz * v_air_b[2])


# inlined into energy_account_range at numba IR level: a compiled function of its own would be one more copy of the
# ELL solve it calls for numba to link and re-optimise
@nb.njit(cache=True, error_model="numpy", inline="always")
def energy_account_one(wake, wake_alone, coupling, ac, x, cmd, ambient, ambient_omega, out):
    """The account (V, N_ENERGY) of one formation into ``out`` (see the module docstring). x (V, 16)
    states, cmd (V, 4) controls, ambient (V, 3) wind NED m/s, ambient_omega (V, 3) rotational gusts rad/s
    body; wake/wake_alone the formation's and one UAV's lattice, coupling a
    :class:`~formation_env.wake.coupling.CouplingArrays`, ac an :class:`~formation_env.sim.params.AircraftArrays`."""
    nv = x.shape[0]
    out[:, :] = 0.0
    for a in range(nv):
        for k in range(x.shape[1]):
            if not math.isfinite(x[a, k]):
                return
    pos, euler = np.empty((nv, 3)), np.empty((nv, 3))
    speed, alpha, beta = np.empty(nv), np.empty(nv), np.empty(nv)
    ell_inputs(x, ambient, wake.wing_origin_body, pos, euler, speed, alpha, beta)
    n = wake.n_panels
    gamma = np.empty(n)
    wind_ned, wind_b, omega_b, omega_ned = np.empty((nv, 3)), np.empty((nv, 3)), np.empty((nv, 3)), np.empty((nv, 3))
    keep = np.empty((n, n + 1))  # the solve's AIC before elimination: the UAVs' lone AICs are its diagonal blocks
    coupled_wind(wake, coupling, pos, euler, speed, alpha, beta, gamma, np.empty((n, 3)), wind_ned, wind_b, omega_b,
                 omega_ned, keep)
    for a in range(nv):
        for i in range(3):
            if not (math.isfinite(wind_ned[a, i]) and math.isfinite(omega_b[a, i])):
                return
    d_form, d_alone = np.empty(nv), np.empty(nv)
    induced_drags_one(wake, wake_alone, pos, euler, speed, alpha, beta, gamma, d_form, d_alone, 1.0, keep)
    w12 = np.zeros(12)
    vb = np.empty(3)
    for a in range(nv):
        xa = x[a]
        rho = air_density_at(-xa[12], ac.atm_T, ac.atm_P, ac.atm_rho, ac.atm_a)
        d_alone_i = d_alone[a]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = quaternion_dcm_terms(xa[6], xa[7], xa[8], xa[9])
        # unit air-relative velocity in the ambient air, body axes: u_b - R^T w_ambient
        vb[0] = xa[0] - (r00 * ambient[a, 0] + r10 * ambient[a, 1] + r20 * ambient[a, 2])
        vb[1] = xa[1] - (r01 * ambient[a, 0] + r11 * ambient[a, 1] + r21 * ambient[a, 2])
        vb[2] = xa[2] - (r02 * ambient[a, 0] + r12 * ambient[a, 1] + r22 * ambient[a, 2])
        norm = math.sqrt(vb[0] * vb[0] + vb[1] * vb[1] + vb[2] * vb[2])
        if not norm > 0.0:
            continue
        for i in range(3):
            vb[i] /= norm
            w12[i] = ambient[a, i]
            w12[6 + i] = 0.0
            w12[9 + i] = ambient_omega[a, i]
        drag_alone = _path_drag(xa, cmd[a], w12, vb, ac)
        for i in range(3):
            w12[6 + i] = wind_ned[a, i]
            w12[9 + i] = ambient_omega[a, i] + omega_b[a, i]
        drag_form = _path_drag(xa, cmd[a], w12, vb, ac)
        ell_saving = rho * (d_alone_i - d_form[a])
        out[a, 0] = drag_alone
        out[a, 1] = drag_form
        out[a, 2] = ell_saving
        out[a, 3] = rho * d_alone_i
        if drag_alone > 0.0:
            out[a, 4] = 100.0 * ell_saving / drag_alone
            out[a, 5] = 100.0 * (drag_alone - drag_form) / drag_alone
    for a in range(nv):  # never NaN (a degenerate solve)
        for k in range(out.shape[1]):
            if not math.isfinite(out[a, k]):
                out[a, k] = 0.0


@nb.njit(cache=True, nogil=True, error_model="numpy")
def energy_account_range(wake, wake_alone, coupling, ac, x, cmd, ambient, ambient_omega, out, start, stop):
    """:func:`energy_account_one` for formations start..stop-1 of a batch: x (B, V, 16), cmd (B, V, 4),
    ambient and ambient_omega (B, V, 3), out (B, V, N_ENERGY); releases the GIL (the decision step's
    thread pool runs chunks of it)."""
    for b in range(start, stop):
        energy_account_one(wake, wake_alone, coupling, ac, x[b], cmd[b], ambient[b], ambient_omega[b], out[b])


def energy_account(wake, wake_alone, coupling, ac, x, cmd, ambient, ambient_omega, out) -> None:
    """:func:`energy_account_one` for every formation of a batch (arguments as :func:`energy_account_range`'s),
    over the decision step's threads when that is faster (:func:`formation_env.sim.dispatch.run_chunks`)."""
    run_chunks(energy_account_range, x.shape[0], (wake, wake_alone, coupling, ac, x, cmd, ambient, ambient_omega, out))
