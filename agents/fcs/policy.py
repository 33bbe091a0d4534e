"""The thesis FCS (Appendix A) as one batched, pure policy: :class:`PIDFlightControl`.

``act(observation, controller_state) -> (command, new_controller_state)`` with ``command`` (B, 4)
= (elevator, aileron, rudder, throttle) in rad and 0..1, ``controller_state`` (B, 7) with the
columns :data:`CSTATE_NAMES` (integrators and the washout filter's state). Observations: see
:mod:`agents.observation`. The same object serves 1 or thousands of aircraft.

Layers (outer to inner): trajectory tracker (A.5, optional) -> autopilot (A.4) -> attitude
control (A.3) -> SAS (A.2) -> surfaces. The continuous-time law (:meth:`evaluate`) gives the
command and the controller-state rates; :meth:`act` advances the controller state by one
explicit-Euler step of ``dt`` (the rate already includes the anti-windup freezes), and
:mod:`agents.fcs.closed_loop` linearises the same law closed around the aircraft.
"""

from __future__ import annotations

import numpy as np

from ..observation import validate_observation
from .attitude import pitch_controller, roll_controller
from .autopilot import altitude_controller, heading_controller, speed_controller
from .gains import FCSConfig
from .sas import sas_surfaces, washout_output_and_rate
from .tracker import trajectory_tracker

__all__ = ["CSTATE_NAMES", "N_CSTATE", "PIDFlightControl"]

CSTATE_NAMES = ("int_speed", "int_altitude", "int_theta", "int_phi", "int_heading", "int_offtrack", "washout")
N_CSTATE = len(CSTATE_NAMES)
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
        """Continuous-time law: ``(command (B, 4), cstate_rate (B, 7), signals dict)``."""
        cfg = self.config
        if validate:
            n = validate_observation(obs)
            cstate = self._check_cstate(cstate, n)
        pos, vel = obs["position_ned"], obs["velocity_ned"]
        phi, theta, psi = obs["euler"][:, 0], obs["euler"][:, 1], obs["euler"][:, 2]
        q, r = obs["rates_body"][:, 1], obs["rates_body"][:, 2]
        pd, vd = obs["position_demand_ned"], obs["velocity_demand_ned"]
        rate = np.zeros_like(cstate)
        signals: dict = {}
        if cfg.use_tracker:
            chi_dem, v_dem, rate[:, _I["int_offtrack"]], errs = trajectory_tracker(
                pos, vel, pd, vd, cstate[:, _I["int_offtrack"]], cfg.tracker, cfg.anti_windup)
            signals.update(errs)
        else:
            chi_dem = np.arctan2(vd[:, 1], vd[:, 0])
            v_dem = np.linalg.norm(vd, axis=1)
        trim_e, trim_a, trim_r, trim_t = cfg.trim_controls
        throttle, rate[:, _I["int_speed"]] = speed_controller(
            v_dem, obs["airspeed"], cstate[:, _I["int_speed"]], trim_t, cfg.autopilot, cfg.throttle_limits, cfg.anti_windup)
        theta_dem, rate[:, _I["int_altitude"]] = altitude_controller(
            pd[:, 2], pos[:, 2], vd[:, 2], vel[:, 2], cstate[:, _I["int_altitude"]], cfg.trim_theta_rad, cfg.autopilot)
        chi = psi if cfg.structure.direction_feedback == "heading" else np.arctan2(vel[:, 1], vel[:, 0])
        phi_dem, rate[:, _I["int_heading"]] = heading_controller(chi_dem, chi, cstate[:, _I["int_heading"]], cfg.autopilot)
        lim = cfg.surface_limit_rad
        # the elevator demand saturates at full deflection (about trim: the total stays within limits)
        elev_dem, rate[:, _I["int_theta"]] = pitch_controller(theta_dem, theta, cstate[:, _I["int_theta"]],
                                                              cfg.attitude, lim, cfg.anti_windup)
        ail_dem, rate[:, _I["int_phi"]] = roll_controller(phi_dem, phi, cstate[:, _I["int_phi"]], cfg.attitude)
        r_w, rate[:, _I["washout"]] = washout_output_and_rate(r, cstate[:, _I["washout"]], cfg.sas, cfg.structure)
        d_e, d_a, d_r = sas_surfaces(elev_dem, ail_dem, q, theta - cfg.trim_theta_rad, phi, r_w, cfg.sas, cfg.structure)
        cmd = np.empty((cstate.shape[0], 4))
        cmd[:, 0] = np.clip(trim_e + d_e, -lim, lim)
        cmd[:, 1] = np.clip(trim_a + d_a, -lim, lim)
        cmd[:, 2] = np.clip(trim_r + d_r, -lim, lim)
        cmd[:, 3] = throttle
        signals.update({"speed_demand": v_dem, "track_angle_demand": chi_dem, "theta_demand": theta_dem,
                        "phi_demand": phi_dem, "elevator_demand": elev_dem, "aileron_demand": ail_dem})
        return cmd, rate, signals

    def act(self, observation: dict, controller_state: np.ndarray):
        """``(command (B, 4), new_controller_state (B, 7))``; pure (inputs are not modified)."""
        cmd, rate, _ = self.evaluate(observation, controller_state)
        return cmd, np.asarray(controller_state, float) + self.dt * rate
