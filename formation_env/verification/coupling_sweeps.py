"""The wake coupling checked on the lateral and vertical sweeps of docs/ell.md ("Coupling"): the follower's
lift, induced-drag and rolling-moment increments (formation minus alone, same attitude and air data) as

* the ELL's own Kutta-Joukowski loads (:func:`formation_env.wake.vehicle_loads` against
  :func:`~formation_env.wake.isolated_loads`);
* what the 6-DOF applies under a coupling (:func:`formation_env.wake.coupling.coupled_wind`'s induced and
  rotational wind through the AeroSim aerodynamics, :func:`sixdof_increments`);
* an independent vortex-lattice code (AeroSandbox: ``tests/oracles/aerosandbox_coupling.py`` writes
  ``tests/data/coupling_aerosandbox.json``).

Two Aerosondes (the ELL model's wing, lift-matched as the ``load_weighted`` coupling flies it), both at the
6-DOF's trim at 25 m/s and 1000 m, wings level; the follower 2 spans behind the leader. Frames: NED earth,
body x forward / y starboard / z down; forces N, moments N m about the follower's wing origin (roll
positive right wing down).
"""

from __future__ import annotations

import numpy as np

from ..aircraft import AEROSONDE
from ..aircraft.aerodynamics import aero_coefficients, aero_forces_moments
from ..atmosphere.standard import standard_atmosphere
from ..geometry import aerosonde
from ..wake import FormationState, WakeModel, isolated_loads, vehicle_loads
from ..wake.arrays import wake_arrays
from ..wake.coupling import coupled_wind, coupling_arrays, lift_matched_vehicle

__all__ = ["SPAN_M", "TRIM_ALPHA_RAD", "AIRSPEED_MPS", "ALTITUDE_M", "LATERAL", "VERTICAL", "sweep_points",
           "sixdof_increments", "CouplingCase", "increments"]

SPAN_M = 2.9
AIRSPEED_MPS = 25.0
ALTITUDE_M = 1000.0
TRIM_ALPHA_RAD = 0.056356858106083554  # formation_env.aircraft.trim(25, 1000).alpha (theta = alpha, level)
TRIM_CONTROLS = (-0.07500655135135188, -0.008517491600587814, -0.0007318439095874257)  # elevator, aileron, rudder
X_B = -2.0
LATERAL = tuple((round(0.6 + 0.1 * i, 2), 0.1) for i in range(9))  # (y, z) b: y 0.6 .. 1.4 at z 0.1
VERTICAL = tuple((0.9, round(-0.3 + 0.1 * i, 2)) for i in range(9))  # z -0.3 .. 0.5 at y 0.9


def sweep_points() -> dict[str, tuple]:
    """The two sweeps: name -> ((y_b, z_b), ...) at x = -2 b."""
    return {"lateral": LATERAL, "vertical": VERTICAL}


def _density() -> float:
    return float(np.asarray(standard_atmosphere(ALTITUDE_M)[2]))


def formation_state(y_b: float, z_b: float, x_b: float = X_B) -> FormationState:
    """Leader at the origin (1000 m up), the follower at (x, y, z) spans NED from it; both at the trim."""
    b, a = SPAN_M, TRIM_ALPHA_RAD
    pos = np.array([[[0.0, 0.0, -ALTITUDE_M], [x_b * b, y_b * b, -ALTITUDE_M + z_b * b]]])
    euler = np.array([[[0.0, a, 0.0], [0.0, a, 0.0]]])
    return FormationState(pos, euler, np.full((1, 2), AIRSPEED_MPS), np.full((1, 2), a), np.zeros((1, 2)))


def sixdof_increments(wind_body, omega_body, rho: float | None = None) -> tuple[float, float, float]:
    """(dL, dD, droll) the AeroSim aerodynamics applies at the trim state (fixed body velocity and controls)
    when the wind ``wind_body`` (m/s, body) and rotational wind ``omega_body`` (rad/s, body) are added,
    against none: lift and drag perpendicular to / along the air-relative velocity without that wind (the
    flight path), roll about body x."""
    rho = _density() if rho is None else rho
    a = TRIM_ALPHA_RAD
    u = AIRSPEED_MPS * np.array([np.cos(a), 0.0, np.sin(a)])

    def forces(w, om):
        vr = u - np.asarray(w, float)
        va = float(np.linalg.norm(vr))
        al, be = np.arctan(vr[2] / vr[0]), np.arcsin(vr[1] / va)
        coeffs = aero_coefficients(al, be, va, 0.0, 0.0, -om[0], -om[1], -om[2], 0.0, *TRIM_CONTROLS, AEROSONDE)
        f, m = aero_forces_moments(*coeffs, 0.5 * rho * va * va, al, be, AEROSONDE)
        return np.asarray(f, float), np.asarray(m, float)

    f0, m0 = forces(np.zeros(3), np.zeros(3))
    f1, m1 = forces(wind_body, omega_body)
    x_w = u / AIRSPEED_MPS
    z_w = np.array([-np.sin(a), 0.0, np.cos(a)])
    df = f1 - f0
    return float(-df @ z_w), float(-df @ x_w), float((m1 - m0)[0])


class CouplingCase:
    """The ELL model of two Aerosondes (``nseg`` horseshoes, lift-matched wing unless ``lift_matched`` is
    False) and the compiled coupling ``coupling``."""

    def __init__(self, coupling: str = "load_weighted", nseg: int = 10, lift_matched: bool = True) -> None:
        vehicle = aerosonde(nseg=nseg)
        if lift_matched:
            vehicle = lift_matched_vehicle(vehicle, AEROSONDE)
        self.model = WakeModel([vehicle, vehicle])
        self.arrays = wake_arrays(self.model, np.zeros(3))
        self.coupling = coupling_arrays(self.model, coupling, AEROSONDE)

    def wind(self, state: FormationState) -> tuple[np.ndarray, np.ndarray]:
        """The follower's induced wind and rotational wind (body axes) under the coupling."""
        n, nv = self.model.n_panels, 2
        out = [np.empty((nv, 3)) for _ in range(4)]
        coupled_wind(self.arrays, self.coupling, state.position_ned[0], state.euler_rad[0], state.airspeed_mps[0],
                     state.alpha_rad[0], state.beta_rad[0], np.empty(n), np.empty((n, 3)), *out)
        return out[1][1], out[2][1]

    def ell(self, state: FormationState) -> tuple[float, float, float]:
        """(dL, dD_i, droll) of the follower from the ELL's Kutta-Joukowski loads."""
        rho = _density()
        form = vehicle_loads(self.model, state, self.model.evaluate(state), rho)
        alone = isolated_loads(self.model, state, rho)
        return (float(form.lift_n[0, 1] - alone.lift_n[0, 1]), float(form.drag_n[0, 1] - alone.drag_n[0, 1]),
                float(form.moment_body_nm[0, 1, 0] - alone.moment_body_nm[0, 1, 0]))

    def sixdof(self, state: FormationState) -> tuple[float, float, float]:
        """(dL, dD, droll) the 6-DOF applies under the coupling."""
        return sixdof_increments(*self.wind(state))


def increments(case: CouplingCase, points) -> tuple[np.ndarray, np.ndarray]:
    """(ELL, coupling) increments (P, 3) = (dL N, dD N, droll N m) at the (y_b, z_b) ``points``."""
    ell, six = [], []
    for y, z in points:
        s = formation_state(y, z)
        ell.append(case.ell(s))
        six.append(case.sixdof(s))
    return np.array(ell), np.array(six)
