"""The wake set-up of the formation simulation and the physics step it runs: ELL effective wind -> Aerosonde dynamics.

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

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..aircraft import AEROSONDE, AerosondeParams
from ..aircraft.state import POS, QUAT
from ..frames import dcm_body_to_ned_from_quaternion, euler_from_quaternion
from ..geometry import Vehicle, aerosonde
from ..wake import FormationState, WakeModel
from ..wake.coupling import COUPLINGS, WAKE_FIDELITIES, lift_matched_vehicle


__all__ = ["WakeConfig", "WAKE_FIDELITIES", "ell_state_from_aircraft", "wake_model_for", "wake_vehicle",
           "resolve_coupling", "resolve_fidelity", "resolve_sheet", "resolve_wake", "wing_origin_body"]

# the sheet law, span correction and residual table each wake fidelity (WAKE_FIDELITIES) sets
_FIDELITY_FLAGS = {"lattice": (False, False, False), "sheet": (True, False, False), "converged": (True, True, True)}


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
    # how the wake reaches the 6-DOF (formation_env.wake.coupling.COUPLINGS): "effective_wind" (the thesis's)
    # or "load_weighted" (consistent with the ELL's loads; the energy tasks'); None: EnvConfig.wake_coupling,
    # else the scenario's (resolve_coupling)
    coupling: str | None = None
    # The next three say how finely the wake is resolved; None: what the wake fidelity (EnvConfig.wake_fidelity, else
    # the scenario's, else "lattice": WAKE_FIDELITIES) sets (resolve_wake), an explicit value overrides it.
    # the span-efficiency correction of the induced-drag saving (WakeModel saving_scale =
    # formation_env.wake.converged.span_efficiency_scale: the coarse lattice's 1/nseg bias of the ratio removed);
    # False: the lattice's own ratio (the thesis; docs/ell.md "Converged saving")
    span_correction: bool | None = None
    # the ELL's sheet law (WakeModel sheet: the other vehicles' trailing legs as a continuous sheet near their
    # wake plane; False the thesis's discrete legs)
    sheet: bool | None = None
    # the residual table of pairs on top of the sheet law and span correction (formation_env.wake.residual: the
    # saving and both couplings' winds of a fine nseg-80 lattice at the coarse lattice's cost); requires
    # the sheet law, span correction, nseg 10, no tailplane and the load_weighted coupling (what it was built for)
    residual_table: bool | None = None

    def __post_init__(self) -> None:
        for name in ("span_correction", "sheet", "residual_table"):
            v = getattr(self, name)
            if v is not None and not isinstance(v, bool):
                raise ValueError(f"WakeConfig: {name} must be None, True or False, got {v!r}")
        if self.residual_table and not (self.sheet is not False and self.span_correction is not False
                                        and self.nseg == 10 and not self.tailplane):
            raise ValueError("WakeConfig: residual_table=True needs sheet=True, span_correction=True, nseg=10 and "
                             f"tailplane=False (the table's base), got sheet={self.sheet!r}, "
                             f"span_correction={self.span_correction!r}, nseg={self.nseg!r}, "
                             f"tailplane={self.tailplane!r}")
        if self.coupling is not None and self.coupling not in COUPLINGS:
            raise ValueError(f"WakeConfig: coupling must be None or one of {tuple(COUPLINGS)}, got {self.coupling!r}")
        if not isinstance(self.update_every, int) or self.update_every < 1:
            raise ValueError(f"WakeConfig: update_every must be an integer >= 1, got {self.update_every!r}")
        if not isinstance(self.nseg, int) or self.nseg < 1:
            raise ValueError(f"WakeConfig: nseg must be an integer >= 1, got {self.nseg!r}")


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


def wing_origin_body(params: AerosondeParams = AEROSONDE) -> np.ndarray:
    """(3,) ELL's vehicle origin (the wing's root quarter-chord point, ~ the aerodynamic centre) relative to
    the CG, m body: the aircraft state is that of its CG, and AeroSim gives both relative to the propeller hub."""
    return np.asarray(params.r_ac_body, float) - np.asarray(params.cg_gross_body, float)


def resolve_coupling(wake: WakeConfig, config=None, scenario=None) -> str:
    """The wake coupling a simulation flies: ``wake.coupling`` if set, else ``config.wake_coupling`` (an
    EnvConfig) if set, else ``scenario.wake_coupling``, else the thesis's "effective_wind"."""
    for source in (wake.coupling, getattr(config, "wake_coupling", None), getattr(scenario, "wake_coupling", None)):
        if source is not None:
            return source
    return "effective_wind"


