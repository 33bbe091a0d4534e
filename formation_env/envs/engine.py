"""The episode engine: B formations of a scenario as one :class:`~formation_env.sim.state.SimState`
stepped by the compiled decision step (:func:`formation_env.sim.step.step`).

This module only builds the named parameter structs from an :class:`EnvConfig`, draws the
per-episode randomisation at reset (numpy generators, one per formation and seed) and offers
read-only views of the state arrays. It holds no physics: every step is the compiled kernel, and
the scenario runner (every UAV PID-flown, one physics step per call) flies the same kernel.
"""

from __future__ import annotations

import math

import numpy as np

from ..aircraft import trim
from ..aircraft.state import POS
from ..atmosphere.frozen_field import frozen_field_reset
from ..control import PIDFlightControl
from ..control.law import fcs_params
from ..control.observation import ned_to_track_frame, track_frame_offset_to_ned
from ..geometry import aerosonde
from ..scenarios import AEROSONDE_SPAN_M, Scenario, get_scenario
from ..sim import WakeConfig
from ..sim.observe import REWARD_TERMS
from ..sim.params import (ACTION_MODE_CODES, RESIDUAL_SCALE, SETPOINT_POSITION_SCALE_M, SETPOINT_SPEED_SCALE_MPS,
                          ActionParams, RewardParams, StepParams, aircraft_arrays, safe_box_arrays, scenario_arrays,
                          setpoint_ranges, setpoint_speed_range, slot_error_axes, turbulence_params,
                          wake_arrays)
from ..sim.state import init_output, init_state
from ..sim.step import observe, refresh, step
from ..wake import WakeModel
from ..wake.loads import isolated_model
from .config import EnvConfig
from .observations import observation_size

__all__ = ["FormationEpisode", "surface_scale", "RESIDUAL_SCALE", "SETPOINT_POSITION_SCALE_M",
           "SETPOINT_SPEED_SCALE_MPS", "AEROSONDE_SPAN_M"]



def surface_scale(limit_rad: float) -> np.ndarray:
    """Surfaces-mode scale per unit action: the FCS surface limit (rad) for the three surfaces,
    0.5 for the throttle."""
    return np.array([limit_rad, limit_rad, limit_rad, 0.5])


