"""The episode engine behind the environments: B formations flying a scenario, each UAV either
flown by the PID baseline or commanded by an agent, on the formation simulator.

Batched over formations (arrays (B, V, ...)); the PettingZoo/Gymnasium envs use B = 1, the vector
envs B > 1. No RL concepts beyond "this vehicle's command comes from outside".

One physics step follows exactly the order of the scenario runner (agents.run), so that a
formation flown entirely by the PID baseline gives the runner's numbers bit for bit:
observation -> demands (reference for vehicle 0, slot behind vehicle 0 for the others) ->
PID -> agent override -> simulator step (ELL wake -> RK4) -> envelope status.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np

from ..aircraft import trim
from ..aircraft.state import N_STATES, POS
from ..atmosphere.dryden import DrydenConfig, DrydenTurbulence, aircraft_seeds
from ..atmosphere.frozen_field import (frozen_field_advance, frozen_field_init, frozen_field_params, frozen_field_reset,
                                       frozen_field_rollout, frozen_field_sample)
from ..atmosphere.wind import WindInput
from ..frames import quaternion_dcm_terms
from ..scenarios import Scenario, get_scenario
from ..sim import FormationSimulator, WakeConfig
from .config import EnvConfig
from .observations import slog
from .rewards import min_separation_m as _min_separation_all

__all__ = ["FormationEpisode", "ActionTarget"]

# Leader manoeuvre rates (reference path): turn 3 deg/s, climb 1.5 m/s, speed change 0.5 m/s^2.
_TURN_RATE = math.radians(3.0)
_CLIMB_RATE = 1.5
_ACCEL = 0.5


@dataclass
class ActionTarget:
    """How agent actions enter: ``mode`` and per-vehicle (B, V, 4) normalised actions in [-1, 1]
    with ``mask`` (V,) True where the vehicle is agent-controlled."""

    mode: str
    actions: np.ndarray
    mask: np.ndarray
    mapped: np.ndarray | None = None  # the surfaces command, computed once per decision


class FormationEpisode:
    """B formations of the scenario's V UAVs. ``reset(seeds)`` then ``physics_step(target)``."""

    def __init__(self, config: EnvConfig, batch_size: int = 1, wake_config: WakeConfig | None = None) -> None:
        from agents.fcs import PIDFlightControl  # the baseline lives in agents/ (imported lazily)
        from agents.observation import fcs_observation, slot_demand, track_frame_offset_to_ned

        if not isinstance(config, EnvConfig):
            raise ValueError(f"FormationEpisode: config must be an EnvConfig, got {type(config).__name__}")
        self.config = config
        self.scenario: Scenario = config.scenario if isinstance(config.scenario, Scenario) else get_scenario(config.scenario)
        sc = self.scenario
        self.batch_size = int(batch_size)
        self.n_vehicles = sc.n_vehicles
        self.dt = sc.dt
        self.duration_s = sc.duration_s if config.duration_s is None else config.duration_s
        self.n_steps = int(round(self.duration_s / self.dt))
        self.wake = sc.wake_default if config.wake is None else config.wake
        self.trim = trim(sc.airspeed_mps, sc.altitude_m)
        self.fcs = PIDFlightControl.from_trim(self.trim, dt=sc.dt)
        self.surface_limit_rad = float(self.fcs.config.surface_limit_rad)
        self.throttle_limits = tuple(float(x) for x in self.fcs.config.throttle_limits)
        self._fcs_observation, self._slot_demand, self._track_to_ned = fcs_observation, slot_demand, track_frame_offset_to_ned
        # ``wake_config`` overrides the ELL options (core, evaluation points ...); ``config.wake``
        # and ``config.wake_update_every`` always apply.
        base = wake_config if wake_config is not None else WakeConfig()
        self.sim = FormationSimulator(self.n_vehicles, self.batch_size, dt=sc.dt, wake=WakeConfig(
            **{**base.__dict__, "enabled": self.wake, "update_every": config.wake_update_every}))
        b, v = self.batch_size, self.n_vehicles
        self.state = np.zeros((b, v, N_STATES))
        self.cstate = np.zeros((b * v, self.fcs.initial_state(1).shape[1]))
        self.step_count = np.zeros(b, dtype=np.int64)
        self.induced = np.zeros((b, v, 3))
        self.omega = np.zeros((b, v, 3))
        self.status = np.zeros((b, v), dtype=np.int64)
        self.commands = np.zeros((b, v, 4))
        self.position_demand = np.zeros((b, v, 3))
        self.velocity_demand = np.zeros((b, v, 3))
        self.slot_jitter = np.zeros((b, v, 3))  # m, track frame, per follower
        self.steady_wind = np.zeros((b, 3))
        self.manoeuvre = np.zeros((b, 4))  # start time s, heading change rad, altitude change m, speed change m/s
        self.ref_pos = np.zeros((b, 3))
        self.ref_vel = np.zeros((b, 3))
        # Turbulence: one frozen field per formation (default) or independent Dryden streams per UAV.
        self.turbulence: list[DrydenTurbulence | None] = [None] * b
        self.gust_ned = np.zeros((b, v, 3))  # frozen-field gust at each UAV's position now, m/s NED
        sigma = config.randomisation.turbulence_sigma_mps
        self.frozen_field = config.turbulence_field == "frozen" and sigma > 0
        if self.frozen_field:
            scales = DrydenConfig.low_altitude(sc.altitude_m, 1.0, sc.airspeed_mps, sc.dt).length_scale_m
            self.field_params = frozen_field_params((sigma,) * 3, scales, sc.airspeed_mps, sc.dt)
            self.field_state = frozen_field_init(self.field_params, b, v)
        self.rngs = [np.random.default_rng(0) for _ in range(b)]
        self._demands_at = None  # step counts at which the stored demands were computed

    # ------------------------------------------------------------------ reset
    def reset(self, indices=None, seeds=None) -> None:
        """Start the formations ``indices`` (default all) anew; ``seeds`` one int (or None) each."""
        idx = np.arange(self.batch_size) if indices is None else np.atleast_1d(np.asarray(indices, dtype=np.int64))
        seeds = [None] * len(idx) if seeds is None else list(seeds)
        if len(seeds) != len(idx):
            raise ValueError(f"reset: {len(seeds)} seeds for {len(idx)} formations")
        sc, rnd, v = self.scenario, self.config.randomisation, self.n_vehicles
        field_seeds = []
        for i, seed in zip(idx, seeds):
            rng = np.random.default_rng(seed)
            self.rngs[i] = rng
            state = np.repeat(self.trim.state, v, axis=0)
            state[:, POS] = sc.start_position_ned()
            jitter = np.zeros((v, 3))
            if v > 1 and rnd.slot_offset_b > 0:
                jitter[1:] = rng.normal(0.0, rnd.slot_offset_b * 2.9, (v - 1, 3))
            self.slot_jitter[i] = jitter
            state[1:, POS] += self._track_to_ned(jitter[1:], 0.0)
            if v > 1 and rnd.initial_offset_m > 0:
                state[1:, POS] += rng.normal(0.0, rnd.initial_offset_m, (v - 1, 3))
            self.state[i] = state
            if rnd.steady_wind_mps > 0:
                speed, direction = rng.uniform(0.0, rnd.steady_wind_mps), rng.uniform(-math.pi, math.pi)
                self.steady_wind[i] = [speed * math.cos(direction), speed * math.sin(direction), 0.0]
            else:
                self.steady_wind[i] = 0.0
            if rnd.any_manoeuvre:
                self.manoeuvre[i] = [rng.uniform(0.0, 0.5 * self.duration_s),
                                     math.radians(rng.uniform(-rnd.leader_turn_deg, rnd.leader_turn_deg)),
                                     rng.uniform(-rnd.leader_climb_m, rnd.leader_climb_m),
                                     rng.uniform(-rnd.leader_speed_mps, rnd.leader_speed_mps)]
            p0, v0 = sc.reference(0.0)
            self.ref_pos[i], self.ref_vel[i] = p0, v0
            self.turbulence[i] = None
            if rnd.turbulence_sigma_mps > 0:
                turbulence_seed = int(rng.integers(2**63 - 1))
                if self.frozen_field:
                    field_seeds.append(turbulence_seed)
                else:
                    cfg = DrydenConfig.low_altitude(sc.altitude_m, 1.0, sc.airspeed_mps, sc.dt)
                    cfg = DrydenConfig((rnd.turbulence_sigma_mps,) * 3, cfg.length_scale_m, sc.airspeed_mps, sc.dt)
                    self.turbulence[i] = DrydenTurbulence(cfg, aircraft_seeds(turbulence_seed, v))
            self.cstate[i * v:(i + 1) * v] = self.fcs.initial_state(v)
            self.step_count[i] = 0
            self.induced[i] = 0.0
            self.omega[i] = 0.0
            self.status[i] = 0
            self.commands[i] = self.trim.controls[0, :4]
        self.sim.reset_wake_hold()
        self._update_demands(self._velocity_ned())
        self._demands_at = None
        if self.frozen_field:
            frozen_field_reset(self.field_params, self.field_state, idx, field_seeds)
            self._sample_gusts()

    # ------------------------------------------------------------------ pieces
    @property
    def time_s(self) -> np.ndarray:
        return self.step_count * self.dt

    def ambient_wind(self) -> np.ndarray:
        """(B, V, 3) ambient wind at each UAV: scenario gusts + steady wind + the frozen turbulence
        field's gust at its position, NED m/s (independent turbulence is in :meth:`turbulence_body`)."""
        w = self.scenario.ambient_wind_ned(self.time_s) + self.steady_wind
        return w[:, None, :] + self.gust_ned

    def _field_geometry(self) -> tuple[np.ndarray, np.ndarray]:
        """Where the frozen field is read: every UAV's position (B, V, 3) and the formation's axes,
        vehicle 0's demanded track (B,). A diverged UAV (its formation's episode is ending) must neither
        stop the batch nor poison the others: non-finite positions and tracks are read as 0, and that
        gust is discarded with the episode."""
        vd0 = self.velocity_demand[:, 0]
        track = np.arctan2(vd0[:, 1], vd0[:, 0])
        pos = self.state[..., 10:13]
        return np.ascontiguousarray(np.where(np.isfinite(pos), pos, 0.0)), np.where(np.isfinite(track), track, 0.0)

    def _sample_gusts(self) -> None:
        """Read the frozen field at every UAV's current position."""
        frozen_field_sample(self.field_params, self.field_state, *self._field_geometry(), self.gust_ned)
        np.nan_to_num(self.gust_ned, copy=False)

    def _advance_turbulence(self) -> None:
        if self.frozen_field:
            frozen_field_advance(self.field_params, self.field_state)
        for t in self.turbulence:
            if t is not None:
                t.step()

    def turbulence_gust_ned(self, index: int | None = None) -> np.ndarray:
        """The turbulence each UAV flies through now, NED m/s (frozen field or independent): (B, V, 3),
        or (V, 3) for formation ``index`` alone (what the per-formation infos read)."""
        sel = slice(None) if index is None else index
        if self.frozen_field:
            return self.gust_ned[sel].copy()
        turbulent = self.turbulence if index is None else [self.turbulence[index]]
        if all(t is None for t in turbulent):
            return np.zeros_like(self.gust_ned[sel])
        from ..frames import dcm_body_to_ned_from_quaternion

        turb_body = self.turbulence_body() if index is None else turbulent[0].velocity_body
        with np.errstate(all="ignore"):
            r_bn = dcm_body_to_ned_from_quaternion(self.state[sel][..., 6:10])
            out = np.einsum("...ij,...j->...i", r_bn, turb_body)
        return np.nan_to_num(out)

    def controller_state(self) -> np.ndarray:
        """(B, V, 7) the PID's integrator and washout states (agents.fcs CSTATE_NAMES)."""
        return self.cstate.reshape(self.batch_size, self.n_vehicles, -1)

    def slot_schedule_features(self) -> np.ndarray:
        """(B, V, 10) each follower's slot schedule as observed: offset now (spans, track frame), its
        rate (slog 1 m/s), next keyframe's offset minus the current one (spans), time to the next
        keyframe (min(t, 10 s) / 10, 1 when none is left). Vehicle 0: zeros and 1."""
        b, v = self.batch_size, self.n_vehicles
        out = np.zeros((b, v, 10))
        out[..., 9] = 1.0
        t = self.time_s.astype(float)
        for j, slot in enumerate(self.scenario.slots):
            off, rate = slot.offset_and_rate(t)
            off = off + self.slot_jitter[:, j + 1]
            times = np.array([k[0] for k in slot.keyframes])
            offs = np.array([k[1] for k in slot.keyframes]) * slot.span_m
            nxt = np.searchsorted(times, t, side="right")
            has = nxt < len(times)
            nxt_c = np.minimum(nxt, len(times) - 1)
            next_off = np.where(has[:, None], offs[nxt_c] + self.slot_jitter[:, j + 1], off)
            out[:, j + 1, 0:3] = off / slot.span_m
            out[:, j + 1, 3:6] = slog(rate, 1.0)
            out[:, j + 1, 6:9] = (next_off - off) / slot.span_m
            out[:, j + 1, 9] = np.where(has, np.minimum(times[nxt_c] - t, 10.0) / 10.0, 1.0)
        return out

    def turbulence_body(self) -> np.ndarray:
        out = np.zeros((self.batch_size, self.n_vehicles, 3))
        for i, turb in enumerate(self.turbulence):
            if turb is not None:
                out[i] = turb.velocity_body
        return out

    def _velocity_ned(self) -> np.ndarray:
        out = np.empty(self.state.shape[:2] + (3,))
        _velocity_ned_kernel(np.ascontiguousarray(self.state), out)
        return out

    def _reference(self, i: int, t: float) -> tuple[np.ndarray, np.ndarray]:
        if not self.config.randomisation.any_manoeuvre:
            return self.scenario.reference(t)
        # Manoeuvring reference: integrated by the engine (explicit Euler on the physics grid).
        t0, dpsi, dh, dv = self.manoeuvre[i]
        tau = max(0.0, t - t0)
        psi = math.copysign(min(abs(dpsi), _TURN_RATE * tau), dpsi)
        climb = math.copysign(_CLIMB_RATE, dh) if 0.0 < tau < abs(dh) / _CLIMB_RATE else 0.0
        speed = self.scenario.airspeed_mps + math.copysign(min(abs(dv), _ACCEL * tau), dv)
        return self.ref_pos[i].copy(), np.array([speed * math.cos(psi), speed * math.sin(psi), -climb])

    def position_demand_now(self) -> np.ndarray:
        """(B, V, 3) demanded positions at the current time and state (the stored demands are those
        of the last physics step's start); computed once per state."""
        if self._demands_at is None or not np.array_equal(self._demands_at, self.step_count):
            self._update_demands(self._velocity_ned())
            self._demands_at = self.step_count.copy()
        return self.position_demand

    def _update_demands(self, vel_ned: np.ndarray) -> None:
        if not self.config.randomisation.any_manoeuvre:
            # Vectorised over formations (elementwise the same arithmetic as the scalar path below).
            t = self.time_s
            pd0, vd0 = self.scenario.reference(t)
            self.position_demand[:, 0], self.velocity_demand[:, 0] = pd0, vd0
            chi = np.arctan2(vd0[:, 1], vd0[:, 0]) if self.scenario.slot_frame == "leader_demand" else None
            for j, slot in enumerate(self.scenario.slots):
                off, rate = slot.offset_and_rate(t)
                p, w = self._slot_demand(self.state[:, 0, 10:13], vel_ned[:, 0], off + self.slot_jitter[:, j + 1], rate,
                                         track_angle_rad=chi)
                self.position_demand[:, j + 1], self.velocity_demand[:, j + 1] = p, w
            return
        for i in range(self.batch_size):
            t = float(self.time_s[i])
            self.position_demand[i, 0], self.velocity_demand[i, 0] = self._reference(i, t)
            vd0 = self.velocity_demand[i, 0]
            chi = np.arctan2(vd0[1], vd0[0]) if self.scenario.slot_frame == "leader_demand" else None
            for j, slot in enumerate(self.scenario.slots):
                off, rate = slot.offset_and_rate(t)
                p, w = self._slot_demand(self.state[i, 0, 10:13], vel_ned[i, 0], off + self.slot_jitter[i, j + 1], rate,
                                         track_angle_rad=chi)
                self.position_demand[i, j + 1], self.velocity_demand[i, j + 1] = p, w

    # ------------------------------------------------------------------ step
    def advance(self, target: ActionTarget | None, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
        """``n_steps`` physics steps with the actions held. Returns (status OR-ed over the steps
        (B, V), smallest CG separation seen (B,)). When every UAV is commanded directly the steps run
        in one compiled call; otherwise step by step with the PID baseline."""
        b, v = self.batch_size, self.n_vehicles
        if target is not None and target.mode == "surfaces" and target.mask.all():
            if target.mapped is None:
                target.mapped = self._apply_commands(target, self.commands)
            times = (self.step_count[None, :] + np.arange(n_steps)[:, None]) * self.dt  # (S, B)
            amb = np.broadcast_to((self.scenario.ambient_wind_ned(times) + self.steady_wind)[:, :, None, :], (n_steps, b, v, 3))
            turb = np.zeros((n_steps, b, v, 3))
            for i in range(b):
                t = self.turbulence[i]
                if t is not None:
                    turb[0, i] = t.velocity_body
                    for s in range(1, n_steps):
                        turb[s, i] = t.step()
                    t.step()
            if self.frozen_field:
                # The substeps run in one compiled call, so the field is read at the positions of the
                # decision's start (the transport delays change by < 1 % of a step over 0.1 s), at each
                # substep's time.
                gusts = frozen_field_rollout(self.field_params, self.field_state, *self._field_geometry(), n_steps)
                amb = amb + np.nan_to_num(gusts)
            self.commands = target.mapped
            res, status_any, min_sep = self.sim.step_many(self.state, target.mapped, amb, turb)
            self._take(res, n_steps)
            if self.frozen_field:
                self._sample_gusts()
            return status_any, min_sep
        status_any = np.zeros((b, v), dtype=np.int64)
        min_sep = np.full(b, np.inf)
        for _ in range(n_steps):
            self.physics_step(target)
            status_any |= self.status
            with np.errstate(invalid="ignore"):
                min_sep = np.fmin(min_sep, _min_separation_all(self.state).min(axis=1))
        return status_any, min_sep

    def physics_step(self, target: ActionTarget | None = None) -> None:
        """Advance every formation by one physics step (dt) with the agents' actions held."""
        b, v = self.batch_size, self.n_vehicles
        amb = self.ambient_wind()
        turb = self.turbulence_body()
        if target is not None and target.mode == "surfaces" and target.mask.all():
            # Every UAV is commanded directly: the PID baseline (and its observation) is not needed.
            if target.mapped is None:
                target.mapped = self._apply_commands(target, self.commands)
            self._advance(target.mapped, amb, turb)
            return
        flat = self.state.reshape(b * v, N_STATES)
        wind = WindInput(wind_ned=(amb + self.induced).reshape(b * v, 3), turbulence_body=turb.reshape(b * v, 3))
        obs0 = self._fcs_observation(flat, np.zeros(3), np.zeros(3), wind)
        self._update_demands(obs0["velocity_ned"].reshape(b, v, 3))
        self._demands_at = None
        pd, vd = self.position_demand.copy(), self.velocity_demand.copy()
        if target is not None and target.mode == "setpoints":
            pd, vd = self._apply_setpoints(target, pd, vd)
        obs = dict(obs0, position_demand_ned=pd.reshape(b * v, 3), velocity_demand_ned=vd.reshape(b * v, 3))
        cmd, self.cstate = self.fcs.act(obs, self.cstate)
        cmd = cmd.reshape(b, v, 4)
        if target is not None and target.mode in ("surfaces", "residual"):
            cmd = self._apply_commands(target, cmd)
        self._advance(cmd, amb, turb)

    def _advance(self, cmd: np.ndarray, amb: np.ndarray, turb: np.ndarray) -> None:
        self.commands = cmd
        res = self.sim.step(self.state, cmd, amb, turb)
        self._advance_turbulence()
        self._take(res, 1)
        if self.frozen_field:
            self._sample_gusts()

    def _take(self, res, n_steps: int) -> None:
        b = self.batch_size
        self.state, self.induced, self.omega, self.status = res.state, res.induced_wind_ned, res.induced_omega_body, res.status
        self.circulation = res.circulation
        self.step_count += n_steps
        self._demands_at = None
        if self.config.randomisation.any_manoeuvre:
            for s in range(n_steps):  # the manoeuvring reference path integrates on the physics grid
                for i in range(b):
                    _, vel = self._reference(i, float((self.step_count[i] - n_steps + s) * self.dt))
                    self.ref_pos[i] = self.ref_pos[i] + self.dt * vel

    def _limits(self) -> tuple[np.ndarray, np.ndarray]:
        lim = self.surface_limit_rad
        return np.array([-lim, -lim, -lim, self.throttle_limits[0]]), np.array([lim, lim, lim, self.throttle_limits[1]])

    def _apply_commands(self, target: ActionTarget, cmd: np.ndarray) -> np.ndarray:
        lo, hi = self._limits()
        a = target.actions
        m = target.mask
        out = cmd.copy()
        if target.mode == "surfaces":
            # a = 0 is the trim command; +-1 spans the surface limit (and half the throttle range) about it
            mapped = np.clip(self.trim.controls[0, :4] + a * surface_scale(self.surface_limit_rad), lo, hi)
            out[:, m] = mapped[:, m]
        else:  # residual: added to the PID command
            out[:, m] = np.clip(cmd[:, m] + a[:, m] * RESIDUAL_SCALE, lo, hi)
        return out

    def _apply_setpoints(self, target: ActionTarget, pd: np.ndarray, vd: np.ndarray):
        a, m = target.actions, target.mask
        chi = np.arctan2(vd[..., 1], vd[..., 0])
        dp = self._track_to_ned(a[..., :3] * SETPOINT_POSITION_SCALE_M, chi)
        speed = np.linalg.norm(vd, axis=-1, keepdims=True)
        dv = vd / np.maximum(speed, 1e-9) * (a[..., 3:4] * SETPOINT_SPEED_SCALE_MPS)
        pd, vd = pd.copy(), vd.copy()
        pd[:, m] += dp[:, m]
        vd[:, m] += dv[:, m]
        return pd, vd


# Action scaling (documented in formation_env.envs.actions)
def surface_scale(limit_rad: float) -> np.ndarray:
    """Surfaces-mode scale per unit action: the FCS surface limit (rad) for the three surfaces,
    0.5 for the throttle."""
    return np.array([limit_rad, limit_rad, limit_rad, 0.5])


RESIDUAL_SCALE = np.array([0.1, 0.1, 0.1, 0.2])  # rad, rad, rad, throttle fraction per unit action
SETPOINT_POSITION_SCALE_M = 5.0  # m per unit action, slot frame (along, starboard, down)
SETPOINT_SPEED_SCALE_MPS = 2.0  # m/s per unit action along the demanded track


@nb.njit(cache=True, error_model="numpy")
def _velocity_ned_kernel(state, out):
    """Ground velocity in NED (B, V, 3) from the body velocities and quaternions."""
    for b in range(state.shape[0]):
        for a in range(state.shape[1]):
            x = state[b, a]
            r00, r01, r02, r10, r11, r12, r20, r21, r22 = quaternion_dcm_terms(x[6], x[7], x[8], x[9])
            out[b, a, 0] = r00 * x[0] + r01 * x[1] + r02 * x[2]
            out[b, a, 1] = r10 * x[0] + r11 * x[1] + r12 * x[2]
            out[b, a, 2] = r20 * x[0] + r21 * x[1] + r22 * x[2]