def resolve_fidelity(config=None, scenario=None) -> str:
    """The wake fidelity a simulation flies (:data:`WAKE_FIDELITIES`): ``config.wake_fidelity`` (an EnvConfig)
    if set, else ``scenario.wake_fidelity``, else the thesis's "lattice"."""
    for source in (getattr(config, "wake_fidelity", None), getattr(scenario, "wake_fidelity", None)):
        if source is not None:
            return source
    return "lattice"


def resolve_wake(wake: WakeConfig, config=None, scenario=None) -> WakeConfig:
    """``wake`` with every choice made: the coupling (:func:`resolve_coupling`) and the sheet law, span
    correction and residual table that are None in ``wake`` set by the wake fidelity (:func:`resolve_fidelity`).
    The converged fidelity's table applies only to the wake it was built for; asked for elsewhere (another
    lattice, a tailplane or the effective-wind coupling) it is one clear error, naming the lighter fidelities."""
    fidelity = resolve_fidelity(config, scenario)
    if fidelity not in _FIDELITY_FLAGS:
        raise ValueError(f"wake fidelity must be one of {WAKE_FIDELITIES}, got {fidelity!r}")
    sheet, span, table = _FIDELITY_FLAGS[fidelity]
    coupling = resolve_coupling(wake, config, scenario)
    sheet = sheet if wake.sheet is None else wake.sheet
    span = span if wake.span_correction is None else wake.span_correction
    table = table if wake.residual_table is None else wake.residual_table
    # checked before the WakeConfig is rebuilt, so that the error names the fidelity that asked for the table
    if table and not (sheet and span and wake.nseg == 10 and not wake.tailplane and coupling == "load_weighted"):
        raise ValueError(f"wake fidelity {fidelity!r}: the residual table needs sheet=True, span_correction=True, "
                         f"nseg=10, tailplane=False and the load_weighted coupling (what it was built for), got "
                         f"sheet={sheet}, span_correction={span}, nseg={wake.nseg}, tailplane={wake.tailplane}, "
                         f"coupling={coupling!r}; fly wake_fidelity 'sheet' or 'lattice' for another wake")
    return dataclasses.replace(wake, coupling=coupling, sheet=sheet, span_correction=span, residual_table=table)


def resolve_sheet(wake: WakeConfig, scenario=None) -> bool:
    """Whether a simulation's ELL takes the sheet law (:class:`WakeModel`'s ``sheet``): ``wake.sheet`` if
    set, else what the scenario's wake fidelity sets (:func:`resolve_wake`)."""
    if wake.sheet is not None:
        return bool(wake.sheet)
    return _FIDELITY_FLAGS[resolve_fidelity(None, scenario)][0]


def wake_vehicle(wake: WakeConfig, coupling: str | None = None) -> Vehicle:
    """The Aerosonde the ELL models as ``wake`` configures it: Table 6.1's wing (and tailplane), with the
    ``load_weighted`` coupling lift-matched (its wing at the 6-DOF's zero-lift angle,
    :func:`formation_env.wake.coupling.lift_matched_vehicle`). ``coupling`` None: ``wake.coupling``."""
    coupling = resolve_coupling(wake) if coupling is None else coupling
    if coupling not in COUPLINGS:
        raise ValueError(f"wake_vehicle: coupling must be one of {tuple(COUPLINGS)}, got {coupling!r}")
    vehicle = aerosonde(nseg=wake.nseg, tailplane=wake.tailplane)
    return lift_matched_vehicle(vehicle, AEROSONDE) if coupling == "load_weighted" else vehicle


def wake_model_for(wake: WakeConfig, n_vehicles: int, coupling: str | None = None,
                   sheet: bool | None = None) -> WakeModel | None:
    """The joint ELL model of ``n_vehicles`` Aerosondes as ``wake`` configures it (None: wake off or one UAV);
    ``coupling`` as :func:`wake_vehicle`'s; with ``wake.span_correction`` its ``saving_scale`` is the vehicle's
    :func:`~formation_env.wake.converged.span_efficiency_scale`; ``sheet`` None: :func:`resolve_sheet` of ``wake``."""
    if not wake.enabled or n_vehicles < 2:
        return None
    if coupling is not None:
        wake = dataclasses.replace(wake, coupling=coupling)
    wake = resolve_wake(wake)  # the Nones as the thesis's lattice sets them
    vehicle = wake_vehicle(wake, coupling)
    scale = 1.0
    if wake.span_correction:
        from ..wake.converged import span_efficiency_scale

        scale = span_efficiency_scale(vehicle)
    residual = None
    if wake.residual_table:
        from ..wake.residual import load_table

        residual = load_table()
    return WakeModel([vehicle] * n_vehicles, core=wake.core, eval_points=wake.eval_points, rotational=wake.rotational,
                     viscous_aic=wake.viscous_aic, saving_scale=scale,
                     sheet=bool(wake.sheet) if sheet is None else bool(sheet), residual=residual)
