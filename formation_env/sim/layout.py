"""The observation layout: which groups one agent's flat observation holds, in which order, and their sizes.

Every observation group is declared once, in :data:`GROUPS` (name, size, whether the size is per observed
neighbour, the :class:`~formation_env.sim.config.EnvConfig` switch of an optional group, and its scaling, unit and
meaning). :class:`ObservationLayout` is the one value the rest of the package passes along: the
:class:`~formation_env.sim.simulation.Simulation` owns the layout of its observations
(``Simulation.observation_layout``), a policy's sidecar records the layout it was trained with
(:meth:`ObservationLayout.to_dict`), and agents, evaluation, replay and training read groups through
:meth:`ObservationLayout.slice` and :meth:`ObservationLayout.split` instead of computing offsets.

Adding an observation group touches the compiled kernel that computes it (``sim/observe.py``; an optional group's
switch is read by its place in the switches tuple the step carries, :meth:`ObservationLayout.switch_flags`), its
numpy oracle (``tests/oracles/env_step.py``), its declaration here and, for an optional group, the EnvConfig field
of its switch (``sim/config.py``; its check is generic): the step's parameters and stages, the Simulation, the envs,
the agents, evaluation, training, sidecars, replay and the documentation's groups table pass the layout along and
stay as they are.

This module is plain Python on purpose: no compiled kernel imports it, so editing it recompiles nothing
(:mod:`formation_env.kernel_cache`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

__all__ = ["ObservationGroup", "GROUPS", "OPTIONS", "MAX_NEIGHBOURS", "ObservationLayout"]

#: the most neighbours :meth:`ObservationLayout.fit` reads from an observation's length (EnvConfig.neighbour_count
#: and Scenario.neighbour_count go up to it too)
MAX_NEIGHBOURS = 64


@dataclass(frozen=True)
class ObservationGroup:
    """One observation group. ``size``: its values (per observed neighbour when ``per_neighbour``); ``option``: the
    EnvConfig switch (a bool field of the same name; the kernel reads it by its place in :data:`OPTIONS`) that adds
    it, None for a group every observation holds; ``scaling``, ``unit``, ``meaning``: its documentation (the groups
    table of docs/environments.md is generated from them)."""

    name: str
    size: int
    per_neighbour: bool = False
    option: str | None = None
    scaling: str = ""
    unit: str = ""
    meaning: str = ""


# In the order the compiled kernel (formation_env.sim.observe.observe_formation) writes them; the slot frame is
# the agent's demanded track (x along, y starboard, z down); slog(x, s) = sign(x) ln(1 + |x| / s).
GROUPS: tuple[ObservationGroup, ...] = (
    ObservationGroup("air_data", 3, scaling="/5, /0.1, /0.1", unit="m/s, rad",
                     meaning="airspeed minus trim airspeed, alpha, beta (relative to ambient + induced wind)"),
    ObservationGroup("attitude", 3, scaling="/0.5", unit="rad", meaning="roll, pitch, heading minus demanded track"),
    ObservationGroup("rates", 3, scaling="/1", unit="rad/s", meaning="body p, q, r"),
    ObservationGroup("altitude", 1, scaling="slog 10 m", unit="m", meaning="altitude minus the scenario altitude"),
    ObservationGroup("slot_position_error", 3, scaling="slog 1 m", unit="m",
                     meaning="position minus slot, slot frame"),
    ObservationGroup("slot_velocity_error", 3, scaling="slog 1 m/s", unit="m/s",
                     meaning="ground velocity minus demanded velocity, slot frame"),
    ObservationGroup("induced_wind", 3, scaling="/1", unit="m/s",
                     meaning="ELL effective induced translational wind, body axes"),
    ObservationGroup("induced_rotation", 3, scaling="/1", unit="rad/s",
                     meaning="ELL effective induced rotational wind, body axes"),
    ObservationGroup("ambient_wind", 3, scaling="slog 1 m/s", unit="m/s",
                     meaning="ambient wind (steady + gusts + turbulence) at the UAV, slot frame"),
    ObservationGroup("engine", 1, scaling="/545 - 1", unit="rad/s", meaning="shaft speed"),
    ObservationGroup("previous_action", 4, scaling="1", unit="-", meaning="the agent's previous action"),
    ObservationGroup("slot_schedule", 10, scaling="spans, slog 1 m/s, /10 s",
                     meaning="slot offset now (spans), its rate, the next keyframe's offset minus the current one, "
                             "time to the next keyframe (min(t, 10 s)/10; 1 when none is left); vehicle 0: zeros and 1"),
    ObservationGroup("controller_state", 7, scaling="slog 1", unit="SI",
                     meaning="the PID's integrators (speed, altitude, pitch, roll, heading, off-track) and washout "
                             "state"),
    ObservationGroup("neighbours", 6, per_neighbour=True, scaling="slog 3 m, slog 1 m/s", unit="m, m/s",
                     meaning="every other UAV in index order, or with `neighbour_count=k` the k whose slots are "
                             "nearest (a missing one: 1 km behind, same velocity): relative position then velocity, "
                             "slot frame"),
    ObservationGroup("neighbour_wind", 3, per_neighbour=True, option="neighbour_wind", scaling="slog 1 m/s",
                     unit="m/s",
                     meaning="each neighbour's ambient wind minus the agent's, slot frame (a missing one: 0)"),
    ObservationGroup("neighbour_attitude", 3, per_neighbour=True, option="neighbour_attitude",
                     scaling="/0.5, /1, /0.5", unit="rad, rad/s",
                     meaning="each neighbour's roll, roll rate and pitch minus the agent's (a missing one: 0)"),
)
_BY_NAME = {g.name: g for g in GROUPS}
#: the EnvConfig switches of the optional groups, in declaration order
OPTIONS: tuple[str, ...] = tuple(g.option for g in GROUPS if g.option)
_OPTION_GROUP = {g.option: g.name for g in GROUPS if g.option}


def _optional_names(optional) -> tuple[str, ...]:
    """``optional`` (names of optional groups, any order) checked and put in declaration order."""
    if isinstance(optional, str):
        optional = (optional,)
    names = set()
    for name in optional:
        g = _BY_NAME.get(name)
        if g is None or g.option is None:
            raise ValueError(f"ObservationLayout: {name!r} is not an optional observation group; optional groups: "
                             f"{tuple(_OPTION_GROUP.values())}")
        names.add(name)
    return tuple(g.name for g in GROUPS if g.name in names)


@dataclass(frozen=True)
class ObservationLayout:
    """The groups of one agent's flat observation and their sizes: ``neighbours`` observed neighbours (an agent of
    a formation of V UAVs observing every other one: V - 1) and the ``optional`` groups switched on (names, kept in
    declaration order). ``neighbours`` None: a layout not yet fixed to a formation (what a classical agent is told:
    :meth:`fit` fixes it from an observation's length); :attr:`groups`, :attr:`size` and :meth:`slice` need it
    fixed."""

    neighbours: int | None = None
    optional: tuple[str, ...] = ()
    #: a task's Python observation groups (:class:`formation_env.tasks.terms.ObservationTerm`), (name, size) pairs
    #: appended after the compiled ones
    extra: tuple[tuple[str, int], ...] = ()

    def __post_init__(self) -> None:
        k = self.neighbours
        if k is not None:
            if isinstance(k, (bool, np.bool_)) or not isinstance(k, (int, np.integer)) or k < 0:
                raise ValueError(f"ObservationLayout: neighbours must be None or an integer >= 0, got {k!r}")
            object.__setattr__(self, "neighbours", int(k))
        object.__setattr__(self, "optional", _optional_names(self.optional))
        extra = tuple((str(n), int(s)) for n, s in self.extra)
        clash = [n for n, s in extra if n in _BY_NAME or s < 1] + [n for i, (n, _) in enumerate(extra)
                                                                   if n in [m for m, _ in extra[:i]]]
        if clash:
            raise ValueError(f"ObservationLayout: a task's observation groups must have new names and sizes >= 1; "
                             f"{clash} do not")
        object.__setattr__(self, "extra", extra)

    def with_extra(self, groups) -> ObservationLayout:
        """This layout with a task's Python groups ((name, size) pairs) appended after the compiled ones."""
        return ObservationLayout(self.neighbours, self.optional, tuple(groups))

    @property
    def compiled_size(self) -> int:
        """Length of the part of the observation the compiled step writes (the groups before ``extra``)."""
        return self.size - sum(s for _, s in self.extra)

    # ------------------------------------------------------------------ construction
    @classmethod
    def of(cls, n_vehicles: int, neighbour_count: int | None = None, options: Mapping | None = None,
           **switches) -> ObservationLayout:
        """The layout of a formation of ``n_vehicles`` UAVs whose agents observe ``neighbour_count`` neighbours (0 or
        None: every other UAV), with the optional groups whose switches (:data:`OPTIONS`) are true in ``options`` (a
        mapping such as a sidecar's or EnvConfig options; other keys ignored) or ``switches``."""
        unknown = sorted(set(switches) - set(OPTIONS))
        if unknown:
            raise TypeError(f"unknown observation switch(es) {unknown}; the optional groups' switches: {OPTIONS}")
        k = int(neighbour_count) if neighbour_count else int(n_vehicles) - 1
        return cls(k, cls.options_on({**(options or {}), **switches}))

    @classmethod
    def for_config(cls, config) -> ObservationLayout:
        """The layout of an :class:`~formation_env.sim.config.EnvConfig` (its scenario's formation and neighbour
        count unless the config sets one)."""
        from ..scenarios import Scenario, get_scenario

        sc = config.scenario if isinstance(config.scenario, Scenario) else get_scenario(config.scenario)
        k = sc.neighbour_count if config.neighbour_count is None else config.neighbour_count
        return cls.of(sc.n_vehicles, k, {o: getattr(config, o) for o in OPTIONS})

    @staticmethod
    def options_on(options: Mapping) -> tuple[str, ...]:
        """The optional groups whose switches are true in ``options`` (any mapping; keys that are not switches are
        ignored)."""
        return tuple(_OPTION_GROUP[o] for o in OPTIONS if options.get(o))

    @classmethod
    def from_dict(cls, data: Mapping | None, options: Mapping | None = None) -> ObservationLayout:
        """The layout a sidecar records (:meth:`to_dict`); ``data`` None (a sidecar written before layouts were
        recorded): derived from the observation switches among its ``options``, the formation unfixed. A recorded
        layout whose groups differ from what this version declares for it is a ValueError (the policy was trained
        on other observations)."""
        if data is None:
            return cls(None, cls.options_on(options or {}))
        if not isinstance(data, Mapping) or "groups" not in data:
            raise ValueError(f"observation layout must be a mapping with 'neighbours' and 'groups', got {data!r}")
        recorded = [(str(name), int(size)) for name, size in data["groups"]]
        n_declared = len(recorded)
        while n_declared and recorded[n_declared - 1][0] not in _BY_NAME:
            n_declared -= 1  # a task's Python groups come last
        unknown = [name for name, _ in recorded[:n_declared] if name not in _BY_NAME]
        if unknown:
            raise ValueError(f"observation layout names groups this version does not declare: {unknown}")
        layout = cls(data.get("neighbours"), tuple(n for n, _ in recorded[:n_declared] if _BY_NAME[n].option),
                     tuple(recorded[n_declared:]))
        if layout.neighbours is not None and list(layout.groups.items()) != recorded:
            raise ValueError(f"observation layout {recorded} differs from this version's for the same groups "
                             f"{list(layout.groups.items())}")
        return layout

    def to_dict(self) -> dict:
        """JSON-ready: ``{"neighbours": k, "groups": [[name, size], ...]}`` (every group, in order)."""
        return {"neighbours": self.neighbours, "groups": [[n, s] for n, s in self.groups.items()]}

    # ------------------------------------------------------------------ reading
    @property
    def options(self) -> dict[str, bool]:
        """The EnvConfig switches that give this layout's optional groups (``{"neighbour_wind": True}``): what a
        policy trained on it must be flown with."""
        return {_BY_NAME[n].option: True for n in self.optional}

    def switches(self) -> dict[str, bool]:
        """Every optional group's switch, True or False, by its EnvConfig name."""
        return {g.option: g.name in self.optional for g in GROUPS if g.option}

    def switch_flags(self) -> tuple[bool, ...]:
        """Every optional group's switch in :data:`OPTIONS` order: what the compiled step carries
        (``StepParams.observation_switches``) and the kernel reads by place."""
        return tuple(g.name in self.optional for g in GROUPS if g.option)

    def _fixed(self, what: str) -> int:
        if self.neighbours is None:
            raise ValueError(f"ObservationLayout.{what}: the layout is not fixed to a formation (neighbours None); "
                             "fix it with fit(size) or of(n_vehicles, ...)")
        return self.neighbours

    @property
    def groups(self) -> dict[str, int]:
        """Name -> size of every group this layout holds, in order (the ``neighbours`` group even when 0)."""
        k = self._fixed("groups")
        return {**{g.name: g.size * k if g.per_neighbour else g.size for g in GROUPS
                   if g.option is None or g.name in self.optional}, **dict(self.extra)}

    @property
    def size(self) -> int:
        """Length D of the flat observation."""
        return sum(self.groups.values())

    def slice(self, name: str) -> slice:
        """Where group ``name`` lies in the flat observation (``obs[..., layout.slice("ambient_wind")]``)."""
        start = 0
        for n, s in self.groups.items():
            if n == name:
                return slice(start, start + s)
            start += s
        raise KeyError(f"observation group {name!r} is not in this layout; it has {tuple(self.groups)}")

    def split(self, obs: np.ndarray) -> dict[str, np.ndarray]:
        """The groups of flat observations ``obs`` (..., D) as views (a group of size 0 left out)."""
        if obs.shape[-1] != self.size:
            raise ValueError(f"observation length {obs.shape[-1]} is not this layout's {self.size}")
        out, k = {}, 0
        for name, size in self.groups.items():
            if size:
                out[name] = obs[..., k:k + size]
            k += size
        return out

    def fit(self, size: int, owner: str = "ObservationLayout") -> ObservationLayout:
        """This layout's groups fixed to the number of neighbours an observation of length ``size`` has (the
        length alone does not say which optional groups it holds: 47 + 6 x 3 = 47 + 9 x 2, so they come from
        here); a ValueError naming ``owner`` when no number fits (at least one neighbour with optional groups)."""
        base = sum(g.size for g in GROUPS if not g.per_neighbour and (g.option is None or g.name in self.optional))
        base += sum(s for _, s in self.extra)
        per = sum(g.size for g in GROUPS if g.per_neighbour and (g.option is None or g.name in self.optional))
        k, rem = divmod(int(size) - base, per)
        low = 1 if self.optional else 0
        if rem or not low <= k <= MAX_NEIGHBOURS:
            if not self.optional:
                raise ValueError(f"{owner}: observation length {size} matches no formation size")
            raise ValueError(f"{owner}: observation length {size} is not that of an observation with "
                             f"{' and '.join(self.optional)} ({base} + {per} k, k >= 1)")
        return ObservationLayout(k, self.optional, self.extra)
