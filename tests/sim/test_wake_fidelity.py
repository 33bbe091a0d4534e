"""The wake fidelity (issue 23 part 7): the energy tasks fly the converged wake (sheet law, span correction and the
residual table of pairs) by default, every other scenario the thesis's lattice; EnvConfig, the WakeConfig and the
evaluation CLI choose another, and a choice the residual table was not built for is one clear error."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from formation_env.sim.config import EnvConfig
from formation_env.scenarios import get_scenario
from formation_env.sim.formation import WAKE_FIDELITIES, WakeConfig, resolve_fidelity, resolve_wake, wake_model_for
from formation_env.sim.simulation import Simulation

ENERGY = ("close_formation", "echelon3", "vee5", "vee9", "vee_rotation", "wake_surfing", "wake_surfing_random_leader")


def test_the_energy_tasks_fly_the_converged_wake_and_the_rest_the_lattice():
    assert WAKE_FIDELITIES == ("lattice", "sheet", "converged")
    for name in ENERGY:
        assert get_scenario(name).wake_fidelity == "converged", name
        w = resolve_wake(WakeConfig(), scenario=get_scenario(name))
        assert (w.sheet, w.span_correction, w.residual_table, w.coupling) == (True, True, True, "load_weighted")
    # the thesis scenarios the thesis's
    for name in ("formation_keeping", "reconfiguration"):
        w = resolve_wake(WakeConfig(), scenario=get_scenario(name))
        assert get_scenario(name).wake_fidelity == "lattice"
        assert (w.sheet, w.span_correction, w.residual_table) == (False, False, False), name


def test_precedence_envconfig_over_scenario_and_explicit_wakeconfig_over_both():
    cf = get_scenario("close_formation")
    assert resolve_fidelity(EnvConfig(scenario="close_formation"), cf) == "converged"
    lat = EnvConfig(scenario="close_formation", wake_fidelity="lattice")
    assert resolve_fidelity(lat, cf) == "lattice"
    w = resolve_wake(WakeConfig(), lat, cf)
    assert (w.sheet, w.span_correction, w.residual_table) == (False, False, False)
    w = resolve_wake(WakeConfig(span_correction=True), EnvConfig(scenario="formation_keeping", wake_fidelity="sheet"),
                     get_scenario("formation_keeping"))
    assert (w.sheet, w.span_correction, w.residual_table) == (True, True, False)
    w = resolve_wake(WakeConfig(residual_table=False), scenario=cf)  # the table off, the rest converged
    assert (w.sheet, w.span_correction, w.residual_table) == (True, True, False)


def test_the_simulation_builds_the_resolved_model():
    """close_formation's Simulation carries the residual table, the sheet law and the span correction; the same
    task flown at the lattice fidelity carries none, and its follower's saving at the slot differs by what the
    converged map says the lattice gets wrong there."""
    conv = Simulation(EnvConfig(scenario="close_formation", compute_benefit=True), batch_size=1)
    lat = Simulation(EnvConfig(scenario="close_formation", compute_benefit=True, wake_fidelity="lattice"), batch_size=1)
    assert conv.wake_fidelity == "converged" and lat.wake_fidelity == "lattice"
    assert conv.wake_model.residual is not None and conv.wake_model.sheet and conv.wake_model.saving_scale != 1.0
    assert lat.wake_model.residual is None and not lat.wake_model.sheet and lat.wake_model.saving_scale == 1.0
    conv.reset(seeds=[3])
    lat.reset(seeds=[3])
    a = conv.step().info.induced_drag_saving[0, 1]
    b = lat.step().info.induced_drag_saving[0, 1]
    assert 0.5 < a < 0.6  # the converged slot's 0.560 (the follower starts on it, calm air)
    assert abs(a - b) > 0.05  # on the wake plane the lattice reads its legs' ripple, not the converged saving


def test_bad_fidelities_are_one_clear_error():
    with pytest.raises(ValueError, match="wake_fidelity must be None .* got 'fine'"):
        EnvConfig(wake_fidelity="fine")
    with pytest.raises(ValueError, match="Scenario.wake_fidelity must be one of"):
        dataclasses.replace(get_scenario("close_formation"), wake_fidelity=True)
    # the residual table is the lift-matched wing's under the load-weighted coupling, at nseg 10 without tailplane
    with pytest.raises(ValueError, match="wake fidelity 'converged'.*load_weighted coupling.*'sheet' or 'lattice'"):
        Simulation(EnvConfig(scenario="close_formation", wake_coupling="effective_wind"), batch_size=1)
    with pytest.raises(ValueError, match="nseg=10"):
        resolve_wake(WakeConfig(nseg=20), scenario=get_scenario("close_formation"))
    assert wake_model_for(WakeConfig(nseg=20), 2).residual is None  # no scenario: the lattice
