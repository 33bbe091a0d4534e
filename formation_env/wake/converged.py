"""The span-efficiency correction of the coarse lattice's induced-drag saving (issue 23 part 6; docs/ell.md,
"Converged saving").

The saving ``1 - D_i(formation) / D_i(alone) = -dD / D_i(alone)`` of a coarse lattice (10 horseshoes per
wing) is biased high away from the wake plane because its *isolated* induced drag is: Kutta-Joukowski at the
bound midpoints of a one-chordwise-panel lattice converges as 1/nseg (lift-matched Aerosonde: D_i / L^2
= 8.852e-5 /N at nseg 10 against 9.684e-5 at 80 and 9.751e-5 at 160, i.e. span efficiency 1.117 -> 1.021
-> 1.014), while the interaction drag per unit lift squared is already close to the fine lattice's there.
For a planform without twist (the lift-matched wing's zero-lift shift is a uniform incidence) the isolated
spanload's shape does not depend on the angle of attack, so D_i / L^2 is a geometry constant of the
lattice (measured: 8.8523e-5 and 8.8515e-5 /N at the trim alpha and 1.7 deg above it) and the ratio

    kappa = (D_i / L^2)_coarse / (D_i / L^2)_fine

turns the coarse saving into the one with the fine lattice's isolated drag: saving x kappa
(:class:`formation_env.wake.WakeModel` ``saving_scale``). kappa is computed once per vehicle from two
isolated solves (:func:`span_efficiency_scale`). It corrects the ratio only: the absolute increments (the
energy account's newtons) and the effective winds are untouched, and so is the wake-plane ripple of the
discrete trailing legs (a different error, docs/ell.md).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

__all__ = ["FINE_NSEG", "REFERENCE_ALPHA_RAD", "induced_drag_per_lift_squared", "refined_vehicle",
           "span_efficiency_scale"]

FINE_NSEG = 80  # the converged reference lattice (horseshoes per surface) kappa is taken against
REFERENCE_ALPHA_RAD = float(np.radians(3.0))  # the isolated solve's angle of attack (kappa is alpha-independent)


def refined_vehicle(vehicle, nseg: int):
    """``vehicle`` with every lifting surface's lattice at ``nseg`` horseshoes (geometry unchanged)."""
    if not isinstance(nseg, int) or nseg < 1:
        raise ValueError(f"refined_vehicle: nseg must be an integer >= 1, got {nseg!r}")
    return dataclasses.replace(vehicle, surfaces=tuple(dataclasses.replace(s, nseg=nseg) for s in vehicle.surfaces))


def induced_drag_per_lift_squared(vehicle, alpha_rad: float = REFERENCE_ALPHA_RAD, airspeed_mps: float = 25.0) -> float:
    """D_i / L^2 (1/N, sea-level density) of ``vehicle`` flying alone at zero attitude and ``alpha_rad``:
    the Kutta-Joukowski near-field loads of its own lattice (:func:`formation_env.wake.vehicle_loads`)."""
    from .loads import vehicle_loads
    from .model import WakeModel
    from .state import FormationState

    model = WakeModel([vehicle])
    state = FormationState(np.zeros((1, 1, 3)), np.array([[[0.0, float(alpha_rad), 0.0]]]),
                           np.full((1, 1), float(airspeed_mps)), np.full((1, 1), float(alpha_rad)), np.zeros((1, 1)))
    loads = vehicle_loads(model, state, model.evaluate(state))
    lift, drag = float(loads.lift_n[0, 0]), float(loads.drag_n[0, 0])
    if not (lift > 0 and drag > 0):
        raise ValueError(f"induced_drag_per_lift_squared: the vehicle must lift at alpha {alpha_rad!r} "
                         f"(lift {lift:g} N, induced drag {drag:g} N)")
    return drag / lift ** 2


@functools.lru_cache(maxsize=32)
def span_efficiency_scale(vehicle, fine_nseg: int = FINE_NSEG) -> float:
    """kappa = (D_i / L^2) of ``vehicle``'s own lattice over that of the same vehicle with ``fine_nseg``
    horseshoes per surface (see the module docstring); the factor on its induced-drag saving
    (``WakeModel(saving_scale=...)``). ``vehicle`` a frozen (hashable) Vehicle; computed once."""
    return induced_drag_per_lift_squared(vehicle) / induced_drag_per_lift_squared(refined_vehicle(vehicle, fine_nseg))
