"""The energy account of the Simulation (formation_env.sim.energy through InfoArrays) and the choice of the
wake coupling (formation_env.sim.formation.resolve_coupling): the energy tasks fly the load-weighted coupling,
the thesis scenarios the thesis's effective wind."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from formation_env.aircraft import AEROSONDE, trim
from formation_env.atmosphere.standard import standard_atmosphere
from formation_env.sim.config import EnvConfig
from formation_env.scenarios import get_scenario
from formation_env.sim import Simulation
from formation_env.sim.energy import ENERGY_COLUMNS
from formation_env.sim.formation import WakeConfig, resolve_coupling

COL = {name: k for k, name in enumerate(ENERGY_COLUMNS)}


def _sim(scenario: str, **options) -> Simulation:
    sim = Simulation(EnvConfig(scenario=scenario, learning="followers", **options), batch_size=2, agents=())
    sim.reset(seeds=[0, 1])
    return sim


def test_coupling_resolution():
    cf, fk = get_scenario("close_formation"), get_scenario("formation_keeping")
    assert cf.wake_coupling == "load_weighted" and get_scenario("wake_surfing").wake_coupling == "load_weighted"
    assert fk.wake_coupling == "effective_wind"
    for name in ("formation_keeping", "reconfiguration"):  # the thesis scenarios keep the thesis's coupling
        assert resolve_coupling(WakeConfig(), EnvConfig(scenario=name), get_scenario(name)) == "effective_wind"
    assert resolve_coupling(WakeConfig(), EnvConfig(scenario="close_formation"), cf) == "load_weighted"
    assert resolve_coupling(WakeConfig(), EnvConfig(scenario="close_formation", wake_coupling="effective_wind"),
                            cf) == "effective_wind"
    assert resolve_coupling(WakeConfig(coupling="load_weighted"), EnvConfig(wake_coupling="effective_wind"),
                            fk) == "load_weighted"
    with pytest.raises(ValueError, match="wake_coupling"):
        EnvConfig(wake_coupling="loads")
    with pytest.raises(ValueError, match="coupling"):
        WakeConfig(coupling="uniform")
    with pytest.raises(ValueError, match="wake_coupling"):
        dataclasses.replace(fk, wake_coupling="none")


def test_energy_account_at_the_close_slot():
    """At the reset (both UAVs trimmed, the follower in its slot): the 6-DOF's drag alone is the trim's
    qS CD; under the load-weighted coupling the 6-DOF applies the ELL's predicted saving (ratio 1.14 at the converged slot on
    the wake plane, 0.97 at the lattice's slot 0.1 b below it), under the thesis's effective wind 1.7x it (the ELL's
    flat wing lifts 60 N of the 103 N)."""
    tr = trim(25.0, 1000.0)
    rho = float(standard_atmosphere(1000.0)[2])
    qs_cd = tr.extras["CD"] * 0.5 * rho * 25.0 ** 2 * AEROSONDE.area
    lw = _sim("close_formation")
    # the thesis's coupling with the sheet law (the converged wake's residual table is built for the load-weighted
    # coupling's lift-matched wing, asking for both is an error, tests/sim/test_wake_fidelity.py; on the wake plane
    # the lattice reads its legs' ripple): measured 1.72x the ELL's saving
    ew = _sim("close_formation", wake_coupling="effective_wind", wake_fidelity="sheet")
    assert lw.wake_coupling == "load_weighted" and ew.wake_coupling == "effective_wind"
    a, e = lw.info.energy_account, ew.info.energy_account
    assert a.shape == (2, 2, len(ENERGY_COLUMNS)) and np.all(np.isfinite(a))
    np.testing.assert_allclose(a[:, :, COL["drag_alone_n"]], qs_cd, rtol=2e-4)
    f = a[:, 1]  # the follower
    ratio = f[:, COL["drag_saving_pct_6dof"]] / f[:, COL["drag_saving_pct_ell"]]
    assert np.all((ratio > 0.8) & (ratio < 1.25)), ratio  # the band; measured 1.14 at the converged slot (0.97 on the lattice)
    assert np.all((f[:, COL["drag_saving_pct_ell"]] > 3.0) & (f[:, COL["drag_saving_pct_ell"]] < 8.0))
    ratio_thesis = e[:, 1, COL["drag_saving_pct_6dof"]] / e[:, 1, COL["drag_saving_pct_ell"]]
    assert np.all(ratio_thesis > 1.4), ratio_thesis
    # the leader 2 spans ahead gains little; the infos' views are the account's columns
    assert np.all(np.abs(a[:, 0, COL["drag_saving_pct_6dof"]]) < 0.3)
    np.testing.assert_array_equal(lw.info.drag_saving_pct_ell, a[..., COL["drag_saving_pct_ell"]])
    np.testing.assert_array_equal(lw.info.drag_saving_pct_6dof, a[..., COL["drag_saving_pct_6dof"]])


def test_energy_account_is_zero_without_wake_and_never_nan():
    off = _sim("close_formation", wake=False)
    assert np.all(off.info.energy_account == 0.0)
    sim = _sim("close_formation")
    sim.state.aircraft[1, 1, 0] = np.nan  # formation 1 diverged: its account reads 0, formation 0's is intact
    acc = sim.info.energy_account
    assert np.all(acc[1] == 0.0) and np.all(np.isfinite(acc)) and acc[0, 1, COL["drag_saving_pct_ell"]] > 0.0