class FormationEpisode:
    """B formations of the scenario's V UAVs: ``reset(indices, seeds)`` then :meth:`decide`.

    ``mask`` (V,) marks the agent-commanded UAVs (default none: every UAV PID-flown);
    ``substeps`` physics steps per decision (default 1)."""

    def __init__(self, config: EnvConfig, batch_size: int = 1, wake_config: WakeConfig | None = None,
                 mask=None, substeps: int = 1) -> None:
        if not isinstance(config, EnvConfig):
            raise ValueError(f"FormationEpisode: config must be an EnvConfig, got {type(config).__name__}")
        self.config = config
        self.scenario: Scenario = config.scenario if isinstance(config.scenario, Scenario) else get_scenario(config.scenario)
        sc = self.scenario
        self.batch_size = int(batch_size)
        self.n_vehicles = v = sc.n_vehicles
        self.dt = sc.dt
        self.duration_s = sc.duration_s if config.duration_s is None else config.duration_s
        self.n_steps = int(round(self.duration_s / self.dt))
        self.wake = sc.wake_default if config.wake is None else config.wake
        self.trim = trim(sc.airspeed_mps, sc.altitude_m)
        self.fcs = PIDFlightControl.from_trim(self.trim, dt=sc.dt)
        fc = self.fcs.config
        self.surface_limit_rad = float(fc.surface_limit_rad)
        self.throttle_limits = tuple(float(x) for x in fc.throttle_limits)
        wc = wake_config if wake_config is not None else WakeConfig()
        vehicle = aerosonde(nseg=wc.nseg, tailplane=wc.tailplane)
        self.wake_model = (WakeModel([vehicle] * v, core=wc.core, eval_points=wc.eval_points, rotational=wc.rotational,
                                     viscous_aic=wc.viscous_aic) if self.wake and v > 1 else None)
        from ..aircraft import AEROSONDE

        self.wing_origin_body = np.asarray(AEROSONDE.r_ac_body, float) - np.asarray(AEROSONDE.cg_gross_body, float)
        lattice = self.wake_model or WakeModel([vehicle])  # the kernel needs arrays even without wake
        self.mask = np.zeros(v, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        rnd, w = config.randomisation, config.reward
        sigma = rnd.turbulence_sigma_mps
        lim = self.surface_limit_rad
        self.params = StepParams(
            float(sc.dt), int(substeps), self.n_steps, self.wake_model is not None, int(config.wake_update_every),
            0 if sigma <= 0 else (1 if config.turbulence_field == "frozen" else 2),
            bool((config.compute_benefit or w.benefit > 0) and self.wake_model is not None),
            aircraft_arrays(), wake_arrays(lattice, self.wing_origin_body),
            wake_arrays(isolated_model(vehicle, wc.core, wc.eval_points, wc.rotational, lattice.kinematic_viscosity,
                                     wc.viscous_aic), self.wing_origin_body), scenario_arrays(sc, rnd.any_manoeuvre),
            fcs_params(fc, sc.dt),
            ActionParams(ACTION_MODE_CODES[config.action_mode], self.mask.copy(),
                         np.ascontiguousarray(self.trim.controls[0, :4], float), surface_scale(lim),
                         np.asarray(RESIDUAL_SCALE, float), *setpoint_ranges(sc), setpoint_speed_range(sc),
                         np.array([-lim, -lim, -lim, self.throttle_limits[0]]),
                         np.array([lim, lim, lim, self.throttle_limits[1]])),
            RewardParams(w.slot, w.slot_scale_m, w.effort, w.rate, w.benefit, w.progress, w.shaping_gamma,
                         w.terminal_forfeit, w.separation, w.barrier_separation_b * AEROSONDE_SPAN_M, w.collision, w.crash,
                         config.collision_separation_b * AEROSONDE_SPAN_M, w.box, w.box_scale_b * AEROSONDE_SPAN_M,
                         *safe_box_arrays(sc), slot_error_axes(sc)),
            turbulence_params(sc, sigma), float(sc.airspeed_mps))
        self.sim_state = init_state(self.batch_size, v, lattice.n_panels, self.params.field)
        self.out = init_output(self.batch_size, v, observation_size(v))

    # ------------------------------------------------------------------ reset
    def reset(self, indices=None, seeds=None) -> None:
        """Start the formations ``indices`` (default all) anew; ``seeds`` one int (or None) each."""
        idx = np.arange(self.batch_size) if indices is None else np.atleast_1d(np.asarray(indices, dtype=np.int64))
        seeds = [None] * len(idx) if seeds is None else list(seeds)
        if len(seeds) != len(idx):
            raise ValueError(f"reset: {len(seeds)} seeds for {len(idx)} formations")
        sc, rnd, v, s = self.scenario, self.config.randomisation, self.n_vehicles, self.sim_state
        field_seeds = []
        start = sc.start_position_ned()
        for i, seed in zip(idx, seeds):
            rng = np.random.default_rng(seed)
            state = np.repeat(self.trim.state, v, axis=0)
            state[:, POS] = start
            jitter = np.zeros((v, 3))
            if v > 1 and rnd.slot_offset_b > 0:
                jitter[1:] = rng.normal(0.0, rnd.slot_offset_b * 2.9, (v - 1, 3))
            s.slot_jitter[i] = jitter
            state[1:, POS] += track_frame_offset_to_ned(jitter[1:], 0.0)
            if v > 1 and rnd.initial_offset_m > 0:
                state[1:, POS] += rng.normal(0.0, rnd.initial_offset_m, (v - 1, 3))
            s.aircraft[i] = state
            if rnd.steady_wind_mps > 0:
                speed, direction = rng.uniform(0.0, rnd.steady_wind_mps), rng.uniform(-math.pi, math.pi)
                s.steady_wind[i] = [speed * math.cos(direction), speed * math.sin(direction), 0.0]
            else:
                s.steady_wind[i] = 0.0
            if rnd.crosswind_mps > 0:  # the reference flies north at the start: east is the crosswind
                s.steady_wind[i, 1] += rng.uniform(-rnd.crosswind_mps, rnd.crosswind_mps)
            s.manoeuvre[i] = 0.0
            if rnd.any_manoeuvre:
                s.manoeuvre[i] = [rng.uniform(0.0, 0.5 * self.duration_s),
                                  math.radians(rng.uniform(-rnd.leader_turn_deg, rnd.leader_turn_deg)),
                                  rng.uniform(-rnd.leader_climb_m, rnd.leader_climb_m),
                                  rng.uniform(-rnd.leader_speed_mps, rnd.leader_speed_mps)]
            s.reference_position[i] = sc.reference(0.0)[0]
            if rnd.turbulence_sigma_mps > 0:
                field_seeds.append(int(rng.integers(2**63 - 1)))
            s.controller[i] = 0.0
            s.controller[i, :, 6] = state[:, 5]  # the washout filter starts settled on the yaw rate
            s.step[i] = 0
            s.induced_wind_ned[i] = 0.0
            s.induced_omega_body[i] = 0.0
            s.circulation[i] = 0.0
            s.status[i] = 0
            s.command[i] = self.trim.controls[0, :4]
            s.previous_action[i] = 0.0
            s.episode_return[i] = 0.0
            s.episode_decisions[i] = 0
            s.gust_ned[i] = 0.0
        if field_seeds:
            frozen_field_reset(self.params.field, s.field, idx, field_seeds)
        refresh(self.params, s, idx, self.out)
        # the slot error the step measures (formation_env.sim.observe.slot_error): slot-frame components of
        # position minus demand, weighted by the scenario's axes (along-track only with a safe box)
        err = s.aircraft[idx][..., 10:13] - s.position_demand[idx]
        chi = np.arctan2(s.velocity_demand[idx, 0, 1], s.velocity_demand[idx, 0, 0])[:, None]
        s.previous_error[idx] = np.linalg.norm(self.params.reward.slot_error_axes * ned_to_track_frame(err, chi), axis=-1)
        self.out.collided[idx] = False
        self.out.crashed[idx] = False
        self.out.saving[idx] = 0.0
        self.out.reward_terms[idx] = 0.0
        self.out.box_depth_m[idx] = 0.0

    # ------------------------------------------------------------------ step
    def decide(self, actions: np.ndarray):
        """One decision for every formation: actions (B, V, 4) in [-1, 1] (validated by the caller;
        rows of PID-flown UAVs are ignored). Returns the :class:`~formation_env.sim.state.StepOutput`."""
        return step(self.params, self.sim_state, np.ascontiguousarray(actions, dtype=float), self.out)

    def observe(self) -> np.ndarray:
        """Recompute demands, turbulence sample and observations (B, V, D) at the current state (after
        editing the state arrays by hand; a step or reset already leaves them current)."""
        return observe(self.params, self.sim_state, self.out)

    def physics_step(self, actions=None) -> None:
        """One physics step (``substeps`` must be 1) with every UAV PID-flown (or ``actions``)."""
        if self.params.substeps != 1:
            raise ValueError("physics_step: this engine was built with substeps > 1; use decide()")
        a = np.zeros((self.batch_size, self.n_vehicles, 4)) if actions is None else actions
        self.decide(a)

    # ------------------------------------------------------------------ views (B, V, ...) of the state
    @property
    def state(self) -> np.ndarray:
        return self.sim_state.aircraft

    @property
    def induced(self) -> np.ndarray:
        return self.sim_state.induced_wind_ned

    @property
    def omega(self) -> np.ndarray:
        return self.sim_state.induced_omega_body

    @property
    def status(self) -> np.ndarray:
        return self.sim_state.status

    @property
    def commands(self) -> np.ndarray:
        return self.sim_state.command

    @property
    def position_demand(self) -> np.ndarray:
        """(B, V, 3) demanded positions at the current state and time, m NED."""
        return self.sim_state.position_demand

    def position_demand_now(self) -> np.ndarray:
        return self.sim_state.position_demand

    @property
    def velocity_demand(self) -> np.ndarray:
        return self.sim_state.velocity_demand

    @property
    def step_count(self) -> np.ndarray:
        return self.sim_state.step

    @property
    def slot_jitter(self) -> np.ndarray:
        return self.sim_state.slot_jitter

    @property
    def manoeuvre(self) -> np.ndarray:
        return self.sim_state.manoeuvre

    @property
    def ref_pos(self) -> np.ndarray:
        return self.sim_state.reference_position

    @property
    def gust_ned(self) -> np.ndarray:
        return self.sim_state.gust_ned

    @property
    def time_s(self) -> np.ndarray:
        return self.sim_state.step * self.dt

    def controller_state(self) -> np.ndarray:
        """(B, V, 7) the PID's integrator and washout states (formation_env.control.CSTATE_NAMES)."""
        return self.sim_state.controller

    def velocity_ned(self) -> np.ndarray:
        """(B, V, 3) ground velocities, m/s NED."""
        from ..frames import dcm_body_to_ned_from_quaternion

        r = dcm_body_to_ned_from_quaternion(self.state[..., 6:10])
        return np.einsum("...ij,...j->...i", r, self.state[..., 0:3])

    def ambient_wind(self) -> np.ndarray:
        """(B, V, 3) ambient wind at each UAV now: scenario gusts + steady wind + turbulence, m/s NED."""
        w = self.scenario.ambient_wind_ned(self.time_s) + self.sim_state.steady_wind
        return w[:, None, :] + self.sim_state.gust_ned

    def turbulence_gust_ned(self, index: int | None = None) -> np.ndarray:
        """The turbulence each UAV flies through now, NED m/s: (B, V, 3), or (V, 3) for formation ``index``."""
        sel = slice(None) if index is None else index
        return self.sim_state.gust_ned[sel].copy()

    def reward_terms(self, index: int) -> dict[str, np.ndarray]:
        """Formation ``index``'s last reward terms, name -> (V,)."""
        t = self.out.reward_terms[index]
        return {**{k: t[:, j] for j, k in enumerate(REWARD_TERMS)}, "total": self.out.reward[index]}
