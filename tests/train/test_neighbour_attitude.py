"""The classical agents told the layout of the neighbours' attitudes (EnvConfig.neighbour_attitude); the option through
training, publication and evaluation is tested with the winds' in tests/train/test_neighbour_wind.py."""

import numpy as np
import pytest


def test_the_classical_agents_read_the_attitudes_when_told():
    """Told the layout, the guard, the station keeper and the formation PID act on the observation with the
    neighbours' attitudes (and with winds and attitudes) exactly as on the plain one."""
    import formation_env
    from agents.common import observation_groups
    from agents.pid_formation import PIDFormation
    from agents.separation_guard import GuardGains, SeparationGuard
    from agents.station_keeper import StationKeeper
    from formation_env.sim.config import Randomisation

    layouts = [(False, False), (False, True), (True, True)]
    envs = [formation_env.parallel_env("echelon3", action_mode="setpoints", neighbour_wind=w, neighbour_attitude=t,
                                       randomisation=Randomisation(turbulence_sigma_mps=1.0, initial_offset_m=4.0))
            for w, t in layouts]
    for env in envs:
        env.reset(seed=7)
    told = [env.observation_layout for env in envs]  # the env's layout: what the agents are told
    guards = [SeparationGuard(GuardGains(guard_m=30.0), layout=layout) for layout in told]
    keepers = [StationKeeper(layout=layout) for layout in told]
    pids = [PIDFormation(layout=layout) for layout in told]
    for agent in keepers + pids:
        agent.reset(3)
    rng = np.random.default_rng(3)
    shifted = 0
    for _ in range(12):
        act = {a: rng.uniform(-1, 1, 4) for a in envs[0].agents}
        obs = [np.stack([o[a] for a in sorted(o)]) for o, *_ in (env.step(act) for env in envs)]
        assert [o.shape[1] for o in obs] == [59, 65, 71]
        a = rng.uniform(-1, 1, (3, 4))
        g0 = guards[0].filter(obs[0], a)
        shifted += int(np.any(g0 != a))
        for i in (1, 2):
            np.testing.assert_array_equal(guards[i].filter(obs[i], a), g0)
        k0, p0 = keepers[0].act(obs[0]), pids[0].act(obs[0])
        for i in (1, 2):
            np.testing.assert_array_equal(keepers[i].act(obs[i]), k0)
            np.testing.assert_array_equal(pids[i].act(obs[i]), p0)
    assert shifted > 0
    with pytest.raises(ValueError, match=r"test.act: observation length 65 is not that of an observation with "
                                         r"neighbour_wind and neighbour_attitude \(47 \+ 12 k, k >= 1\)"):
        observation_groups(obs[1], "test", told[2])
