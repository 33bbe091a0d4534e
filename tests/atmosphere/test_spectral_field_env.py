"""The spectral turbulence field in the decision step: the default model, what each UAV samples (its own
position in the one field, carried by the steady wind), the rotational gusts reaching the 6-DOF, and
the other models' names."""

import numpy as np
import pytest

from formation_env.atmosphere.spectral_field import spectral_field_sample
from formation_env.sim import EnvConfig, Simulation
from formation_env.sim.config import TURBULENCE_FIELDS, Randomisation

RND = Randomisation(turbulence_sigma_mps=1.0, steady_wind_mps=4.0, slot_offset_b=0.1)


def _sim(field="von_karman", batch=2):
    cfg = EnvConfig(scenario="formation_keeping", turbulence_field=field, randomisation=RND)
    return Simulation(cfg, batch_size=batch, agents=())


def _api_sample(sim):
    s = sim.state
    chi = np.arctan2(s.velocity_demand[:, 0, 1], s.velocity_demand[:, 0, 0])
    return spectral_field_sample(sim.params.field.modes, s.modes, s.aircraft[:, :, 10:13], s.step * sim.dt,
                                 s.steady_wind, chi, s.aircraft[:, :, 6:10])


def test_default_is_von_karman_and_every_uav_samples_the_one_field_at_its_position():
    assert EnvConfig().turbulence_field == "von_karman" and TURBULENCE_FIELDS[0] == "von_karman"
    sim = _sim()
    sim.reset(seeds=[3, 4])
    assert np.abs(sim.state.steady_wind).max() > 0.1  # the field moves with this wind
    for k in range(4):
        gust, omega = _api_sample(sim)
        np.testing.assert_array_equal(sim.state.gust_ned, gust)
        np.testing.assert_array_equal(sim.state.gust_omega_body, omega)
        assert np.abs(omega).max() > 0.0
        sim.step()


def test_rotational_gusts_reach_the_dynamics():
    """The same episode with the modes' rotational coefficients zeroed (held for the track angle, so the
    kernel keeps them) flies differently; the translational gusts are the same at the start."""
    a, b = _sim(batch=1), _sim(batch=1)
    a.reset(seeds=[5])
    b.reset(seeds=[5])
    b.state.modes.omega_coef[:] = 0.0  # coef_chi is set: the kernel does not recompute them
    b.observe()
    assert not np.abs(b.state.gust_omega_body).any() and np.abs(a.state.gust_omega_body).any()
    np.testing.assert_array_equal(a.state.gust_ned, b.state.gust_ned)
    a.step()
    b.step()
    assert not np.array_equal(a.aircraft, b.aircraft)


@pytest.mark.parametrize("field", ["lanes", "independent", "frozen"])
def test_lane_models_have_no_rotational_gusts_and_frozen_is_lanes(field):
    sim = _sim(field)
    sim.reset(seeds=[1, 2])
    sim.step()
    assert np.abs(sim.state.gust_ned).max() > 0 and not sim.state.gust_omega_body.any()
    if field == "frozen":
        lanes = _sim("lanes")
        lanes.reset(seeds=[1, 2])
        lanes.step()
        np.testing.assert_array_equal(sim.state.gust_ned, lanes.state.gust_ned)
        np.testing.assert_array_equal(sim.aircraft, lanes.aircraft)


def test_bad_turbulence_field_names_the_value_and_the_choices():
    with pytest.raises(ValueError, match=r"turbulence_field must be one of .*von_karman.*got 'mann'"):
        EnvConfig(turbulence_field="mann")
