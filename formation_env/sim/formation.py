"""The formation simulator: one physics step = ELL effective wind -> Aerosonde dynamics.

No RL concepts here. State is an array (B formations, V aircraft, 16 states; the layout of
:mod:`formation_env.aircraft.state`); every function is batched over B and V.

One step (held over the RK4 step, as the thesis's Simulink model holds its inputs):

1. each aircraft's pose and its air data relative to the *ambient* wind (steady + gust +
   turbulence) go to ELL; the induced wind is not fed back into ELL's air data because the joint
   solve already accounts for the other vehicles' influence on each circulation;
2. ELL returns each aircraft's effective induced translational wind (NED) and rotational wind
   (body) (thesis Eqs. 4.4-4.7);
3. the dynamics see air-relative velocity = ground velocity - (ambient + induced) wind and
   air-relative rates = body rates - rotational wind (Eqs. 4.8, 4.9).

A formation with a non-finite or out-of-envelope aircraft keeps stepping (its rows may become
non-finite) but gets no wake evaluation and zero induced wind; callers read ``status`` and end
the episode.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..aircraft import AEROSONDE, DEFAULT_OPTIONS, AerosondeParams, ModelOptions
from ..aircraft.envelope import DEFAULT_LIMITS, EnvelopeLimits
from ..aircraft.kernels import pack as pack_aircraft
from ..aircraft.state import N_STATES, POS, QUAT
from ..frames import dcm_body_to_ned_from_quaternion, euler_from_quaternion
from ..geometry import Vehicle, aerosonde
from ..wake import FormationState, WakeModel

from ..wake.arrays import wake_arrays
from .kernels import min_separation, pack_limits, step_range
from .params import AircraftArrays


__all__ = ["WakeConfig", "FormationSimulator", "ell_state_from_aircraft", "StepResult"]


@dataclass(frozen=True)
class WakeConfig:
    """How the ELL wake is modelled in the simulator (see :class:`formation_env.wake.WakeModel`)."""

    enabled: bool = True
    nseg: int = 10
    tailplane: bool = False
    core: str = "kurylowich"
    eval_points: str = "control"
    rotational: str = "lstsq"
    viscous_aic: bool = True
    update_every: int = 1  # physics steps between ELL evaluations (induced wind held in between)

    def __post_init__(self) -> None:
        if not isinstance(self.update_every, int) or self.update_every < 1:
            raise ValueError(f"WakeConfig: update_every must be an integer >= 1, got {self.update_every!r}")
        if not isinstance(self.nseg, int) or self.nseg < 1:
            raise ValueError(f"WakeConfig: nseg must be an integer >= 1, got {self.nseg!r}")


@dataclass
class StepResult:
    """What one simulator step produced, arrays (B, V, ...)."""

    state: np.ndarray  # (B, V, 16)
    induced_wind_ned: np.ndarray  # (B, V, 3) m/s
    induced_omega_body: np.ndarray  # (B, V, 3) rad/s
    status: np.ndarray  # (B, V) Status flags, 0 = valid
    circulation: np.ndarray | None = field(default=None)  # (B, N) from the latest ELL solve


def ell_state_from_aircraft(state: np.ndarray, ambient_wind_ned: np.ndarray, wing_origin_body: np.ndarray) -> FormationState:
    """ELL's view of B formations: pose of each wing origin and air data relative to the ambient air.

    state (B, V, 16); ambient_wind_ned (B, V, 3); wing_origin_body (3,): the wing's root
    quarter-chord point relative to the aircraft's reference point (its CG), body axes.
    """
    q = state[..., QUAT]
    r_bn = dcm_body_to_ned_from_quaternion(q)  # body -> NED
    pos = state[..., POS] + np.einsum("...ij,j->...i", r_bn, wing_origin_body)
    v_air_ned = np.einsum("...ij,...j->...i", r_bn, state[..., 0:3]) - ambient_wind_ned
    v_air_body = np.einsum("...ji,...j->...i", r_bn, v_air_ned)
    speed = np.linalg.norm(v_air_body, axis=-1)
    alpha = np.arctan2(v_air_body[..., 2], v_air_body[..., 0])
    beta = np.arcsin(np.clip(v_air_body[..., 1] / np.maximum(speed, 1e-9), -1.0, 1.0))
    return FormationState(pos, euler_from_quaternion(q), np.maximum(speed, 1e-3), alpha, beta)


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
        self.wake_model = (WakeModel([vehicle] * n_vehicles, core=wake.core, eval_points=wake.eval_points,
                                     rotational=wake.rotational, viscous_aic=wake.viscous_aic)
                           if wake.enabled and n_vehicles > 1 else None)
        # ELL's vehicle origin is the wing's root quarter-chord point (~ the aerodynamic centre);
        # the aircraft state is that of its CG. AeroSim gives both relative to the propeller hub.
        self.wing_origin_body = np.asarray(params.r_ac_body, float) - np.asarray(params.cg_gross_body, float)
        # The compiled step needs lattice arrays even when the wake is off (it then skips ELL).
        self._kernel_model = self.wake_model or WakeModel([vehicle])
        self._aircraft = AircraftArrays(*pack_aircraft(params, options), pack_limits(limits))
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
        from .step import _run_chunks

        b, v = self.batch_size, self.n_vehicles
        m = self._kernel_model
        update = self._steps % self.wake_config.update_every == 0
        self._steps += 1
        if self._held_gamma is None or self._held_gamma.shape != (b, m.n_panels):
            self._held_gamma = np.zeros((b, m.n_panels))
        out = np.empty((b, v, N_STATES))
        status = np.empty((b, v), dtype=np.int64)
        _run_chunks(step_range, b, (np.ascontiguousarray(state), np.ascontiguousarray(controls), np.ascontiguousarray(amb),
                                    np.ascontiguousarray(turb), self._held_wind, self._held_omega, self._held_gamma, update,
                                    self.wake_model is not None, self._wake, self._aircraft, self.dt, out, status))
        gamma = self._held_gamma.copy() if self.wake_model is not None else None
        return StepResult(out, self._held_wind.copy(), self._held_omega.copy(), status, gamma)
