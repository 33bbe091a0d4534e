"""The public batched simulation engine: :class:`Simulation`, B formations of a scenario stepped together.

Everything that flies episodes goes through it: the PettingZoo / Gymnasium / vector env adapters (which
keep no state of their own), the scenario runner (every UAV PID-flown at the physics rate), the batched
rollout of the evaluation, replay and the wake-surfing evaluation.

>>> from formation_env.sim import EnvConfig, Simulation
>>> sim = Simulation(EnvConfig(scenario="formation_keeping", action_mode="setpoints"), batch_size=4)
>>> out = sim.reset(seeds=[0, 1, 2, 3])
>>> out = sim.step(np.zeros((4, sim.n_agents, 4)))     # out.observation (4, V, D), out.reward (4, V), ...

The state is one :class:`~formation_env.sim.state.SimState` of arrays (nothing carries physics in
hidden attributes); :meth:`step` is the compiled decision step (:func:`formation_env.sim.step.step`),
:meth:`reset` draws each episode's randomisation with a numpy generator per formation and seed. What a
caller needs to set (a per-episode steady wind) is a reset option, never a write into the state arrays.
The arrays :meth:`step` returns are views updated in place by the next call: copy what you keep.

The boundary is checked (:mod:`formation_env.sim.validation`, the same checks the env adapters use): actions
real, finite and of shape (B, A, 4), clipped to [-1, 1]; seeds None or integers in [0, 2**63 - 1]; formation
indices distinct and in range; a batch size whose state fits in half the machine's memory. Each bad input is one
``ValueError`` (``TypeError`` for an unknown option name) saying what is allowed.

After an episode's end: a formation whose last step terminated or truncated it is frozen until it is reset. A
:meth:`step` leaves its state as it was, returns its last observation again with zero reward (and zero reward
terms), and holds its ``terminated`` / ``truncated`` flags, so nothing is flown or paid past the end. The vector
envs reset finished formations within the same call (auto-reset), so they never step a frozen one; a batched
rollout that steps on until its last formation ends reads the finished ones unchanged.

Shapes: B formations, V UAVs, A agents (the UAVs the actions command; the others fly the thesis PID),
D the observation size (its groups: ``observation_layout``). Units SI, frames NED earth and body (x forward, y starboard, z down).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..aircraft import AEROSONDE, trim
from ..aircraft.state import POS
from ..atmosphere.frozen_field import frozen_field_reset
from ..atmosphere.spectral_field import spectral_field_reset
from ..control import PIDFlightControl
from ..control.law import fcs_params, settled_controller
from ..control.observation import ned_to_track_frame, track_frame_offset_to_ned
from ..scenarios import AEROSONDE_SPAN_M, Scenario, get_scenario
from ..wake import WakeModel
from ..wake.coupling import coupling_arrays
from ..wake.loads import isolated_model
from .config import EnvConfig
from .formation import WakeConfig, resolve_fidelity, resolve_wake, wake_model_for, wake_vehicle, wing_origin_body
from .infos import INFO_REWARD_KEYS, InfoArrays, reward_info_key, separation_each
from .layout import ObservationLayout
from .observe import REWARD_TERMS
from .params import (TURBULENCE_CODES, ActionParams, RewardParams, StepParams, aircraft_arrays, scenario_arrays,
                     turbulence_params, wake_arrays)
from .state import StepOutput, init_output, init_state
from .step import observe, refresh, step
from .validation import batch_arrays as _batch_arrays
from .validation import check_actions, check_batch_size, check_indices, check_seeds
from .warmup import ensure_warm

__all__ = ["Simulation", "SimOutput", "InfoArrays", "RESET_OPTIONS", "INFO_REWARD_KEYS", "reward_info_key",
           "separation_each"]

#: the options :meth:`Simulation.reset` takes (an unknown one is a ``TypeError``)
RESET_OPTIONS = ("steady_wind_ned",)


def _trim_cached(airspeed_mps: float, altitude_m: float, fuel_kg: float):
    """:func:`~formation_env.aircraft.trim` at (airspeed, altitude, fuel), course north (the last few kept: a
    batch of resets at the trim's fuel trims the followers once)."""
    key = (float(airspeed_mps), float(altitude_m), float(fuel_kg))
    hit = _TRIMS.get(key)
    if hit is None:
        if len(_TRIMS) > 64:
            _TRIMS.clear()
        hit = _TRIMS[key] = trim(*key)
    return hit


_TRIMS: dict = {}


class SimOutput(NamedTuple):
    """What :meth:`Simulation.reset` and :meth:`Simulation.step` return, for every UAV (views: copy to keep).

    ``terminated`` / ``truncated`` describe the last step (a reset leaves them as they were, so that a
    caller resetting finished formations keeps reading why they finished)."""

    observation: np.ndarray  # (B, V, D) float64
    reward: np.ndarray  # (B, V) total reward of the last decision (0 after a reset)
    terminated: np.ndarray  # (B,) bool: collision or a UAV left the envelope
    truncated: np.ndarray  # (B,) bool: time limit reached (and not terminated)
    info: "InfoArrays"  # every info quantity as arrays with the batch axis


class Simulation:
    """B formations of ``config``'s scenario: ``reset(indices, seeds, options)``, then ``step(actions)``.

    ``agents``: the UAV indices the actions command (default: ``config.learning``; ``()``: every UAV
    flies the thesis PID, the scenario runner's case). ``wake_config``: how the ELL is modelled
    (default :class:`~formation_env.sim.formation.WakeConfig`). One decision holds the actions for
    ``physics_hz / config.control_hz`` physics steps."""

    def __init__(self, config: EnvConfig, batch_size: int = 1, *, agents=None,
                 wake_config: WakeConfig | None = None) -> None:
        if not isinstance(config, EnvConfig):
            raise ValueError(f"Simulation: config must be an EnvConfig, got {type(config).__name__}")
        ensure_warm(Simulation)  # a cold kernel cache compiles here, with progress on stderr, not in the first step
        if isinstance(batch_size, (bool, np.bool_)) or not isinstance(batch_size, (int, np.integer)) or batch_size < 1:
            raise ValueError(f"batch_size must be an integer >= 1, got {batch_size!r}")
        self.config = config
        self.scenario: Scenario = config.scenario if isinstance(config.scenario, Scenario) else get_scenario(config.scenario)
        sc = self.scenario
        self.batch_size = int(batch_size)
        self.n_vehicles = v = sc.n_vehicles
        self.agent_indices = self._agent_indices(agents)
        self.agent_mask = np.zeros(v, dtype=bool)
        self.agent_mask[list(self.agent_indices)] = True
        self.dt = sc.dt
        ratio = (1.0 / sc.dt) / config.control_hz
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(f"control_hz must divide the physics rate {1.0 / sc.dt:g} Hz, got {config.control_hz!r}")
        self.substeps = int(round(ratio))
        self.duration_s = sc.duration_s if config.duration_s is None else config.duration_s
        self.n_steps = int(round(self.duration_s / self.dt))
        self.wake = sc.wake_default if config.wake is None else config.wake
        # the neighbours each agent observes (0: every other UAV; k: the k nearest by slot)
        self.neighbour_count = sc.neighbour_count if config.neighbour_count is None else config.neighbour_count
        self.observation_layout = ObservationLayout.for_config(config)  # the groups and sizes of an observation
        self.trim = trim(sc.airspeed_mps, sc.altitude_m)
        fc = PIDFlightControl.from_trim(self.trim, dt=sc.dt, throttle_limits=(0.0, config.throttle_max)).config
        self.surface_limit_rad = float(fc.surface_limit_rad)
        self.throttle_limits = tuple(float(x) for x in fc.throttle_limits)
        # every wake choice made (coupling; sheet law, span correction, residual table from the wake fidelity)
        wc = resolve_wake(wake_config if wake_config is not None else WakeConfig(), config, sc)
        self.wake_config = wc
        self.wake_coupling = wc.coupling  # how the wake reaches the 6-DOF
        self.wake_fidelity = resolve_fidelity(config, sc)
        vehicle = wake_vehicle(wc)
        self.wake_model = wake_model_for(wc, v) if self.wake else None
        self.wing_origin_body = wing_origin_body(AEROSONDE)
        lattice = self.wake_model or WakeModel([vehicle])  # the kernel needs arrays even without wake
        alone = isolated_model(vehicle, wc.core, wc.eval_points, wc.rotational, lattice.kinematic_viscosity,
                               wc.viscous_aic)
        rnd, w = config.randomisation, config.reward
        # vehicle 0's reference carried by the air (EnvConfig.leader_reference, else the scenario's)
        self.leader_air_relative = (sc.leader_air_relative if config.leader_reference is None
                                    else config.leader_reference == "air")
        if (sc.leader_schedule is not None or self.leader_air_relative) and rnd.any_manoeuvre:
            given = {k: getattr(rnd, k) for k in ("leader_turn_deg", "leader_climb_m", "leader_speed_mps",
                                                  "leader_speed_offset_min_mps", "leader_speed_offset_max_mps")
                     if getattr(rnd, k) != 0.0}
            raise ValueError(f"scenario {sc.name!r} with its leader's reference set here (a Scenario.leader_schedule, or "
                             f"carried by the air: Scenario.leader_air_relative / EnvConfig.leader_reference 'air') cannot "
                             f"take a randomised leader manoeuvre or speed offset, which would replace it: got {given}; "
                             f"leader_turn_deg, leader_climb_m, leader_speed_mps and the speed offsets must be 0 for it "
                             f"(or EnvConfig.leader_reference 'ground' where the scenario has no leader_schedule)")
        sigma = rnd.turbulence_sigma_mps
        self.params = StepParams(
            dt_s=float(sc.dt), substeps=self.substeps, episode_steps=self.n_steps,
            wake_on=self.wake_model is not None, wake_update_every=int(config.wake_update_every),
            turbulence=0 if sigma <= 0 else TURBULENCE_CODES[config.turbulence_field],
            benefit_on=bool((config.compute_benefit or w.benefit > 0) and self.wake_model is not None),
            aircraft=aircraft_arrays(), wake=wake_arrays(lattice, self.wing_origin_body),
            wake_alone=wake_arrays(alone, self.wing_origin_body),
            scenario=scenario_arrays(sc, rnd.any_manoeuvre, self.leader_air_relative),
            fcs=fcs_params(fc, sc.dt), action=self._action_params(config), reward=self._reward_params(config),
            field=turbulence_params(sc, sigma, config.turbulence_field), trim_airspeed_mps=float(sc.airspeed_mps),
            coupling=coupling_arrays(lattice, self.wake_coupling, AEROSONDE), neighbour_count=self.neighbour_count,
            observation_switches=self.observation_layout.switch_flags())
        self.obs_size = self.observation_layout.size
        # the memory the batch needs, from one formation's arrays, checked before the batch's are allocated
        one = _batch_arrays(init_state(1, v, lattice.n_panels, self.params.field), init_output(1, v, self.obs_size))
        check_batch_size(self.batch_size, sum(a.nbytes for a in one) + 2 * v * 4 * 8, scenario=sc.name)
        self.state = init_state(self.batch_size, v, lattice.n_panels, self.params.field)
        self.output: StepOutput = init_output(self.batch_size, v, self.obs_size)
        self._per_formation = _batch_arrays(self.state, self.output)  # what a frozen formation keeps (step)
        self._ended = np.zeros(self.batch_size, dtype=bool)  # episode ended at a step, not reset since: frozen
        self._any_ended = False
        self.info = InfoArrays(self)
        self._actions = np.zeros((self.batch_size, v, 4))
        self._reset_once = np.zeros(self.batch_size, dtype=bool)
        self._all_reset = False
        self._all_agents = bool(self.agent_mask.all())

    # ------------------------------------------------------------------ construction
    def _agent_indices(self, agents) -> tuple[int, ...]:
        n, cfg = self.n_vehicles, self.config
        if agents is not None:
            idx = tuple(int(i) for i in agents)
            bad = [i for i in idx if not 0 <= i < n]
            if bad or len(set(idx)) != len(idx):
                raise ValueError(f"agents {list(agents)} must be unique UAV indices in [0, {n - 1}]")
            return tuple(sorted(idx))
        if cfg.learning == "all":
            return tuple(range(n))
        if cfg.learning == "followers":
            if n < 2:
                raise ValueError(f"learning='followers' needs a formation; scenario {cfg.scenario!r} has one UAV")
            return tuple(range(1, n))
        bad = [i for i in cfg.learning if not 0 <= i < n]
        if bad:
            raise ValueError(f"learning indices {bad} out of range for {n} UAVs in {cfg.scenario!r}")
        return tuple(sorted(cfg.learning))

    def _action_params(self, config: EnvConfig) -> ActionParams:
        return ActionParams.from_config(config.action_mode, self.agent_mask, self.trim.controls[0, :4],
                                        self.surface_limit_rad, self.throttle_limits, self.scenario)

    def _reward_params(self, config: EnvConfig) -> RewardParams:
        return RewardParams.from_config(config.reward, self.scenario, config.collision_separation_b,
                                        duration_s=self.duration_s, control_hz=config.control_hz)

    # ------------------------------------------------------------------ API
    @property
    def n_agents(self) -> int:
        return len(self.agent_indices)

    @property
    def benefit_enabled(self) -> bool:
        return bool(self.params.benefit_on)

    def reset(self, indices=None, seeds=None, options: dict | None = None) -> SimOutput:
        """Start the formations ``indices`` (default all) anew; ``seeds`` one int (or None) each.

        ``options`` (applied to every formation reset): ``steady_wind_ned`` (3,) or (n, 3) m/s NED
        replaces the episode's drawn steady wind (the random draws are made all the same, so the rest of
        the episode is the seed's)."""
        idx = check_indices(indices, self.batch_size)
        seeds = check_seeds(seeds, len(idx))
        wind = self._reset_options(options, len(idx))
        if not len(idx):  # nothing to reset
            return self._result()
        sc, rnd, v, s = self.scenario, self.config.randomisation, self.n_vehicles, self.state
        field_seeds, field_scales = [], []
        start = sc.start_position_ned()
        for i, seed in zip(idx, seeds):
            rng = np.random.default_rng(seed)
            state = np.repeat(self.trim.state, v, axis=0)
            state[:, POS] = start
            jitter = np.zeros((v, 3))
            if v > 1 and rnd.slot_offset_b > 0:
                jitter[1:] = rng.normal(0.0, rnd.slot_offset_b * AEROSONDE_SPAN_M, (v - 1, 3))
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
                s.manoeuvre[i, :4] = [rng.uniform(0.0, 0.5 * self.duration_s),
                                  math.radians(rng.uniform(-rnd.leader_turn_deg, rnd.leader_turn_deg)),
                                  rng.uniform(-rnd.leader_climb_m, rnd.leader_climb_m),
                                  rng.uniform(-rnd.leader_speed_mps, rnd.leader_speed_mps)]
            # the manoeuvring path's start, or an air-relative leader's air displacement (none yet)
            s.reference_position[i] = 0.0 if self.leader_air_relative else sc.reference(0.0)[0]
            if rnd.turbulence_sigma_mps > 0:
                field_seeds.append(int(rng.integers(2**63 - 1)))
                # drawn only with a spread, so that every other configuration keeps its seeds' episodes
                field_scales.append(1.0 - rnd.turbulence_sigma_spread * rng.uniform()
                                    if rnd.turbulence_sigma_spread > 0 else 1.0)
            s.controller[i] = 0.0
            s.controller[i, :, 6] = state[:, 5]  # the washout filter starts settled on the yaw rate
            s.command[i] = self.trim.controls[0, :4]
            if rnd.random_leader:  # drawn last: the episode's other draws are the seed's without them
                self._random_leader(i, rng, state)
            s.step[i] = 0
            s.induced_wind_ned[i] = 0.0
            s.induced_omega_body[i] = 0.0
            s.circulation[i] = 0.0
            s.status[i] = 0
            s.previous_action[i] = 0.0
            s.episode_return[i] = 0.0
            s.episode_decisions[i] = 0
            s.gust_ned[i] = 0.0
            s.gust_omega_body[i] = 0.0
        if wind is not None:
            s.steady_wind[idx] = wind
        if field_seeds:  # the field of the configured model from each episode's seed (the same draw for every model)
            if self.params.turbulence == TURBULENCE_CODES["von_karman"]:
                spectral_field_reset(self.params.field.modes, s.modes, idx, field_seeds)
                if rnd.turbulence_sigma_spread > 0:  # the episode's intensity: every mode scaled alike
                    s.modes.amplitude[idx] *= np.asarray(field_scales)[:, None, None]
            else:
                frozen_field_reset(self.params.field.lanes, s.field, idx, field_seeds)
        refresh(self.params, s, idx, self.output)
        # the slot error the step measures (formation_env.sim.observe.slot_error): slot-frame components of
        # position minus demand, weighted by the scenario's axes (along-track only with a safe box); the
        # infos at reset report the same quantity as after a step
        err = s.aircraft[idx][..., POS] - s.position_demand[idx]
        chi = np.arctan2(s.velocity_demand[idx, 0, 1], s.velocity_demand[idx, 0, 0])[:, None]
        s.previous_error[idx] = np.linalg.norm(self.params.reward.slot_error_axes * ned_to_track_frame(err, chi), axis=-1)
        o = self.output
        o.slot_error_m[idx] = s.previous_error[idx]
        o.separation_m[idx] = np.stack([separation_each(s.aircraft[i]) for i in idx])
        o.min_separation_m[idx] = o.separation_m[idx].min(axis=1)
        o.collided[idx] = False
        o.crashed[idx] = False
        o.saving[idx] = 0.0
        o.reward[idx] = 0.0
        o.reward_terms[idx] = 0.0
        o.box_depth_m[idx] = 0.0
        self._reset_once[idx] = True
        self._ended[idx] = False
        self._any_ended = bool(self._ended.any())
        return self._result()

    def _random_leader(self, i: int, rng, state: np.ndarray) -> None:
        """Formation i's leader weight and speed (``Randomisation.leader_speed_offset_*_mps``, ``leader_fuel_offset_*_kg``):
        draws the base speed offset, then the leader's fuel (each only when on); the leader starts trimmed for its
        fuel at that speed, the followers at it with the trim's fuel, each with its controller settled on its trim
        (:func:`~formation_env.control.law.settled_controller`). ``state`` (V, 16): the start state, positions kept."""
        rnd, sc, s = self.config.randomisation, self.scenario, self.state
        dv = rng.uniform(rnd.leader_speed_offset_min_mps, rnd.leader_speed_offset_max_mps) if rnd.random_speed else 0.0
        f0 = self.trim.fuel
        fuel = rng.uniform(f0 + rnd.leader_fuel_offset_min_kg, f0 + rnd.leader_fuel_offset_max_kg) if rnd.random_fuel \
            else f0
        s.manoeuvre[i, 4] = dv
        speed = sc.airspeed_mps + dv
        trims = [_trim_cached(speed, sc.altitude_m, fuel)] + [_trim_cached(speed, sc.altitude_m, self.trim.fuel)] * \
            (self.n_vehicles - 1)
        for k, tr in enumerate(trims):
            pos = state[k, POS].copy()
            state[k] = tr.state[0]
            state[k, POS] = pos
            s.command[i, k] = tr.controls[0, :4]
            s.controller[i, k] = settled_controller(self.params.fcs, tr.controls[0, :4], tr.theta, tr.phi,
                                                    tr.state[0, 5])
        s.aircraft[i] = state

    def _reset_options(self, options, n: int):
        if options is None:
            return None
        if not isinstance(options, dict):
            raise ValueError(f"reset options must be a dict or None, got {type(options).__name__}")
        unknown = sorted(set(options) - set(RESET_OPTIONS))
        if unknown:
            raise TypeError(f"unknown reset option {unknown[0]!r}; reset options: {list(RESET_OPTIONS)}")
        wind = options.get("steady_wind_ned")
        if wind is None:
            return None
        w = np.asarray(wind, dtype=float)
        if w.shape not in ((3,), (n, 3)) or not np.all(np.isfinite(w)) or np.any(np.abs(w) > 50.0):
            raise ValueError(f"reset option steady_wind_ned must be finite m/s NED within +-50 m/s, shape (3,) or "
                             f"({n}, 3), got {wind!r}")
        return w

    def step(self, actions=None) -> SimOutput:
        """One decision of every formation: ``actions`` (B, A, 4) real numbers for the agents, None for zeros.
        Checked as the module docstring says (:func:`~formation_env.sim.validation.check_actions`): values outside
        [-1, 1] clipped to it, the action space's rule; a formation whose episode ended stays frozen."""
        if not self._all_reset and not self._reset_once.all():
            raise RuntimeError(f"step() before reset(): formation(s) {np.nonzero(~self._reset_once)[0].tolist()} "
                               "were never reset; call reset() first")
        self._all_reset = True  # (once every formation was reset: the check above costs ~1.5 us a decision)
        if actions is not None:
            actions = check_actions(actions, (self.batch_size, self.n_agents, 4))
            if self._all_agents:  # every vehicle an agent: a plain copy
                np.copyto(self._actions, actions, casting="unsafe")  # as an assignment casts
            else:
                self._actions[:, self.agent_mask] = actions
        frozen = saved = None
        if self._any_ended:  # keep the finished formations as they are
            frozen = np.nonzero(self._ended)[0]
            saved = [a[frozen] for a in self._per_formation]  # fancy indexing copies
        step(self.params, self.state, self._actions, self.output)
        o = self.output
        if frozen is not None:
            for a, kept in zip(self._per_formation, saved):
                a[frozen] = kept
            o.reward[frozen] = 0.0
            o.reward_terms[frozen] = 0.0
        np.logical_or(o.terminated, o.truncated, out=self._ended)
        self._any_ended = bool(self._ended.any())
        return self._result()

    def observe(self) -> np.ndarray:
        """Recompute demands, turbulence sample and observations (B, V, D) at the current state."""
        return observe(self.params, self.state, self.output)

    def _result(self) -> SimOutput:
        o = self.output
        return SimOutput(o.observation, o.reward, o.terminated, o.truncated, self.info)

    # ------------------------------------------------------------------ infos (read by InfoArrays alone)
    def infos(self, i: int) -> list[dict]:
        """Per-vehicle info dicts of formation ``i`` (the adapters' infos): ``self.info.formation(i).per_vehicle()``
        (:meth:`InfoArrays.per_vehicle`: flat, the same keys at reset and after every step, copies)."""
        return self.info.formation(i).per_vehicle()

    # ------------------------------------------------------------------ read-only views (B, V, ...)
    @property
    def aircraft(self) -> np.ndarray:
        """(B, V, 16) Aerosonde states (formation_env.aircraft.state layout)."""
        return self.state.aircraft

    @property
    def position_demand(self) -> np.ndarray:
        """(B, V, 3) demanded positions at the current state and time, m NED."""
        return self.state.position_demand

    @property
    def induced(self) -> np.ndarray:
        """(B, V, 3) ELL effective induced wind, m/s NED: ``info.induced_wind_ned_mps``."""
        return self.info.induced_wind_ned_mps

    @property
    def omega(self) -> np.ndarray:
        """(B, V, 3) ELL effective rotational wind, rad/s body: ``info.induced_omega_body_rad_s``."""
        return self.info.induced_omega_body_rad_s

    @property
    def commands(self) -> np.ndarray:
        """(B, V, 4) controls of the last physics step: ``info.command``."""
        return self.info.command

    @property
    def velocity_demand(self) -> np.ndarray:
        """(B, V, 3) demanded ground velocities, m/s NED: ``info.velocity_demand_ned_mps``."""
        return self.info.velocity_demand_ned_mps

    @property
    def time_s(self) -> np.ndarray:
        """(B,) episode time, s: ``info.time_s``."""
        return self.info.time_s

    def velocity_ned(self) -> np.ndarray:
        """(B, V, 3) ground velocities, m/s NED."""
        from ..frames import dcm_body_to_ned_from_quaternion

        x = self.state.aircraft
        return np.einsum("...ij,...j->...i", dcm_body_to_ned_from_quaternion(x[..., 6:10]), x[..., 0:3])

    def ambient_wind(self) -> np.ndarray:
        """(B, V, 3) ambient wind at each UAV now: scenario gusts + steady wind + turbulence, m/s NED."""
        w = self.scenario.ambient_wind_ned(self.time_s) + self.state.steady_wind
        return w[:, None, :] + self.state.gust_ned

    def reward_terms(self, index: int) -> dict[str, np.ndarray]:
        """Formation ``index``'s last reward terms, name -> (V,) (``info.formation(index)``'s ``reward_terms`` by name
        and its ``reward`` as ``"total"``)."""
        f = self.info.formation(index)
        t = f.reward_terms
        return {**{k: t[:, j] for j, k in enumerate(REWARD_TERMS)}, "total": f.reward}
