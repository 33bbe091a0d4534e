"""One reader of the infos: ``Simulation.info`` (InfoArrays) is the source; the per-UAV dicts of
``Simulation.infos(i)``, a formation's view (``info.formation(i)``) and the simulation's state properties read
the same values."""

import numpy as np

from formation_env.sim import EnvConfig, Randomisation, Simulation
from formation_env.sim.infos import INFO_REWARD_KEYS
from formation_env.sim.observe import REWARD_TERMS


def _flown(batch=3, steps=3):
    cfg = EnvConfig(scenario="formation_keeping", action_mode="setpoints", compute_benefit=True, duration_s=2.0,
                    randomisation=Randomisation(initial_offset_m=1.0, turbulence_sigma_mps=1.0))
    sim = Simulation(cfg, batch_size=batch)
    sim.reset(seeds=list(range(batch)))
    rng = np.random.default_rng(0)
    for _ in range(steps):
        sim.step(rng.uniform(-0.3, 0.3, (batch, sim.n_agents, 4)))
    return sim


def test_infos_dicts_are_the_info_arrays_of_each_formation():
    sim = _flown()
    info = sim.info
    for i in range(sim.batch_size):
        view = info.formation(i)
        dicts = sim.infos(i)
        assert len(dicts) == sim.n_vehicles
        for v, d in enumerate(dicts):
            assert d["time_s"] == float(info.time_s[i]) and type(d["time_s"]) is float
            assert d["collision"] is bool(info.collision[i])
            for key in ("slot_error_m", "min_separation_m", "fuel_kg", "status", "crashed", "box_depth_m",
                        "induced_drag_saving"):
                assert d[key] == getattr(info, key)[i, v], key
                assert d[key] == getattr(view, key)[v], key
            for key in ("slot_error_ned_m", "induced_wind_ned_mps", "induced_omega_body_rad_s", "gust_ned_mps",
                        "gust_omega_body_rad_s", "command"):
                assert np.array_equal(d[key], getattr(info, key)[i, v]), key
                assert not np.shares_memory(d[key], getattr(info, key)), key  # copies, never the state
            for j, term in enumerate(REWARD_TERMS):
                assert d[INFO_REWARD_KEYS[j]] == info.reward_terms[i, v, j], term
            assert d[INFO_REWARD_KEYS[-1]] == info.reward[i, v]


def test_simulation_properties_are_views_of_the_info_arrays():
    sim = _flown(batch=2, steps=1)
    assert sim.induced is sim.info.induced_wind_ned_mps is sim.state.induced_wind_ned
    assert sim.omega is sim.info.induced_omega_body_rad_s
    assert sim.commands is sim.info.command
    assert sim.velocity_demand is sim.info.velocity_demand_ned_mps
    np.testing.assert_array_equal(sim.time_s, sim.info.time_s)
    np.testing.assert_array_equal(sim.info.formation(1).slot_error_track_m, sim.info.slot_error_track_m[1])
    np.testing.assert_array_equal(sim.info.formation(0).energy_account, sim.info.energy_account[0])
    terms = sim.reward_terms(1)
    np.testing.assert_array_equal(terms["total"], sim.info.reward[1])
