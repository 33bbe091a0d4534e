"""The Aerosonde 6-DOF flight-dynamics model (AeroSim Blockset Aerosonde, thesis Appendix A).

Public API (everything batched over a leading axis of B aircraft):

* :mod:`.state`: state layout (B, 16), :func:`euler_angles`.
* :mod:`.eom`: :func:`make_state`, :func:`step` (RK4), :func:`derivatives`, :func:`outputs`, :class:`ModelOptions`.
* :mod:`.trim`: :func:`trim` -> :class:`TrimResult`.
* :mod:`.linearise`: :func:`linearise`, :func:`open_loop_modes`.
* :mod:`.envelope`: :func:`check_envelope`, :class:`EnvelopeLimits`, :class:`Status`.
* :mod:`.actuators`: :class:`ActuatorConfig`, :class:`Actuators`.
* :mod:`.params`: :class:`AerosondeParams`, ``AEROSONDE``.
"""

from .envelope import EnvelopeLimits, Status, check_envelope, describe_status
from .eom import DEFAULT_OPTIONS, ModelOptions, air_data_of, derivatives, make_state, outputs, step, validate_controls
from .params import AEROSONDE, AerosondeParams
from .state import N_STATES, STATE_NAMES, euler_angles
from .trim import TrimResult, trim, trim_state_and_controls

__all__ = [
    "AEROSONDE", "AerosondeParams", "DEFAULT_OPTIONS", "ModelOptions", "N_STATES", "STATE_NAMES",
    "TrimResult", "derivatives", "euler_angles", "make_state", "outputs", "step", "trim", "validate_controls",
    "air_data_of", "check_envelope", "describe_status", "EnvelopeLimits", "Status", "trim_state_and_controls",
]
