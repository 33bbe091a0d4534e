"""``extremum_seeking``: the classical controller for formation drag minimisation, as a wake-surfing baseline.

Extremum seeking (ES; Krstic and Wang 2000; for formation flight Binetti, Ariyur, Krstic and Bernelli
2003, and the flight tests that located the energy-optimal slot from measured drag) moves the
follower's slot set-point to maximise a measured performance index without a model of the wake:

* a sinusoidal dither on the lateral and vertical set-points, at two different frequencies
  (``a_y sin(w_y t)``, ``a_z sin(w_z t)``) so that the two gradient components separate;
* the measured saving J (the env's ``StepOutput.saving``: the ELL induced-drag saving, an ideal,
  noise-free measurement of exactly what the reward pays; a flight test measures it through the fuel
  flow, with noise and lag, so this is ES's best case) is high-pass filtered (corner ``w_h``),
  multiplied by each dither delayed by the plant's lag (``phase_lag_s``: the PID's response from
  set-point to position), and low-pass filtered (corner ``w_l``): the gradient estimate;
* the set-point centre climbs the gradient (``d theta / dt = gain * gradient``), held inside the
  safe box less the dither amplitude and a margin (so that the dithered set-point, and the aircraft
  tracking it in turbulence, stay in the box), clipped there (anti-windup).

What flies the set-point (the env's ``setpoints`` action mode, mapped onto the safe box): by default
:class:`agents.station_keeper.StationKeeper` (``inner="station_keeper"``: close formation's precise holding loop,
told the dithered set-point as its slot, the way the wake-surfing oracle keeper is told the optimum), or the thesis
PID stiffened by a vertical PI inner loop (``inner="pid"``, the issue-16 design: on the converged wake's sharp
optimum it reaches 0.22 of it on the tuning episodes against the keeper's 0.41). The along-track station is held by
:class:`agents.pid_formation.PIDFormation`'s speed channel (wind feed-forward, PD and integral on the along-track
error): the along-track set-point is fixed in wake surfing, and the thesis tracker's proportional along-track loop
alone lags 8 m per 1 m/s of wind. The gains were tuned on training seeds
(``formation-env evaluate --scenario wake_surfing --task-report --tune``; docs/wake_surfing.md has the sweep and its numbers).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from agents.common import check_gains
from agents.pid_formation import PIDFormation

__all__ = ["ExtremumSeekingGains", "ExtremumSeeking", "INNER_LOOPS"]

#: what flies the seeker's set-point: the thesis PID with a vertical PI around it, or the station keeper
INNER_LOOPS = ("pid", "station_keeper")


@dataclass(frozen=True)
class ExtremumSeekingGains:
    """ES parameters (SI: m, s, rad/s). The defaults are the sweep's best on 16 training-range episodes
    (``formation-env evaluate --scenario wake_surfing --task-report --tune``; docs/wake_surfing.md)."""

    # Issue 23 part 7 (the converged wake, whose optimum on the leader's wake plane is sharp: 0.22 of saving lost
    # 0.1 b above or below it): the sweep's best with the station keeper flying the set-point (84 combinations in five
    # rounds; docs/wake_surfing.md). A vertical dither of 0.4 m (0.14 b) reads the gradient through the turbulence's
    # noise better than the lattice era's 0.12 m (0.369 -> 0.408 of the optimum); 0.6 m loses more than it reads.
    amplitude_y_m: float = 0.35  # lateral dither amplitude
    amplitude_z_m: float = 0.4  # vertical dither amplitude
    period_y_s: float = 12.0  # lateral dither period
    period_z_s: float = 9.0  # vertical dither period (not a harmonic of the lateral one)
    # the lag from set-point to position at the dither frequencies, by which the demodulating dither is delayed: the
    # thesis PID's measured step responses (63 % in ~2.2 s laterally and ~2.3 s vertically, a first order plus
    # ~0.8 s delay) set 2.3 s / 2.1 s; the station keeper's vertical loop is faster (the sweep: 0.5 s, against 1.0 s
    # and 2.1 s)
    phase_lag_y_s: float = 2.3
    phase_lag_z_s: float = 0.5
    highpass_rad_s: float = 0.6  # washout of the measured saving
    lowpass_rad_s: float = 2.0  # gradient estimate filter
    gain_y: float = 0.5  # m/s of set-point motion per (unit saving per m) of gradient (ascent)
    gain_z: float = 1.0
    # the centre keeps this far inside the box's walls (beyond the dither): the PID's tracking error under
    # turbulence would carry a follower dithering at a wall out of the box (the lattice era's optimum lay on the
    # box's floor)
    margin_m: float = 0.15
    # with inner="pid": the inner loops around the ES set-point (pid_formation's cross-track and vertical laws, on the
    # error from the set-point instead of the slot): they raise the PID's position-loop gains, so the
    # aircraft follows the dither and stays near the set-point in turbulence; 0 leaves the PID alone
    kp_y: float = 0.0  # m of set-point displacement per m of lateral error (on: worse, see the sweep)
    ki_y: float = 0.0  # m per m s
    kp_z: float = 3.0
    ki_z: float = 0.5

    def __post_init__(self) -> None:
        check_gains(self)
        for name in ("period_y_s", "period_z_s", "highpass_rad_s", "lowpass_rad_s"):  # divisors / filter corners
            if getattr(self, name) <= 0:
                raise ValueError(f"ExtremumSeekingGains.{name} must be > 0, got {getattr(self, name)!r}")


class ExtremumSeeking:
    """Batched, stateful (the :class:`formation_env.rollout.Policy` protocol, with ``observe``): ``reset(n_rows)``,
    then per decision ``observe(decision)`` (the measured saving) and ``act(obs (n_rows, D)) -> (n_rows, 4)``
    set-point actions in [-1, 1]. ``setpoint_low_m`` / ``setpoint_high_m`` (3,) are the env's set-point
    ranges (:func:`formation_env.sim.params.setpoint_ranges`), ``speed_range_mps`` its speed range
    (:func:`formation_env.sim.params.setpoint_speed_range`). ``box_low_m`` / ``box_high_m`` (3,): the safe box's
    walls as offsets from the slot (:func:`formation_env.sim.params.safe_box_offsets`), which hold the centre
    (default: the set-point ranges; the two differ where the set-point map reaches beyond the box). ``centre_m``
    (n_rows, 2) is the set-point centre (lateral, vertical offsets from the starting slot, m) ES has converged to
    so far."""

    action_mode = "setpoints"

    def __init__(self, setpoint_low_m, setpoint_high_m, speed_range_mps: float,
                 gains: ExtremumSeekingGains | None = None, control_hz: float = 10.0, *, box_low_m=None,
                 box_high_m=None, inner: str = "station_keeper") -> None:
        if inner not in INNER_LOOPS:
            raise ValueError(f"ExtremumSeeking: inner must be one of {INNER_LOOPS}, got {inner!r}")
        self.inner = inner
        self.gains = ExtremumSeekingGains() if gains is None else gains
        if not isinstance(self.gains, ExtremumSeekingGains):
            raise ValueError(f"ExtremumSeeking: gains must be an ExtremumSeekingGains, got {type(gains).__name__}")
        if isinstance(control_hz, bool) or not isinstance(control_hz, (int, float)) or not (
                math.isfinite(control_hz) and control_hz > 0):
            raise ValueError(f"ExtremumSeeking: control_hz must be a finite number > 0, got {control_hz!r}")
        self.low = np.asarray(setpoint_low_m, dtype=float).reshape(3)
        self.high = np.asarray(setpoint_high_m, dtype=float).reshape(3)
        if np.any(self.high[1:] - self.low[1:] <= 0):
            raise ValueError(f"ExtremumSeeking: the lateral and vertical set-point ranges must be open, got "
                             f"{self.low} .. {self.high}")
        self.box_low = self.low.copy() if box_low_m is None else np.asarray(box_low_m, dtype=float).reshape(3)
        self.box_high = self.high.copy() if box_high_m is None else np.asarray(box_high_m, dtype=float).reshape(3)
        if np.any(self.box_high[1:] - self.box_low[1:] <= 0) or not np.all(np.isfinite(self.box_low) & np.isfinite(self.box_high)):
            raise ValueError(f"ExtremumSeeking: the box must be finite and open laterally and vertically, got "
                             f"{self.box_low} .. {self.box_high}")
        self.control_hz = float(control_hz)
        self.along = PIDFormation(control_hz=control_hz, setpoint_low_m=self.low, setpoint_high_m=self.high,
                                  speed_range_mps=speed_range_mps)
        self.keeper = None
        if inner == "station_keeper":
            from agents.station_keeper import StationKeeper

            self.keeper = StationKeeper(control_hz=control_hz)
        self.reset(1)

    def reset(self, n_rows: int) -> None:
        if isinstance(n_rows, bool) or not isinstance(n_rows, (int, np.integer)) or n_rows < 1:
            raise ValueError(f"ExtremumSeeking.reset: n_rows must be an integer >= 1, got {n_rows!r}")
        n = int(n_rows)
        self._saving = None
        self.t_s = np.zeros(n)
        self.centre_m = np.zeros((n, 2))
        self.washout = np.full(n, np.nan)  # the high-pass filter's low-passed saving (NaN: not started)
        self.gradient = np.zeros((n, 2))
        self.integral = np.zeros((n, 2))
        self.along.reset(n)
        if self.keeper is not None:
            self.keeper.reset(n)

    def reset_rows(self, rows) -> None:
        rows = np.asarray(rows)
        self.t_s[rows] = 0.0
        self.centre_m[rows] = 0.0
        self.washout[rows] = np.nan
        self.gradient[rows] = 0.0
        self.integral[rows] = 0.0
        self.along.reset_rows(rows)
        if self.keeper is not None:
            self.keeper.reset_rows(rows)

    def _dither(self, t_s: np.ndarray) -> np.ndarray:
        g = self.gains
        return np.stack([g.amplitude_y_m * np.sin(2 * np.pi * t_s / g.period_y_s),
                         g.amplitude_z_m * np.sin(2 * np.pi * t_s / g.period_z_s)], axis=1)

    def observe(self, decision) -> None:
        """The rollout's step output before each decision (:class:`formation_env.rollout.Decision`): ES climbs
        the measured saving of the previous decision (0 at the start and for ended episodes)."""
        self._saving = np.asarray(decision.saving, dtype=float)

    def act(self, obs, saving=None) -> np.ndarray:
        """Set-point actions (N, 4); ``saving`` (N,) the last measured saving (default: the one
        :meth:`observe` received, 0 before any)."""
        obs = np.asarray(obs, dtype=float)
        if saving is None:
            saving = getattr(self, "_saving", None)
            if saving is None or saving.shape[0] != obs.shape[0]:
                saving = np.zeros(obs.shape[0])
        j = np.nan_to_num(np.asarray(saving, dtype=float).reshape(-1))
        if obs.ndim != 2 or obs.shape[0] != j.shape[0]:
            raise ValueError(f"ExtremumSeeking.act: obs (N, D) and saving (N,) must agree, got {obs.shape} and {j.shape}")
        if self.t_s.shape[0] != obs.shape[0]:
            self.reset(obs.shape[0])
        g = self.gains
        dt = 1.0 / self.control_hz
        # gradient estimate from the saving just measured (the response to the dither one lag ago)
        fresh = np.isnan(self.washout)
        self.washout[fresh] = j[fresh]
        self.washout += dt * g.highpass_rad_s * (j - self.washout)
        j_hp = j - self.washout
        lagged = np.stack([self._dither(self.t_s - g.phase_lag_y_s)[:, 0], self._dither(self.t_s - g.phase_lag_z_s)[:, 1]],
                          axis=1)
        amp = np.array([max(g.amplitude_y_m, 1e-9), max(g.amplitude_z_m, 1e-9)])
        demod = j_hp[:, None] * lagged * (2.0 / amp)  # J ~ J0 + dJ/dtheta a sin: 2/a <J sin> = dJ/dtheta
        self.gradient += dt * g.lowpass_rad_s * (demod - self.gradient)
        # gradient ascent of the centre, held inside the box less the dither (anti-windup: clipped)
        lo = self.box_low[1:] + np.array([g.amplitude_y_m, g.amplitude_z_m]) + g.margin_m
        hi = self.box_high[1:] - np.array([g.amplitude_y_m, g.amplitude_z_m]) - g.margin_m
        step = dt * np.array([g.gain_y, g.gain_z]) * self.gradient
        self.centre_m = np.clip(self.centre_m + step, np.minimum(lo, 0.0), np.maximum(hi, 0.0))
        self.t_s += dt
        setpoint = self.centre_m + self._dither(self.t_s)
        if self.keeper is not None:
            return self._keeper_act(obs, setpoint)
        # inner loops: displace the demand against the error from the set-point (PI, conditional
        # integration: the integral stops while its output is saturated)
        err = self._slot_error_m(obs)[:, 1:3] - setpoint
        kp, ki = np.array([g.kp_y, g.kp_z]), np.array([g.ki_y, g.ki_z])
        demand = setpoint - kp * err - ki * self.integral
        # the demand stays inside the box, as the seeker was designed and tuned (issue 16, when the set-point map
        # ended at the walls); where the map reaches beyond the box (wake_surfing since issue 24) this keeps its
        # tuned behaviour (the conditional integration below sees the clip as saturation)
        demand = np.clip(demand, self.box_low[1:], self.box_high[1:])
        act = np.zeros((obs.shape[0], 4))
        act[:, 1] = self.along.setpoint_action(demand[:, 0], 1)
        act[:, 2] = self.along.setpoint_action(demand[:, 1], 2)
        free = (demand > self.box_low[1:]) & (demand < self.box_high[1:]) & (np.abs(act[:, 1:3]) < 1.0)
        self.integral += np.where(free | (np.sign(act[:, 1:3]) * err > 0), err * dt, 0.0)
        act[:, 3] = self.along.act(obs)[:, 3]
        return np.clip(act, -1.0, 1.0).astype(np.float32)

    def _keeper_act(self, obs: np.ndarray, setpoint: np.ndarray) -> np.ndarray:
        """The station keeper holding ``setpoint`` (N, 2) (lateral, vertical offsets from the slot, m;
        :meth:`agents.station_keeper.StationKeeper.hold_offset_m`); the speed channel stays ``pid_formation``'s (the
        box's +-4 m/s range; the keeper's own is 2)."""
        return self.along.hold_actions(self.keeper.hold_offset_m(obs, setpoint), obs).astype(np.float32)

    @staticmethod
    def _slot_error_m(obs: np.ndarray) -> np.ndarray:
        """(N, 3) position minus the nominal slot demand, m, slot frame (from the observation)."""
        from agents.pid_formation import inverse_slog
        from formation_env.envs.observations import POSITION_SCALE_M
        from formation_env.sim.layout import ObservationLayout

        # the group lies before the neighbours' groups: at the same place in every layout
        return inverse_slog(obs[:, ObservationLayout(0).slice("slot_position_error")], POSITION_SCALE_M)
