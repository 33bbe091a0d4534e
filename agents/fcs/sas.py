"""Stability augmentation system (thesis A.2, Table A.8).

* pitch stabiliser: pitch rate and pitch attitude (about trim) to elevator,
* yaw damper: washed-out yaw rate to rudder,
* spiral stabiliser: bank angle to aileron,
* aileron-to-rudder interlink.

Signs (AeroSim: +elevator nose down, +aileron rolls left, +rudder yaws left): the printed
negative gains enter a negative-feedback junction, ``surface = demand - K * signal``. So
``elevator = demand + 0.28 q + 1.0 (theta - theta_trim)`` (nose up -> trailing edge down),
``aileron = demand + 0.2 phi`` (right bank -> roll left). The interlink is summed into the yaw
damper's junction ahead of its gain (the structure that reproduces Table A.12, docs/fcs.md):
``rudder = 0.25 (r_w + 0.5 aileron_demand)`` (yaw right -> yaw left; right-roll aileron
(negative) -> right rudder (negative), a coordinated turn).
"""

from __future__ import annotations

import numpy as np

from .gains import FCSStructure, SASGains

__all__ = ["washout_output_and_rate", "sas_surfaces"]


def washout_output_and_rate(r: np.ndarray, x_w: np.ndarray, gains: SASGains, structure: FCSStructure):
    """Washout filter on the yaw rate: output ``r_w = r - x_w`` and the low-pass state's rate.

    ``"time_constant"`` form ``T s/(T s + 1)``: ``x_w' = (r - x_w) / T``;
    ``"pole"`` form ``s/(s + T)``: ``x_w' = T (r - x_w)``.
    """
    r_w = r - x_w
    rate = r_w / gains.T_r_washout_s if structure.washout == "time_constant" else gains.T_r_washout_s * r_w
    return r_w, rate


def sas_surfaces(elevator_demand, aileron_demand, q, theta_pert, phi, r_washout, gains: SASGains,
                 structure: FCSStructure):
    """Surface perturbations about trim (rad): ``(d_elevator, d_aileron, d_rudder)``.

    ``elevator_demand``/``aileron_demand`` come from the attitude controllers; ``theta_pert`` is
    ``theta - theta_trim``.
    """
    d_elev = elevator_demand - (gains.K_q_elevator * q + gains.K_theta_elevator * theta_pert)
    d_ail = aileron_demand - gains.K_phi_aileron * phi
    interlink = aileron_demand if structure.interlink_source == "demand" else d_ail
    if structure.interlink_path == "yaw_damper":
        d_rud = -gains.K_r_rudder * (r_washout + gains.K_aileron_rudder_interlink * interlink)
    else:
        d_rud = -gains.K_r_rudder * r_washout + gains.K_aileron_rudder_interlink * interlink
    return d_elev, d_ail, d_rud
