"""Per-agent observations: a documented, normalised feature vector (or the same groups as a Dict).

Quantities that grow without bound during an episode (position, velocity and wind errors, distances
to neighbours, controller integrators) are *signed-log* scaled, ``slog(x, s) = sign(x) ln(1 + |x| / s)``:
linear (x / s) near zero, so small errors keep their resolution, and logarithmic far out, so a
UAV 300 m from its slot (slog = 5.7 at s = 1 m) is still distinguished from one 30 m away (3.4)
instead of saturating. Bounded quantities are divided by a scale. Every value is finally clipped to
[-OBS_CLIP, OBS_CLIP] (10: e^10 s, ~22 km for s = 1 m, far beyond any reachable error); a non-finite
value (only possible when the episode is ending because the aircraft diverged) is replaced by 0.

The "slot frame" of an agent is its demanded track: x along the demanded ground velocity, y to
starboard of it, z down. The slot is the agent's demanded position (vehicle 0: its reference path;
followers: vehicle 0's position plus the slot offset along vehicle 0's demanded track).

The groups, in order, with their sizes, scaling, units and meaning are declared once, in
:data:`formation_env.sim.layout.GROUPS` (the table below and docs/environments.md's are generated from it); the
groups of one env's observations are its :class:`~formation_env.sim.layout.ObservationLayout`
(``Simulation.observation_layout``).
"""

from __future__ import annotations

import numpy as np

# one table of scales, read by the compiled kernel (formation_env.sim.observe) and this documentation
from ..sim.observe import (ALTITUDE_SCALE_M, CONTROLLER_STATE_SCALE, CONTROLLER_STATE_SIZE,
                           NEIGHBOUR_POSITION_SCALE_M, OBS_CLIP, OMEGA_REF, POSITION_SCALE_M, SCHEDULE_SIZE,
                           VELOCITY_SCALE_MPS, WIND_SCALE_MPS)
from ..sim.layout import GROUPS as _GROUPS
from ..sim.layout import OPTIONS, ObservationLayout

__all__ = ["OBS_CLIP", "GROUPS", "SCHEDULE_SIZE", "CONTROLLER_STATE_SIZE", "ObservationLayout", "observation_size",
           "group_sizes", "to_dict", "slog", "groups_table"]

GROUPS = tuple(g.name for g in _GROUPS)
SCALES = (ALTITUDE_SCALE_M, CONTROLLER_STATE_SCALE, NEIGHBOUR_POSITION_SCALE_M, OMEGA_REF, POSITION_SCALE_M,
          VELOCITY_SCALE_MPS, WIND_SCALE_MPS)


def slog(x, scale):
    """Signed log: sign(x) ln(1 + |x| / scale) (x / scale near zero, logarithmic far out)."""
    return np.sign(x) * np.log1p(np.abs(x) / scale)


def _layout(n_vehicles, neighbour_count, switches, options) -> ObservationLayout:
    """The layout of the helpers below: ``switches`` the optional groups' switches given positionally, in the order
    of :data:`formation_env.sim.layout.OPTIONS`, ``options`` by name."""
    if len(switches) > len(OPTIONS):
        raise TypeError(f"at most {len(OPTIONS)} positional observation switches ({OPTIONS}), got {len(switches)}")
    return ObservationLayout.of(n_vehicles, neighbour_count, dict(zip(OPTIONS, switches)), **options)


def group_sizes(n_vehicles: int, neighbour_count: int | None = None, *switches: bool, **options: bool) -> dict[str, int]:
    """Size of each observation group for V UAVs (``neighbour_count`` k: k neighbours observed, whatever V; the
    optional groups' switches, EnvConfig's, by name or in the order of ``OPTIONS``): :attr:`ObservationLayout.groups`."""
    return _layout(n_vehicles, neighbour_count, switches, options).groups


def observation_size(n_vehicles: int, neighbour_count: int | None = None, *switches: bool, **options: bool) -> int:
    """Length D of one UAV's flat observation (arguments as :func:`group_sizes`): :attr:`ObservationLayout.size`."""
    return _layout(n_vehicles, neighbour_count, switches, options).size


def to_dict(vector: np.ndarray, n_vehicles, neighbour_count: int | None = None, *switches: bool,
            **options: bool) -> dict[str, np.ndarray]:
    """Split flat observations (..., D) into the named groups: ``n_vehicles`` an :class:`ObservationLayout` (the
    env's: ``Simulation.observation_layout``), or a formation size with the arguments of :func:`group_sizes`."""
    layout = n_vehicles if isinstance(n_vehicles, ObservationLayout) else _layout(n_vehicles, neighbour_count,
                                                                                  switches, options)
    return layout.split(vector)


def groups_table() -> list[str]:
    """The groups as a markdown table (docs/environments.md's): name, size, scaling, unit, meaning."""
    rows = ["| group | size | scaling | unit | meaning |", "|---|---|---|---|---|"]
    for g in _GROUPS:
        size = f"{g.size} per neighbour" if g.per_neighbour else str(g.size)
        meaning = (f"option `{g.option}=True`: " if g.option else "") + g.meaning
        rows.append(f"| `{g.name}` | {size} | {g.scaling} | {g.unit} | {meaning} |")
    return rows


if __doc__:  # None under python -OO
    __doc__ += "\n" + "\n".join(groups_table()) + "\n"
