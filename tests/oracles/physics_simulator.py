"""A physics-only harness of the compiled step (:func:`formation_env.sim.kernels.step_range`): B formations of
V Aerosondes advanced by one RK4 step with given controls and winds, wake coupled through ELL, no control and
no RL. The tests hold the kernel to the numpy reference (:mod:`tests.oracles.formation_step`) through it, and
check batch = single. (Formerly ``formation_env.sim.FormationSimulator``; the public engine is
:class:`formation_env.sim.Simulation`.)"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from formation_env.aircraft import AEROSONDE, DEFAULT_OPTIONS, AerosondeParams, ModelOptions
from formation_env.aircraft.envelope import DEFAULT_LIMITS, EnvelopeLimits
from formation_env.aircraft.state import N_STATES
from formation_env.geometry import Vehicle, aerosonde
from formation_env.sim.formation import WakeConfig, ell_state_from_aircraft, wake_model_for, wing_origin_body
from formation_env.sim.kernels import min_separation, step_range
from formation_env.sim.params import aircraft_arrays
from formation_env.wake import WakeModel
from formation_env.wake.arrays import wake_arrays

__all__ = ["FormationSimulator", "StepResult"]


@dataclass
class StepResult:
    """What one simulator step produced, arrays (B, V, ...)."""

    state: np.ndarray  # (B, V, 16)
    induced_wind_ned: np.ndarray  # (B, V, 3) m/s
    induced_omega_body: np.ndarray  # (B, V, 3) rad/s
    status: np.ndarray  # (B, V) Status flags, 0 = valid
    circulation: np.ndarray | None = field(default=None)  # (B, N) from the latest ELL solve




class FormationSimulator:
    """B formations of V Aerosondes flying together, wake coupled through ELL.

    Parameters
    ----------
    n_vehicles, batch_size: V and B.
    dt: physics step, s (RK4; 0.02 s as the thesis's Simulink runs).
    wake: :class:`WakeConfig` (``WakeConfig(enabled=False)`` flies without wake interaction).
    params, options, limits: the aircraft model's data, options and flight envelope.
    """

    def __init__(self, n_vehicles: int, batch_size: int = 1, *, dt: float = 0.02, wake: WakeConfig = WakeConfig(),
                 params: AerosondeParams = AEROSONDE, options: ModelOptions = DEFAULT_OPTIONS,
                 limits: EnvelopeLimits = DEFAULT_LIMITS) -> None:
        if not isinstance(n_vehicles, int) or n_vehicles < 1:
            raise ValueError(f"FormationSimulator: n_vehicles must be an integer >= 1, got {n_vehicles!r}")
        if not isinstance(batch_size, int) or batch_size < 1:
            raise ValueError(f"FormationSimulator: batch_size must be an integer >= 1, got {batch_size!r}")
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"FormationSimulator: dt must be finite and > 0, got {dt!r}")
        self.n_vehicles, self.batch_size, self.dt = n_vehicles, batch_size, float(dt)
        self.wake_config, self.params, self.options, self.limits = wake, params, options, limits
        vehicle: Vehicle = aerosonde(nseg=wake.nseg, tailplane=wake.tailplane)
        self.vehicle = vehicle
        self.wake_model = wake_model_for(wake, n_vehicles)
        self.wing_origin_body = wing_origin_body(params)
        # The compiled step needs lattice arrays even when the wake is off (it then skips ELL).
        self._kernel_model = self.wake_model or WakeModel([vehicle])
        self._aircraft = aircraft_arrays(params, options, limits)
        self._wake = wake_arrays(self._kernel_model, self.wing_origin_body)
        self._steps = 0
        self._held_wind = np.zeros((batch_size, n_vehicles, 3))
        self._held_omega = np.zeros((batch_size, n_vehicles, 3))
        self._held_gamma = None

    def reset_wake_hold(self) -> None:
        """Forget the held induced wind (call when formations are reset)."""
        self._steps = 0
        self._held_wind[:] = 0.0
        self._held_omega[:] = 0.0
        self._held_gamma = None

    def induced_wind(self, state: np.ndarray, ambient_wind_ned: np.ndarray, valid: np.ndarray | None = None):
        """ELL effective wind for the valid formations: (wind_ned (B,V,3), omega_body (B,V,3), circulation)."""
        b, v = state.shape[:2]
        wind = np.zeros((b, v, 3))
        omega = np.zeros((b, v, 3))
        if self.wake_model is None:
            return wind, omega, None
        ok = np.all(np.isfinite(state.reshape(b, -1)), axis=1) & np.all(np.isfinite(ambient_wind_ned.reshape(b, -1)), axis=1)
        if valid is not None:
            ok &= valid
        gamma = np.zeros((b, self.wake_model.n_panels))
        if np.any(ok):
            idx = np.nonzero(ok)[0]
            ell = ell_state_from_aircraft(state[idx], ambient_wind_ned[idx], self.wing_origin_body)
            sol = self.wake_model.evaluate(ell)
            wind[idx], omega[idx], gamma[idx] = sol.wind_ned, sol.omega_body, sol.circulation
        return wind, omega, gamma

    def step(self, state: np.ndarray, controls: np.ndarray, ambient_wind_ned: np.ndarray | None = None,
             turbulence_body: np.ndarray | None = None) -> StepResult:
        """Advance every formation by ``dt``. state (B,V,16), controls (B,V,4|5) [elevator, aileron,
        rudder, throttle(, flap)] in rad and 0..1; ambient_wind_ned and turbulence_body (B,V,3) m/s."""
        b, v = self.batch_size, self.n_vehicles
        state = np.asarray(state, dtype=float)
        if state.shape != (b, v, N_STATES):
            raise ValueError(f"FormationSimulator.step: state must have shape {(b, v, N_STATES)}, got {state.shape}")
        controls = np.asarray(controls, dtype=float)
        if controls.ndim != 3 or controls.shape[:2] != (b, v) or controls.shape[2] not in (4, 5):
            raise ValueError(f"FormationSimulator.step: controls must have shape {(b, v, 4)}, got {controls.shape}")
        if not np.all(np.isfinite(controls)):
            raise ValueError("FormationSimulator.step: controls contain NaN or inf")
        amb = np.zeros((b, v, 3)) if ambient_wind_ned is None else np.broadcast_to(np.asarray(ambient_wind_ned, float), (b, v, 3))
        turb = np.zeros((b, v, 3)) if turbulence_body is None else np.broadcast_to(np.asarray(turbulence_body, float), (b, v, 3))
        return self._step_compiled(state, controls, amb, turb)

    def step_many(self, state: np.ndarray, controls: np.ndarray, ambient_seq: np.ndarray, turbulence_seq: np.ndarray):
        """S physics steps with the controls held (the same step as :meth:`step`).

        ambient_seq, turbulence_seq: (S, B, V, 3), the winds of each step. Returns
        ``(StepResult after the last step, status OR-ed over the steps (B, V), smallest CG separation
        seen (B,))``. Inputs must already be valid (finite controls of the right shapes).
        """
        b, v = self.batch_size, self.n_vehicles
        status_any = np.zeros((b, v), dtype=np.int64)
        min_sep = np.full(b, np.inf)
        x = state
        for s in range(ambient_seq.shape[0]):
            res = self._step_compiled(x, controls, ambient_seq[s], turbulence_seq[s])
            x = res.state
            status_any |= res.status
            sep = np.array([min_separation(x[i]) for i in range(b)])
            min_sep = np.where((sep < min_sep) | np.isnan(sep), sep, min_sep)
        return res, status_any, min_sep

    def _step_compiled(self, state, controls, amb, turb) -> StepResult:
        """The same step in compiled code (:func:`formation_env.sim.kernels.step_one` per formation,
        formations on the decision step's thread pool)."""
        from formation_env.sim.dispatch import run_chunks

        b, v = self.batch_size, self.n_vehicles
        m = self._kernel_model
        update = self._steps % self.wake_config.update_every == 0
        self._steps += 1
        if self._held_gamma is None or self._held_gamma.shape != (b, m.n_panels):
            self._held_gamma = np.zeros((b, m.n_panels))
        out = np.empty((b, v, N_STATES))
        status = np.empty((b, v), dtype=np.int64)
        run_chunks(step_range, b, (np.ascontiguousarray(state), np.ascontiguousarray(controls), np.ascontiguousarray(amb),
                                    np.ascontiguousarray(turb), self._held_wind, self._held_omega, self._held_gamma, update,
                                    self.wake_model is not None, self._wake, self._aircraft, self.dt, out, status))
        gamma = self._held_gamma.copy() if self.wake_model is not None else None
        return StepResult(out, self._held_wind.copy(), self._held_omega.copy(), status, gamma)
