"""The formation step composed from the package's public numpy-facing functions (envelope check,
ELL WakeModel.evaluate, the aircraft step): the readable reference the compiled
formation_env.sim.kernels.step_one is held to (formerly FormationSimulator(backend="numpy"))."""

from __future__ import annotations

import numpy as np

from formation_env.aircraft import check_envelope, step
from formation_env.aircraft.state import N_STATES
from formation_env.atmosphere.wind import WindInput
from tests.oracles.physics_simulator import StepResult


def reference_step(sim, state, controls, amb, turb) -> StepResult:
    """One step of the FormationSimulator ``sim`` (its held wake state is updated)."""
    b, v = sim.batch_size, sim.n_vehicles
    status_before = check_envelope(state.reshape(b * v, -1), WindInput(wind_ned=amb.reshape(b * v, 3)),
                                   sim.limits, sim.params).reshape(b, v)
    formation_ok = np.all(status_before == 0, axis=1)
    if sim._steps % sim.wake_config.update_every == 0:
        sim._held_wind, sim._held_omega, sim._held_gamma = sim.induced_wind(state, amb, formation_ok)
    sim._steps += 1
    wind_in = WindInput(wind_ned=amb.reshape(b * v, 3), turbulence_body=turb.reshape(b * v, 3),
                        ell_translational_ned=sim._held_wind.reshape(b * v, 3),
                        ell_rotational_body=sim._held_omega.reshape(b * v, 3))
    with np.errstate(all="ignore"):  # a diverging aircraft may overflow; it is flagged below
        new = step(state.reshape(b * v, -1), controls.reshape(b * v, -1), wind_in, sim.dt, sim.params, sim.options)
    new = new.reshape(b, v, N_STATES)
    total_wind = WindInput(wind_ned=(amb + sim._held_wind).reshape(b * v, 3), turbulence_body=turb.reshape(b * v, 3))
    status = check_envelope(new.reshape(b * v, -1), total_wind, sim.limits, sim.params).reshape(b, v)
    return StepResult(new, sim._held_wind.copy(), sim._held_omega.copy(), status, sim._held_gamma)
