"""Numbers shared across formation-env: the one place each is defined (issue 21).

Units SI. Nothing here imports anything, so every subpackage may import it.
"""

from __future__ import annotations

__all__ = ["AEROSONDE_SPAN_M", "RESIDUAL_SCALE", "SETPOINT_POSITION_SCALE_M", "SETPOINT_SPEED_SCALE_MPS",
           "MAX_DURATION_S"]

AEROSONDE_SPAN_M = 2.9  # Aerosonde wing span b, m (thesis Table 6.1): the unit of slot offsets ("spans")
RESIDUAL_SCALE = (0.1, 0.1, 0.1, 0.2)  # ``residual`` action: rad, rad, rad, throttle fraction per unit action
SETPOINT_POSITION_SCALE_M = 5.0  # ``setpoints`` action: m per unit action, slot frame (along, starboard, down)
SETPOINT_SPEED_SCALE_MPS = 2.0  # ``setpoints`` action: m/s per unit action along the demanded track
MAX_DURATION_S = 3600.0  # longest episode or run a duration override may ask for, s (one hour of flight)
