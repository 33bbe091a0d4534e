"""Action levels (every agent's action is a Box(-1, 1, (4,)) held over the physics steps of one decision).

=============  ==============================================================================================
mode           meaning of a = (a0, a1, a2, a3)
=============  ==============================================================================================
surfaces       elevator, aileron, rudder = trim + a_k * L (L = the FCS surface limit, rad);
               throttle = trim + 0.5 a3; all clipped to the limits. a = 0 flies the trim controls.
residual       added to the PID baseline's command: (0.1, 0.1, 0.1 rad, 0.2 throttle) * a, then clipped.
setpoints      offsets of the PID trajectory tracker's demands: position demand + 5 m * (a0, a1, a2) along,
               starboard of and below the demanded track; speed demand + 2 m/s * a3 along the track.
               With a safe box (``wake_surfing``): a1, a2 span the box piecewise linearly (0 the slot,
               +-1 its walls), a0 is held (along-track fixed), a3 spans +-4 m/s
               (:func:`formation_env.sim.params.setpoint_ranges`, ``setpoint_speed_range``).
=============  ==============================================================================================

The scales live in :mod:`formation_env.sim.params` (``surface_scale``, ``RESIDUAL_SCALE``,
``SETPOINT_POSITION_SCALE_M``, ``SETPOINT_SPEED_SCALE_MPS``).
"""

from .config import ACTION_MODES
from ..sim.params import RESIDUAL_SCALE, SETPOINT_POSITION_SCALE_M, SETPOINT_SPEED_SCALE_MPS
from ..sim.params import surface_scale

__all__ = ["ACTION_MODES", "RESIDUAL_SCALE", "SETPOINT_POSITION_SCALE_M", "SETPOINT_SPEED_SCALE_MPS", "surface_scale"]
