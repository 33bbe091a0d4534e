"""The thesis FCS (Appendix A) as one batched, pure policy: :class:`PIDFlightControl`.

``act(observation, controller_state) -> (command, new_controller_state)`` with ``command`` (B, 4)
= (elevator, aileron, rudder, throttle) in rad and 0..1, ``controller_state`` (B, 7) with the
columns :data:`CSTATE_NAMES` (integrators and the washout filter's state). Observations: see
:mod:`formation_env.control.observation`. The same object serves 1 or thousands of aircraft.

Layers (outer to inner): trajectory tracker (A.5, optional) -> autopilot (A.4) -> attitude
control (A.3) -> SAS (A.2) -> surfaces. The continuous-time law (:meth:`evaluate`) gives the
command and the controller-state rates; :meth:`act` advances the controller state by one
explicit-Euler step of ``dt`` (the rate already includes the anti-windup freezes), and
:mod:`formation_env.control.closed_loop` linearises the same law closed around the aircraft.
"""

from __future__ import annotations

import numpy as np

from .gains import FCSConfig
from .law import CSTATE_NAMES, N_CSTATE, SIGNAL_NAMES, fcs_law_batch, fcs_params
from .observation import validate_observation

__all__ = ["CSTATE_NAMES", "N_CSTATE", "PIDFlightControl"]

_I = {n: i for i, n in enumerate(CSTATE_NAMES)}


class PIDFlightControl:
    """The Appendix A flight control system with the thesis's gains (a stateless object: all
    memory is in the controller-state array the caller carries)."""

    cstate_names = CSTATE_NAMES

    def __init__(self, config: FCSConfig | None = None, dt: float = 0.02):
        self.config = FCSConfig() if config is None else config
        if not isinstance(self.config, FCSConfig):
            raise ValueError(f"PIDFlightControl: config must be an FCSConfig, got {type(config).__name__}")
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"PIDFlightControl: dt must be finite and > 0, got {dt!r}")
        self.dt = float(dt)
        self.params = fcs_params(self.config, self.dt)

    @classmethod
    def from_trim(cls, trim_result=None, dt: float = 0.02, **config_kwargs) -> "PIDFlightControl":
        """An FCS whose reference controls and pitch are those of ``trim_result`` (default: the
        Table A.5 trim, 25 m/s, 1000 m, 2 kg)."""
        if trim_result is None:
            from formation_env.aircraft import trim

            trim_result = trim()
        cfg = FCSConfig(trim_controls=tuple(float(x) for x in trim_result.controls[0, :4]),
                        trim_theta_rad=float(trim_result.theta), **config_kwargs)
        return cls(cfg, dt)

    def initial_state(self, batch_size: int, observation: dict | None = None) -> np.ndarray:
        """Zero integrators; the washout filter starts settled on the current yaw rate."""
        if not isinstance(batch_size, (int, np.integer)) or batch_size < 1:
            raise ValueError(f"initial_state: batch_size must be an integer >= 1, got {batch_size!r}")
        c = np.zeros((int(batch_size), N_CSTATE))
        if observation is not None:
            if validate_observation(observation) != batch_size:
                raise ValueError("initial_state: observation batch size differs from batch_size")
            c[:, _I["washout"]] = observation["rates_body"][:, 2]
        return c

    def _check_cstate(self, cstate, n: int) -> np.ndarray:
        c = np.asarray(cstate, dtype=float)
        if c.shape != (n, N_CSTATE):
            raise ValueError(f"controller_state must have shape {(n, N_CSTATE)}, got {c.shape}")
        if not np.all(np.isfinite(c)):
            raise ValueError("controller_state contains NaN or inf")
        return c

    def evaluate(self, obs: dict, cstate: np.ndarray, validate: bool = True):
        """Continuous-time law (compiled, :func:`formation_env.control.law.fcs_law`): ``(command
        (B, 4), cstate_rate (B, 7), signals dict)`` with the signals of :data:`SIGNAL_NAMES`."""
        if validate:
            n = validate_observation(obs)
            cstate = self._check_cstate(cstate, n)
        cstate = np.ascontiguousarray(cstate, dtype=float)
        n = cstate.shape[0]
        f = lambda k: np.ascontiguousarray(obs[k], dtype=float)  # noqa: E731
        cmd, rate, sig = np.empty((n, 4)), np.empty((n, N_CSTATE)), np.empty((n, len(SIGNAL_NAMES)))
        fcs_law_batch(f("position_ned"), f("velocity_ned"), f("euler"), f("rates_body"), f("airspeed"),
                      np.ascontiguousarray(np.broadcast_to(obs["position_demand_ned"], (n, 3)), dtype=float),
                      np.ascontiguousarray(np.broadcast_to(obs["velocity_demand_ned"], (n, 3)), dtype=float),
                      cstate, self.params, cmd, rate, sig)
        signals = {k: sig[:, i] for i, k in enumerate(SIGNAL_NAMES) if self.config.use_tracker or i < 6}
        return cmd, rate, signals

    def act(self, observation: dict, controller_state: np.ndarray):
        """``(command (B, 4), new_controller_state (B, 7))``; pure (inputs are not modified)."""
        cmd, rate, _ = self.evaluate(observation, controller_state)
        return cmd, np.asarray(controller_state, float) + self.dt * rate
