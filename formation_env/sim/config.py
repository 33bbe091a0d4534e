"""Environment configuration: frozen dataclasses validated on construction (ValueError names the field).

Every numeric option has a type and a physical range, all in one table, :data:`OPTION_RANGES`
(``"Owner.name" -> (min, max, unit, why)``); docs/environments.md's "Option ranges" table is the same table
(``tests/envs/test_validation.py`` holds them equal). A value outside it is a ``ValueError`` naming the
option, the value and the range."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field, fields

import numpy as np

from ..constants import MAX_DURATION_S
from .layout import OPTIONS as OBSERVATION_OPTIONS

__all__ = ["ACTION_MODES", "OBS_MODES", "TURBULENCE_FIELDS", "TURBULENCE_FIELD_ALIASES", "OPTION_RANGES", "RewardWeights",
           "Randomisation", "EnvConfig"]

ACTION_MODES = ("surfaces", "residual", "setpoints")
OBS_MODES = ("flat", "dict")
TURBULENCE_FIELDS = ("von_karman", "dryden", "lanes", "independent")
TURBULENCE_FIELD_ALIASES = {"frozen": "lanes"}  # the lanes' name before issue 23 (saved configs and evaluations)

_WEIGHT = (0.0, 1e4, "", "a reward weight: non-negative and bounded, so a decision's reward stays finite "
           "(1e4 x the largest term is far below the float range)")

#: every numeric option: "Owner.name" -> (min, max, unit, why); min and max inclusive. For a 25 m/s,
#: 2.9 m span UAV (the Aerosonde) at 1000 m, physics at 50 Hz.
#: how vehicle 0's reference moves (EnvConfig.leader_reference): over the ground (the thesis's) or with the air
LEADER_REFERENCES = ("ground", "air")

OPTION_RANGES: dict[str, tuple[float, float, str, str]] = {
    "EnvConfig.control_hz": (0.5, 50.0, "Hz", "decision rate; must also divide the physics rate (50 Hz): at most one "
                             "decision per physics step, at least one every 2 s (100 physics steps)"),
    "EnvConfig.collision_separation_b": (0.0, 2.0, "spans", "CG separation that ends the episode; the closest slot "
                                         "(formation_keeping, 2.2 spans away) must stay outside it"),
    "EnvConfig.duration_s": (0.02, MAX_DURATION_S, "s", "episode length: at least one physics step (the scenario's "
                             "dt, 0.02 s in every built-in scenario), at most MAX_DURATION_S (one hour of flight)"),
    "EnvConfig.wake_update_every": (1, 50, "physics steps", "integer; ELL solves held at most 1 s (50 steps at "
                                    "50 Hz): the wake geometry moves a span in ~0.1 s"),
    "EnvConfig.throttle_max": (0.8, 2.0, "", "the flight control's throttle ceiling for every UAV: 1 is the Aerosonde's "
                               "full throttle; above 1 a counterfactual engine (manifold pressure above ambient, the "
                               "AeroSim engine map extrapolated) for measuring what thrust authority limits; below 0.8 "
                               "the 25 m/s trim (0.71) has no margin"),
    "RewardWeights.slot": _WEIGHT,
    "RewardWeights.slot_scale_m": (0.1, 1000.0, "m", "Huber knee of the slot error: from a tenth of a metre to "
                                   "the whole formation"),
    "RewardWeights.along_track_weight": (0.0, 1.0, "", "weight of the along-track component of the slot error "
                                         "against the cross-track ones (1: the distance from the slot)"),
    "RewardWeights.effort": _WEIGHT,
    "RewardWeights.rate": _WEIGHT,
    "RewardWeights.benefit": _WEIGHT,
    "RewardWeights.benefit_cap": (0.0, 2.0, "", "largest induced-drag saving the benefit term pays (the ELL reports at "
                                  "most ~1.06, on the leader's wake plane)"),
    "RewardWeights.progress": _WEIGHT,
    "RewardWeights.shaping_gamma": (0.0, 1.0, "", "a discount factor"),
    "RewardWeights.terminal_forfeit": (0.0, 10.0, "", "multiple of the slot cost still to come that a collision or "
                                       "crash forfeits (1: ending is never cheaper than flying on)"),
    "RewardWeights.separation": _WEIGHT,
    "RewardWeights.barrier_separation_b": (0.0, 10.0, "spans", "where the separation barrier starts (29 m): "
                                           "beyond every slot of the built-in formations"),
    "RewardWeights.collision": _WEIGHT,
    "RewardWeights.crash": _WEIGHT,
    "RewardWeights.box": _WEIGHT,
    "RewardWeights.box_scale_b": (0.01, 10.0, "spans", "Huber knee of the depth outside the safe box (3 cm to "
                                  "29 m)"),
    "RewardWeights.hold": _WEIGHT,
    "RewardWeights.hold_radius_b": (0.01, 10.0, "spans", "distance from the slot beyond which the hold phase charges "
                                    "the hold cost (3 cm to 29 m; the reconfiguration success window: 1 span)"),
    "Randomisation.initial_offset_m": (0.0, 50.0, "m", "std of the initial position jitter: up to ~6 slot "
                                       "spacings; beyond, followers start in another formation's place"),
    "Randomisation.slot_offset_b": (0.0, 2.0, "spans", "std of the slot jitter: about one slot spacing "
                                    "(2 spans) at most"),
    "Randomisation.steady_wind_mps": (0.0, 20.0, "m/s", "steady wind below the 25 m/s airspeed, so the "
                                      "formation can still make ground along its track (20 m/s: a strong gale)"),
    "Randomisation.crosswind_mps": (0.0, 20.0, "m/s", "as steady_wind_mps: a 20 m/s crosswind crabs a "
                                    "25 m/s UAV by 53 deg"),
    "Randomisation.turbulence_sigma_mps": (0.0, 10.0, "m/s", "turbulence intensity: MIL-F-8785C severe turbulence "
                                           "(exceeded with probability 1e-5) is ~5-7 m/s at low and medium "
                                           "altitude, extreme (1e-6) ~8-10 m/s"),
    "Randomisation.turbulence_sigma_spread": (0.0, 1.0, "", "fraction of turbulence_sigma_mps the per-episode "
                                              "intensity may fall below it: sigma drawn in [(1 - spread) sigma, sigma]"),
    "Randomisation.leader_turn_deg": (0.0, 180.0, "deg", "heading change of the leader's manoeuvre: a turn "
                                      "about (beyond 180 deg the same heading is reached the other way)"),
    "Randomisation.leader_climb_m": (0.0, 500.0, "m", "altitude change of the leader's manoeuvre: half the "
                                     "1000 m altitude, so a descent stays clear of the ground"),
    "Randomisation.leader_speed_mps": (0.0, 10.0, "m/s", "speed change of the leader's manoeuvre: 25 +- 10 m/s "
                                       "stays inside the model's 15-50 m/s airspeed bounds"),
    "Randomisation.leader_speed_offset_min_mps": (-5.0, 0.0, "m/s", "lower end of the leader's per-episode speed "
                                                  "offset from the scenario's 25 m/s: the Aerosonde trims at 20-30 m/s at "
                                                  "1000 m (heavy and slow its elevator nears the 25 deg limit)"),
    "Randomisation.leader_speed_offset_max_mps": (0.0, 5.0, "m/s", "upper end of the leader's per-episode speed "
                                                  "offset (fast, the throttle nears 1: at 28 m/s it is 0.99-1.04)"),
    "Randomisation.leader_fuel_offset_min_kg": (-1.5, 0.0, "kg", "lower end of the leader's per-episode fuel offset "
                                                "from the trim's 2 kg: 0.5 kg left at least (an empty tank stops the "
                                                "engine; 9.0 kg with AeroSim's 8.5 kg empty mass)"),
    "Randomisation.leader_fuel_offset_max_kg": (0.0, 3.0, "kg", "upper end of the leader's per-episode fuel offset: "
                                                "5 kg, AeroSim's capacity (13.5 kg gross)"),
}


def _is_real(value) -> bool:
    if not isinstance(value, numbers.Real) or isinstance(value, (bool, np.bool_)):
        return False
    try:
        return math.isfinite(float(value))
    except OverflowError:  # an int beyond the float range
        return False


def _in_range(owner: str, name: str, value, *, integer: bool = False, low: float | None = None) -> float | int:
    """``value`` checked against ``OPTION_RANGES[owner.name]`` (``low`` overrides the minimum)."""
    lo, hi, unit, why = OPTION_RANGES[f"{owner}.{name}"]
    lo = lo if low is None else low
    span = f"[{lo:g}, {hi:g}]" + (f" {unit}" if unit else "")
    if not _is_real(value) or (integer and not isinstance(value, (int, np.integer))):
        kind = "an integer" if integer else "a finite number"
        raise ValueError(f"{owner}: {name} must be {kind} in {span} ({why}), got {value!r}")
    if not lo <= value <= hi:
        raise ValueError(f"{owner}: {name} must be in {span} ({why}), got {value!r}")
    return int(value) if integer else float(value)


def _validate_fields(obj) -> None:
    owner = type(obj).__name__
    for f in fields(obj):
        object.__setattr__(obj, f.name, _in_range(owner, f.name, getattr(obj, f.name)))


@dataclass(frozen=True)
class RewardWeights:
    """Per-agent reward (per decision), with e the agent's distance from its slot (m; vehicle 0: from its
    reference path; in a scenario with a safe box, its along-track distance only; its along-track component
    weighted by ``along_track_weight``), h the Huber function h(x) = x^2 / 2 for |x| <= 1 and |x| - 1/2 beyond, d its
    distance to the nearest other UAV and a its normalised action:

        r = - slot * h(e / slot_scale_m)                                   quadratic near the slot, linear far
            + progress * (shaping_gamma * Phi(s') - Phi(s)),  Phi = -h(e / slot_scale_m)   potential-based
            - separation * ((d_safe - d) / (d_safe - d_coll))^2   for d < d_safe        barrier before a collision
            - effort * |a|^2 / 4 - rate * |a - a_prev|^2 / 4
            + benefit * min(induced-drag saving, benefit_cap)
            - (collision + F) * [collision] - (crash + F) * [left the envelope or non-finite]
            - box * (1 + h(min(q / box_scale, 5))) * [q > 0]  q: distance outside the scenario's safe box
            - (hold + H) * [hold phase and e >= hold_radius]              the success window of a moving slot

    F = terminal_forfeit * slot * h(min(e_prev, 100 m) / slot_scale_m) * (decisions left until the time
    limit): ending the episode forfeits the slot costs still to come, so a collision or crash must charge
    them, or ending early would pay (with terminal_forfeit = 1 the episode is never cheaper to end than to
    fly on at the current error).

    The safe box (:attr:`formation_env.scenarios.Scenario.safe_box_b`, relative to vehicle 0 in the slot frame)
    exists only in scenarios that define one (``wake_surfing``); q = 0 elsewhere. Its cost is a step of
    ``box`` as soon as the UAV is outside (a constraint, not a shaping: it must outweigh any saving the
    ELL reports beyond the box, up to ~0.8 in the band around the leader's wake plane the box excludes)
    plus h of the depth in ``box_scale_b`` spans (quadratic near the wall, linear far out).

    The hold phase of a UAV is the time after the last keyframe of its slot schedule (a moving slot, e.g.
    ``reconfiguration``: from 50 s; a fixed slot: the whole episode); the leader has none. There ``hold`` is
    charged at every decision the UAV is at least ``hold_radius_b`` spans from its slot (e as in the slot term):
    a step, like the success criterion of a reconfiguration (within 1 span at every decision of the last 5 s),
    which the Huber slot cost alone does not pose. H = terminal_forfeit * hold * (hold-phase decisions left) is
    charged with a collision or crash: with terminal_forfeit = 1 ending the episode never avoids the hold costs
    still to come (at most one per decision, as if outside the radius throughout).

    d_safe = ``barrier_separation_b`` spans, d_coll = the env's ``collision_separation_b`` spans. The slot
    term never saturates: it keeps decreasing with the error however far the UAV drifts. The shaping
    term is potential-based (Ng et al. 1999) and leaves the optimal policy unchanged when
    ``shaping_gamma`` equals the learner's discount."""

    slot: float = 1.0
    slot_scale_m: float = 5.0
    # < 1 poses a precision task: the saving of close formation changes within a tenth of a span across
    # the track and hardly along it (semi-infinite trailing legs), so the cross-track error is what to pay
    along_track_weight: float = 1.0
    effort: float = 0.01
    rate: float = 0.05
    benefit: float = 0.0
    # a task whose allowed region excludes where the lattice overstates the saving (close_formation: the band
    # |z| < 0.1 b around the leader's wake plane, issue 23 part 6) caps the paid saving at its optimum's, so
    # that entering the band pays nothing more than holding the slot; 2.0: no cap
    benefit_cap: float = 2.0
    progress: float = 1.0
    shaping_gamma: float = 0.995
    terminal_forfeit: float = 1.0
    separation: float = 5.0
    barrier_separation_b: float = 1.2
    collision: float = 50.0
    crash: float = 50.0
    box: float = 0.0
    box_scale_b: float = 0.1
    hold: float = 0.0
    hold_radius_b: float = 1.0

    def __post_init__(self) -> None:
        _validate_fields(self)  # each weight within OPTION_RANGES (a number, never bool)


@dataclass(frozen=True)
class Randomisation:
    """Per-episode randomisation for learning (all zero: the thesis scenario exactly).

    initial_offset_m: std of each follower's initial position jitter (NED, m).
    slot_offset_b: std of each slot's offset jitter (spans), applied to the whole schedule.
    steady_wind_mps: maximum steady horizontal wind speed (uniform in [0, max], random direction).
    crosswind_mps: maximum steady crosswind, perpendicular to the reference's initial track (uniform in
        +-max; added to the steady wind). A crosswind crabs the formation and turns the wake, which
        trails along the air-relative velocity, against the track (the wake-surfing task's moving optimum).
    turbulence_sigma_mps: turbulence intensity (m/s, all axes; MIL-F-8785C low-altitude scale lengths); the
        model is EnvConfig.turbulence_field (one frozen von Karman field per formation by default).
    turbulence_sigma_spread: each episode draws its intensity uniformly in [(1 - spread) sigma, sigma] (0: every
        episode at turbulence_sigma_mps; 1: from calm air to sigma), so one policy learns every level it will be
        judged at. Spectral fields only (von Karman, Dryden): the episode's field modes are scaled.
    leader_turn_deg, leader_climb_m, leader_speed_mps: amplitude of one random manoeuvre of the
        reference (heading change, altitude change, speed change), each drawn uniformly in +-amplitude
        and started at a random time in the first half of the episode.
    leader_speed_offset_min_mps, leader_speed_offset_max_mps: the leader's speed from the start: the reference
        path's speed is the scenario's (25 m/s) plus an offset drawn uniformly in [min, max] per episode (the
        manoeuvre's speed change adds to it); every UAV starts trimmed at it. Both 0: off; with
        leader_speed_mps at most 10 m/s from 25 in all (the model's 15-50 m/s). The Aerosonde trims at 1000 m
        from 20 to 30 m/s at every fuel load, but at 28 m/s its throttle is at 1 (0.99 at 2 kg, 1.04 at 5 kg: no
        margin) and at 21 m/s with 5 kg its elevator at -23 deg of its 25 (measured with aircraft.trim).
    leader_fuel_offset_min_kg, leader_fuel_offset_max_kg: the leader's initial fuel is the trim's 2 kg plus an
        offset drawn uniformly in [min, max] kg per episode (its weight: AeroSim mass = 8.5 kg empty + fuel), and
        it starts trimmed for it. Both 0: off.
    These are drawn after every other draw of the episode, so turning them on keeps its wind,
    manoeuvre and turbulence (the field's seed is drawn only with turbulence: a calm episode draws another leader); the leader (and, at another speed, every UAV) starts in trim with its flight
    control's integrators settled there (:meth:`formation_env.sim.Simulation.reset`).
    """

    initial_offset_m: float = 0.0
    slot_offset_b: float = 0.0
    steady_wind_mps: float = 0.0
    crosswind_mps: float = 0.0
    turbulence_sigma_mps: float = 0.0
    turbulence_sigma_spread: float = 0.0
    leader_turn_deg: float = 0.0
    leader_climb_m: float = 0.0
    leader_speed_mps: float = 0.0
    leader_speed_offset_min_mps: float = 0.0
    leader_speed_offset_max_mps: float = 0.0
    leader_fuel_offset_min_kg: float = 0.0
    leader_fuel_offset_max_kg: float = 0.0

    def __post_init__(self) -> None:
        _validate_fields(self)
        a, b = self.leader_speed_offset_min_mps, self.leader_speed_offset_max_mps
        if max(abs(a), abs(b)) + self.leader_speed_mps > 10.0:
            raise ValueError(f"Randomisation: the leader's speed offset plus leader_speed_mps must stay within 10 m/s "
                             f"of 25 (the model's 15-50 m/s airspeed bounds), got offsets [{a!r}, {b!r}] and "
                             f"leader_speed_mps {self.leader_speed_mps!r}")

    @property
    def any_manoeuvre(self) -> bool:
        """The reference path is integrated (a manoeuvre or a per-episode base speed)."""
        return (self.leader_turn_deg > 0 or self.leader_climb_m > 0 or self.leader_speed_mps > 0
                or self.random_speed)

    @property
    def random_leader(self) -> bool:
        """The leader's weight or speed is drawn per episode (and the UAVs start trimmed for it)."""
        return self.random_speed or self.random_fuel

    @property
    def random_fuel(self) -> bool:
        """The leader's fuel (weight) is drawn per episode."""
        return (self.leader_fuel_offset_min_kg, self.leader_fuel_offset_max_kg) != (0.0, 0.0)

    @property
    def random_speed(self) -> bool:
        """The leader's speed is drawn per episode."""
        return (self.leader_speed_offset_min_mps, self.leader_speed_offset_max_mps) != (0.0, 0.0)


@dataclass(frozen=True)
class EnvConfig:
    """Options of the formation environments.

    scenario: a name from :func:`formation_env.scenarios.scenario_names`, or a Scenario object.
    learning: which UAVs are agents: "all", "followers" (vehicle 0 flies the PID baseline on its
        path: a scripted leader) or a tuple of vehicle indices.
    action_mode: "surfaces" | "residual" | "setpoints" (what each action means: the environments
        page, "Action space"; the scales: :mod:`formation_env.sim.params`).
    control_hz: agent decision rate; the physics runs at 1 / scenario dt (50 Hz) and the action is
        held in between. Must divide the physics rate.
    wake: ELL wake coupling on or off (None: the scenario's default).
    obs_mode: "flat" (normalised Box, default) or "dict".
    collision_separation_b: minimum CG separation, spans, below which the episode ends (collision).
    duration_s: episode length (None: the scenario's).
    compute_benefit: compute each UAV's induced-drag saving (ELL Kutta-Joukowski loads against the same
        UAV alone) every decision, at the last physics step's ELL solve, for the infos (also forced on when
        the benefit weight is > 0; compiled into the decision step).
    wake_update_every: physics steps between ELL solves (1: every 50 Hz step, the default; 2: 25 Hz,
        about twice as fast; the induced wind is held in between).
    turbulence_field: the turbulence model (with ``randomisation.turbulence_sigma_mps`` > 0):
        "von_karman" (default) or "dryden": one frozen spatial field per formation (random Fourier modes,
        isotropic MIL-F-8785C / MIL-HDBK-1797 spectra), carried with the steady wind, that every UAV samples
        at its own position, with rotational gusts over the span and to the tail
        (:mod:`formation_env.atmosphere.spectral_field`); "lanes": the earlier approximation of a frozen
        Dryden field (one Dryden lane per UAV, Cholesky-mixed, Taylor-delayed; no rotational gusts;
        :mod:`formation_env.atmosphere.frozen_field`), also accepted under its old name "frozen";
        "independent": each UAV its own Dryden stream (uncorrelated gusts, for robustness studies).
    wake_coupling: how the ELL's wake reaches the 6-DOF (:mod:`formation_env.wake.coupling`): "effective_wind"
        (the thesis's uniform span average, Eqs. 4.4-4.7) or "load_weighted" (lift-matched ELL wing and
        load-weighted wind: the 6-DOF's lift, drag and rolling-moment increments are the ELL's); None (default):
        the scenario's (``load_weighted`` in the energy tasks close_formation and wake_surfing, the thesis's
        elsewhere).
    wake_fidelity: how finely the ELL resolves the wake another vehicle meets
        (:data:`formation_env.sim.formation.WAKE_FIDELITIES`): "lattice" (the thesis's 10 horseshoes per wing and
        discrete trailing legs), "sheet" (the other vehicles' legs as a continuous sheet near their wake plane) or
        "converged" (the sheet law, span correction and residual table of pairs: the saving and load-weighted wind
        of an nseg-80 lattice, within 0.2 % of its peak, at the nseg-10 cost; needs the load_weighted coupling);
        None (default): the scenario's ("converged" in close_formation and the N-UAV close formations, "lattice"
        elsewhere).
    throttle_max: the flight control's throttle ceiling for every UAV (1, the default: the Aerosonde's full
        throttle). Above 1 the engine's manifold pressure passes ambient and the AeroSim engine map is extrapolated:
        not an aircraft but a counterfactual with more thrust, for measuring what thrust authority limits a
        controller (docs/tasks/close_formation.md, "Known limits and open problems").
    leader_reference: how vehicle 0's reference moves (:data:`LEADER_REFERENCES`): "ground" (the thesis's: at the
        trim speed over the ground at a fixed altitude) or "air" (carried along the track and vertically by the air
        vehicle 0 flies in: a leader that holds its airspeed and flies level in the air mass;
        :attr:`formation_env.scenarios.Scenario.leader_air_relative`); None (default): the scenario's ("air" in
        close_formation, echelon3, vee5, vee9 and vee_rotation, "ground" elsewhere). Not with randomised leader
        manoeuvres.
    neighbour_count: the other UAVs each agent observes (the ``neighbours`` group): 0 every other UAV in index
        order (6 (V - 1) values: the size grows with the formation); k >= 1 the k whose slots are nearest the
        agent's, nearest first (6 k values whatever the formation's size, so one policy flies an echelon of 3,
        a vee of 5 and a vee of 9; a neighbour the formation lacks reads as a UAV 1 km behind); None (default):
        the scenario's (2 in the N-UAV close formations echelon3, vee5, vee9; 0 elsewhere).
    neighbour_wind: False (default) or True: the observation ends with the ``neighbour_wind`` group, each
        observed neighbour's ambient wind (steady + gusts + turbulence) minus the agent's own, in the agent's slot
        frame (3 values per neighbour; what formation members share over a data link). In a frozen field the UAV
        ahead meets now the air the agent meets a fraction of a second later, and the difference is what moves
        it (and its wake) relative to the agent.
    neighbour_attitude: False (default) or True: then the ``neighbour_attitude`` group, each observed neighbour's
        roll / 0.5 rad, roll rate (rad/s) and pitch minus the agent's / 0.5 rad (3 values per neighbour, after the
        winds when both are on). Its roll sets the height of its wingtip vortices (+-b/2 sin phi), where the
        agent's saving peaks; no other group carries it.
    reward, randomisation: a :class:`RewardWeights` / :class:`Randomisation`, or a dict of its options (exactly
        the instance built from it: the options it leaves out take their defaults; an unknown key is a
        ``TypeError`` naming it, a bad value a ``ValueError`` naming the option).
    """

    scenario: object = "formation_keeping"  # a scenario name or a formation_env.scenarios.Scenario
    learning: str | tuple = "all"
    action_mode: str = "setpoints"
    control_hz: float = 10.0
    wake: bool | None = None
    obs_mode: str = "flat"
    collision_separation_b: float = 0.5
    duration_s: float | None = None
    compute_benefit: bool = False
    wake_update_every: int = 1
    turbulence_field: str = "von_karman"
    wake_coupling: str | None = None
    wake_fidelity: str | None = None
    neighbour_count: int | None = None
    neighbour_wind: bool = False
    neighbour_attitude: bool = False
    throttle_max: float = 1.0
    leader_reference: str | None = None
    reward: RewardWeights = field(default_factory=RewardWeights)
    randomisation: Randomisation = field(default_factory=Randomisation)

    def __post_init__(self) -> None:
        from ..scenarios import Scenario, get_scenario, scenario_names
        from .validation import nested_options

        # the nested options: an instance, or a dict of its options (the same as the instance built from it)
        object.__setattr__(self, "reward", nested_options("EnvConfig", "reward", RewardWeights, self.reward))
        object.__setattr__(self, "randomisation", nested_options("EnvConfig", "randomisation", Randomisation,
                                                                 self.randomisation))
        if not isinstance(self.scenario, Scenario) and (not isinstance(self.scenario, str)
                                                        or self.scenario not in scenario_names()):
            raise ValueError(f"EnvConfig: unknown scenario {self.scenario!r}; available: {scenario_names()}")
        for name, choices in (("action_mode", ACTION_MODES), ("obs_mode", OBS_MODES)):
            value = getattr(self, name)
            if not isinstance(value, str) or value not in choices:
                raise ValueError(f"EnvConfig: {name} must be one of {choices}, got {value!r}")
        field_name = self.turbulence_field
        if not isinstance(field_name, str) or (field_name not in TURBULENCE_FIELDS
                                               and field_name not in TURBULENCE_FIELD_ALIASES):
            raise ValueError(f"EnvConfig: turbulence_field must be one of {TURBULENCE_FIELDS} (or 'frozen', the old name "
                             f"of 'lanes'), got {field_name!r}")
        if self.randomisation.turbulence_sigma_spread > 0 and field_name not in ("von_karman", "dryden"):
            raise ValueError(f"EnvConfig: randomisation.turbulence_sigma_spread > 0 (got "
                             f"{self.randomisation.turbulence_sigma_spread!r}) needs a spectral turbulence_field "
                             f"('von_karman' or 'dryden'), got {field_name!r}")
        sc = self.scenario if isinstance(self.scenario, Scenario) else get_scenario(self.scenario)
        physics_hz = 1.0 / sc.dt
        hz = _in_range("EnvConfig", "control_hz", self.control_hz)
        ratio = physics_hz / hz
        if abs(ratio - round(ratio)) > 1e-9:
            lo, hi, unit, why = OPTION_RANGES["EnvConfig.control_hz"]
            divisors = [f"{physics_hz / k:g}" for k in range(1, 11) if physics_hz / k >= lo]
            raise ValueError(f"EnvConfig: control_hz must divide the physics rate {physics_hz:g} Hz (e.g. "
                             f"{', '.join(divisors)}, ... down to {lo:g} Hz), got {self.control_hz!r}")
        object.__setattr__(self, "control_hz", hz)
        object.__setattr__(self, "collision_separation_b",
                           _in_range("EnvConfig", "collision_separation_b", self.collision_separation_b))
        if self.duration_s is not None:  # at least one physics step of this scenario
            object.__setattr__(self, "duration_s", _in_range("EnvConfig", "duration_s", self.duration_s, low=sc.dt))
        object.__setattr__(self, "wake_update_every",
                           _in_range("EnvConfig", "wake_update_every", self.wake_update_every, integer=True))
        object.__setattr__(self, "throttle_max", _in_range("EnvConfig", "throttle_max", self.throttle_max))
        if not (self.wake is None or isinstance(self.wake, (bool, np.bool_))):
            raise ValueError(f"EnvConfig: wake must be True, False or None (the scenario's default), got {self.wake!r}")
        if self.wake is not None:
            object.__setattr__(self, "wake", bool(self.wake))
        if self.wake_coupling is not None:
            from ..wake.coupling import COUPLINGS

            if not isinstance(self.wake_coupling, str) or self.wake_coupling not in COUPLINGS:
                raise ValueError(f"EnvConfig: wake_coupling must be None or one of {tuple(COUPLINGS)}, "
                                 f"got {self.wake_coupling!r}")
        if self.wake_fidelity is not None:
            from ..wake.coupling import WAKE_FIDELITIES

            if not isinstance(self.wake_fidelity, str) or self.wake_fidelity not in WAKE_FIDELITIES:
                raise ValueError(f"EnvConfig: wake_fidelity must be None (the scenario's) or one of {WAKE_FIDELITIES}, "
                                 f"got {self.wake_fidelity!r}")
        if self.leader_reference is not None and (not isinstance(self.leader_reference, str)
                                                  or self.leader_reference not in LEADER_REFERENCES):
            raise ValueError(f"EnvConfig: leader_reference must be None (the scenario's) or one of {LEADER_REFERENCES}, "
                             f"got {self.leader_reference!r}")
        if self.neighbour_count is not None:
            k = self.neighbour_count
            if isinstance(k, (bool, np.bool_)) or not isinstance(k, (int, np.integer)) or not 0 <= k <= 64:
                raise ValueError(f"EnvConfig: neighbour_count must be None (the scenario's), 0 (every other UAV) or an "
                                 f"integer in 1..64, got {k!r}")
            object.__setattr__(self, "neighbour_count", int(k))
        for name in OBSERVATION_OPTIONS:  # the optional observation groups' switches (formation_env.sim.layout)
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise ValueError(f"EnvConfig: {name} must be True or False, got {getattr(self, name)!r}")
            object.__setattr__(self, name, bool(getattr(self, name)))
        if not isinstance(self.compute_benefit, (bool, np.bool_)):
            raise ValueError(f"EnvConfig: compute_benefit must be True or False, got {self.compute_benefit!r}")
        object.__setattr__(self, "compute_benefit", bool(self.compute_benefit))
        object.__setattr__(self, "learning", _learning(self.learning))


def _learning(learning):
    """``learning`` checked: "all", "followers" or a tuple/list of distinct UAV indices (returned as a tuple)."""
    what = "'all', 'followers' or a tuple/list of UAV indices (ints)"
    if isinstance(learning, str):
        if learning not in ("all", "followers"):
            raise ValueError(f"EnvConfig: learning must be {what}, got {learning!r}")
        return learning
    if not isinstance(learning, (tuple, list, range, np.ndarray)) or (isinstance(learning, np.ndarray)
                                                                     and learning.ndim != 1):
        raise ValueError(f"EnvConfig: learning must be {what}, got {learning!r} ({type(learning).__name__})")
    items = tuple(learning)
    bad = [i for i in items if isinstance(i, (bool, np.bool_)) or not isinstance(i, (int, np.integer))]
    if bad:
        raise ValueError(f"EnvConfig: learning indices must be integers (UAV indices), got {bad[0]!r} in {learning!r}")
    idx = tuple(int(i) for i in items)
    if not idx or len(set(idx)) != len(idx):
        raise ValueError(f"EnvConfig: learning indices must be non-empty and unique, got {learning!r}")
    return idx
