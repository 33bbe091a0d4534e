"""Numpy reference of the compiled Aerosonde RK4 step.

:func:`step_numpy` is the step of :func:`formation_env.aircraft.step` (which runs the compiled
``formation_env.aircraft.kernels.rk4_batch``) composed from the vectorised equations of motion,
:func:`formation_env.aircraft.eom.derivatives`: the readable form the kernel transcribes line by
line. ``tests/aircraft/test_aircraft_kernels.py`` holds the two equal to round-off.
"""

from __future__ import annotations

import numpy as np

from formation_env.aircraft.aerodynamics import air_data
from formation_env.aircraft.eom import (DEFAULT_OPTIONS, ModelOptions, _check_dt, _relative_velocity,
                                        _rotation_terms, _wind, derivatives, validate_controls)
from formation_env.aircraft.params import AEROSONDE, AerosondeParams
from formation_env.aircraft.state import ALPHA_PREV, FUEL, N_INTEGRATED, OMEGA, QUAT, as_state
from formation_env.atmosphere.wind import WindInput

__all__ = ["step_numpy"]


def step_numpy(state, controls, wind: WindInput | None = None, dt: float = 0.02,
               params: AerosondeParams = AEROSONDE, options: ModelOptions = DEFAULT_OPTIONS) -> np.ndarray:
    """One fixed RK4 step of ``dt`` for B aircraft, numpy (the arguments and result of
    :func:`formation_env.aircraft.step`): alpha-dot is the backward difference of the raw angle of
    attack, held over the stages; the quaternion is renormalised after the step."""
    s = as_state(state)
    n = s.shape[0]
    u = validate_controls(controls, n)
    wnd = _wind(wind, n)
    dt = _check_dt(dt)
    with np.errstate(all="ignore"):  # a diverged row must not warn-spam; check_envelope reports it
        x0 = s[:, :N_INTEGRATED]
        R = _rotation_terms(s[:, QUAT])
        alpha_now = air_data(_relative_velocity(s, R, wnd), params)[1]
        alphadot = (alpha_now - s[:, ALPHA_PREV]) / dt if options.alpha_dot else 0.0
        k1 = derivatives(x0, u, wnd, alphadot, params, options)
        k2 = derivatives(x0 + (0.5 * dt) * k1, u, wnd, alphadot, params, options)
        k3 = derivatives(x0 + (0.5 * dt) * k2, u, wnd, alphadot, params, options)
        k4 = derivatives(x0 + dt * k3, u, wnd, alphadot, params, options)
        out = np.empty_like(s)
        out[:, :N_INTEGRATED] = x0 + (dt / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)
        quat = out[:, QUAT]
        out[:, QUAT] = quat / np.sqrt(np.sum(quat * quat, axis=1))[:, None]
        out[:, FUEL] = np.clip(out[:, FUEL], 0.0, params.fuel_capacity)
        out[:, OMEGA] = np.maximum(out[:, OMEGA], 0.0)
        out[:, ALPHA_PREV] = alpha_now
    return out
