"""Trajectory-tracker errors (thesis A.5, Eqs. A.16-A.21) in numpy, for histories and analysis; the
tracker itself is compiled in :func:`formation_env.control.law.trajectory_tracker`.

With ``chi_d = atan2(Vd_east, Vd_north)`` the demanded track, ``d = X - X_d`` (current minus
demanded position, NED) and ``dV = V - V_d``, rotated into the demanded-track frame (u along the
demanded velocity, n down): ``ATD = d_u``, ``OTD = d_v``, ``dOTD = dV_v`` (Eqs. A.19-A.21).

* off-track: ``chi_demand = chi_d - sat(Kp_Y OTD + Ki_Y int(OTD) + Kd_Y dOTD, +-40 deg)``
  (the printed positive gains act on the current-minus-demanded distance, so the sign is the
  negative-feedback junction's), conditional-integration anti-windup on the integral;
* along-track: ``V_demand = |V_d| - sat(Kp_X ATD, +-7.5 m/s)`` (behind the demanded point -> faster).
"""

from __future__ import annotations

import numpy as np


__all__ = ["track_errors"]


def track_errors(position_ned, velocity_ned, position_demand_ned, velocity_demand_ned):
    """``(ATD, OTD, dOTD, chi_d)`` per aircraft (m, m, m/s, rad); Eqs. A.16-A.21."""
    vd = np.asarray(velocity_demand_ned)
    chi_d = np.arctan2(vd[..., 1], vd[..., 0])
    c, s = np.cos(chi_d), np.sin(chi_d)
    d = np.asarray(position_ned) - np.asarray(position_demand_ned)
    dv = np.asarray(velocity_ned) - vd
    atd = c * d[..., 0] + s * d[..., 1]
    otd = -s * d[..., 0] + c * d[..., 1]
    dotd = -s * dv[..., 0] + c * dv[..., 1]
    return atd, otd, dotd, chi_d
