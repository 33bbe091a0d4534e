"""The batched rollout (formation_env.rollout): the loop every evaluation, replay and the scenario runner fly."""

from __future__ import annotations

import numpy as np

from formation_env.rollout import Decision, FunctionPolicy, Recorder, ZeroPolicy, rollout
from formation_env.sim import EnvConfig, Randomisation, Simulation


def _config(**kw):
    return EnvConfig(scenario="formation_keeping", learning="followers", duration_s=3.0, **kw)


class _Obs(Recorder):
    def start(self, sim, out):
        self.obs = [out.observation.copy()]

    def after_step(self, sim, out, actions, alive, k):
        self.obs.append(np.where(alive[:, None, None], out.observation, np.nan))


def test_rollout_is_the_manual_loop_bit_for_bit():
    cfg = _config(action_mode="setpoints", randomisation=Randomisation(turbulence_sigma_mps=1.0, initial_offset_m=2.0))
    rng = np.random.default_rng(3)
    table = rng.uniform(-1, 1, (30, 2, 4))
    calls = []

    def act(obs):
        calls.append(obs.shape)
        return table[len(calls) - 1]

    sim = Simulation(cfg, batch_size=2)
    rec = _Obs()
    res = rollout(sim, FunctionPolicy(act), [11, 12], recorders=[rec])
    assert res.decisions.tolist() == [30, 30] and not res.terminated.any()
    assert calls[0] == (2, sim.obs_size)
    manual = Simulation(cfg, batch_size=2)
    out = manual.reset(seeds=[11, 12])
    for k in range(30):
        np.testing.assert_array_equal(rec.obs[k], out.observation)
        out = manual.step(table[k].reshape(2, 1, 4))
    np.testing.assert_array_equal(rec.obs[30], out.observation)


def test_an_episode_that_ends_early_is_recorded_as_such_and_the_others_fly_on():
    """Row 0 holds full elevator and aileron in surfaces mode and leaves the envelope (at 0.9 s); formation 1
    flies the whole episode exactly as it would alone."""
    cfg = _config(action_mode="surfaces")

    def act(obs):
        a = np.zeros((obs.shape[0], 4))
        a[0, 0] = a[0, 1] = 1.0
        return a

    sim = Simulation(cfg, batch_size=2)
    rec = _Obs()
    res = rollout(sim, FunctionPolicy(act), [5, 6], recorders=[rec])
    assert res.terminated[0] and res.crashed[0] and res.decisions[0] < 30
    assert not res.terminated[1] and res.decisions[1] == 30
    alone = Simulation(cfg, batch_size=1)
    rec1 = _Obs()
    rollout(alone, FunctionPolicy(lambda o: np.zeros((1, 4))), [6], recorders=[rec1])
    np.testing.assert_array_equal(np.stack(rec.obs)[:, 1], np.stack(rec1.obs)[:, 0])


def test_observe_gets_the_previous_decisions_saving():
    cfg = _config(action_mode="setpoints", compute_benefit=True)
    seen = []

    class Watch(ZeroPolicy):
        def observe(self, decision):
            assert isinstance(decision, Decision)
            seen.append(decision.saving.copy())

    sim = Simulation(cfg, batch_size=2)
    savings = []

    class Saving(Recorder):
        def after_step(self, sim, out, actions, alive, k):
            savings.append(out.info.induced_drag_saving[:, 1].copy())

    rollout(sim, Watch(), [1, 2], recorders=[Saving()])
    assert len(seen) == 30 and np.all(seen[0] == 0.0)
    for k in range(1, 30):
        np.testing.assert_array_equal(seen[k], savings[k - 1])
    assert np.all(np.asarray(savings) > 0.05)  # the thesis slot's follower saves induced drag
