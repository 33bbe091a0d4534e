"""``EnvConfig.throttle_max``: the flight control's throttle ceiling, the counterfactual engine of issue 24's thrust
ceiling (docs/close_formation.md, "Ceilings"). At 1 (the default) the Aerosonde's full throttle; above it the FCS may
command more and the extrapolated engine map gives more thrust."""

import numpy as np
import pytest

from formation_env.sim.config import EnvConfig
from formation_env.sim import Simulation


def _fly_full_speed_demand(throttle_max: float, seconds: float = 6.0):
    """The follower of close_formation (calm air) asked for the most speed the set-points give (+2 m/s and the
    along-track offset 5 m ahead) for ``seconds``: (largest throttle command, follower's ground-speed gain m/s)."""
    cfg = EnvConfig(scenario="close_formation", learning="followers", action_mode="setpoints", throttle_max=throttle_max)
    sim = Simulation(cfg, batch_size=1)
    sim.reset(None, [3])
    v0 = np.linalg.norm(sim.velocity_ned()[0, 1])
    act = np.array([[[1.0, 0.0, 0.0, 1.0]]])
    top = 0.0
    for _ in range(int(seconds * cfg.control_hz)):
        out = sim.step(act)
        assert not (out.terminated[0] or out.truncated[0])
        top = max(top, float(sim.commands[0, 1, 3]))
    assert np.isfinite(sim.state.aircraft).all()
    return top, float(np.linalg.norm(sim.velocity_ned()[0, 1]) - v0)


def test_the_default_ceiling_is_full_throttle_and_a_higher_one_adds_thrust():
    assert EnvConfig().throttle_max == 1.0
    top1, gain1 = _fly_full_speed_demand(1.0)
    top15, gain15 = _fly_full_speed_demand(1.5)
    assert top1 == pytest.approx(1.0, abs=1e-12)  # the demand saturates the real engine ...
    assert 1.2 < top15 <= 1.5  # ... and the counterfactual one goes past it
    assert gain15 > gain1 + 0.2  # more thrust, more speed in the same time (m/s)


def test_the_ceiling_reaches_the_simulation_and_is_checked():
    sim = Simulation(EnvConfig(scenario="close_formation", learning="followers", throttle_max=1.3), batch_size=1)
    assert sim.throttle_limits == (0.0, 1.3)
    with pytest.raises(ValueError, match=r"throttle_max must be in \[0.8, 2\]"):
        EnvConfig(throttle_max=2.5)
