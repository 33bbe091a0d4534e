"""The engine's boundary (formation_env.sim.validation): Simulation.__init__ / reset / step and the adapters refuse
bad actions, seeds, indices, batch sizes and nested options with one clear error; a formation whose episode ended
is frozen (its state, observation and done flags held, zero reward) in Simulation and in every adapter."""

import gymnasium as gym
import numpy as np
import pytest

import formation_env
from formation_env.envs import FormationVecEnv, FormationVectorEnv
from formation_env.sim import EnvConfig, Simulation
from formation_env.sim.config import Randomisation, RewardWeights
from formation_env.sim.validation import MAX_SEED, check_actions, check_batch_size
from formation_env.tasks import get_task, make_config


@pytest.fixture(scope="module")
def sim():
    s = Simulation(make_config(scenario="close_formation", duration_s=5.0), batch_size=2)
    s.reset(seeds=[0, 1])
    return s


# ------------------------------------------------------------------ actions
@pytest.mark.parametrize("value, match", [(np.nan, r"formation\(s\) \[0\] contain NaN or inf"),
                                          (np.inf, "NaN or inf"), (-np.inf, "NaN or inf")])
def test_step_refuses_non_finite_actions_naming_the_formation(sim, value, match):
    a = np.zeros((2, sim.n_agents, 4))
    a[0, -1, 2] = value
    before = sim.state.aircraft.copy()
    with pytest.raises(ValueError, match=match):
        sim.step(a)
    assert np.array_equal(sim.state.aircraft, before)  # refused before anything flew


@pytest.mark.parametrize("bad, match", [
    ("abc", "real numbers"), (np.zeros((2, 2, 3)), r"shape \(2, 2, 4\)"), (np.zeros((2, 4)), "shape"),
    (np.zeros((2, 2, 4), dtype=bool), "boolean"), (np.zeros((2, 2, 4), dtype=complex), "complex"),
    ([[["0", 0, 0, 0]] * 2, [[0, 0, 0, 0]] * 2], "real numbers"), ([[[None] * 4] * 2, [[0] * 4] * 2], "real numbers"),
    ([[[0, 0]], [[0, 0, 0, 0]]], "real numbers|shape"), (np.array([{}]), "real numbers"),
    ([[[0, True, 0, 0]] * 2] * 2, "booleans")])
def test_step_refuses_actions_that_are_not_real_numbers_of_the_shape(sim, bad, match):
    assert sim.n_agents == 2
    with pytest.raises(ValueError, match=match):
        sim.step(bad)


def test_out_of_range_actions_are_clipped_as_the_action_space_says():
    cfg = make_config(scenario="close_formation", duration_s=5.0)
    a, b = Simulation(cfg, batch_size=2), Simulation(cfg, batch_size=2)
    a.reset(seeds=[3, 4])
    b.reset(seeds=[3, 4])
    big = np.full((2, 2, 4), 1e9)
    big[1] = -7.0
    ra = a.step(big).reward.copy()
    rb = b.step(np.clip(big, -1.0, 1.0)).reward.copy()
    assert np.array_equal(ra, rb) and np.all(np.isfinite(ra)) and ra.min() > -100.0


def test_the_fast_path_returns_in_range_floats_as_they_are():
    a = np.linspace(-1.0, 1.0, 16, dtype=np.float32).reshape(2, 2, 4)
    assert check_actions(a, (2, 2, 4)) is a
    out = check_actions(a * 3, (2, 2, 4))
    assert out.dtype == np.float64 and out.min() == -1.0 and out.max() == 1.0


# ------------------------------------------------------------------ seeds, indices, sizes
@pytest.mark.parametrize("seed", [-1, 2**63, 1.5, "0", True, np.float64(2.0)])
def test_every_seed_entry_point_refuses_a_bad_seed(sim, seed):
    with pytest.raises(ValueError, match="seed"):
        sim.reset(seeds=[seed, 0])
    with pytest.raises(ValueError, match="seed"):
        FormationVecEnv(1, scenario="formation_keeping", learning="followers", seed=seed)
    venv = FormationVecEnv(1, scenario="formation_keeping", learning="followers")
    with pytest.raises(ValueError, match="seed"):
        venv.seed(seed)
    with pytest.raises(ValueError, match="seed"):
        FormationVectorEnv(1, scenario="formation_keeping", learning="followers").reset(seed=seed)
    with pytest.raises(ValueError, match="seed"):
        formation_env.parallel_env("formation_keeping").reset(seed=seed)


def test_the_largest_seeds_are_accepted(sim):
    sim.reset(seeds=[MAX_SEED, 0])
    venv = FormationVecEnv(2, scenario="formation_keeping", learning="followers")
    venv.seed(MAX_SEED - 1)  # formation 1 gets MAX_SEED
    venv.reset()
    with pytest.raises(ValueError, match=str(MAX_SEED - 1)):
        venv.seed(MAX_SEED)  # formation 1 would get MAX_SEED + 1


@pytest.mark.parametrize("indices", [[2], [-1], [0, 0], [0.5], ["a"], [[0, 1]]])
def test_reset_refuses_bad_formation_indices(sim, indices):
    with pytest.raises(ValueError, match=r"indices must be distinct integer formation indices in \[0, 1\]"):
        sim.reset(indices, seeds=[0] * len(indices))


def test_reset_with_no_index_is_a_no_op(sim):
    before = sim.state.aircraft.copy()
    sim.reset([], [])
    assert np.array_equal(sim.state.aircraft, before)


def test_a_batch_beyond_the_memory_bound_is_refused_stating_it():
    with pytest.raises(ValueError, match=r"batch_size 1,000,000,000 needs .* GiB .* at most [\d,]+ formations fit"):
        Simulation(EnvConfig(scenario="close_formation"), batch_size=10**9)
    with pytest.raises(ValueError, match=r"at most 2 formations fit in 50% of this machine's 1.0 kB memory"):
        check_batch_size(3, 256, memory_bytes=1024)
    assert check_batch_size(2, 256, memory_bytes=1024) == 2
    for bad in (0, -3, 2.0, True, "4", None):
        with pytest.raises(ValueError, match="batch_size must be an integer >= 1"):
            Simulation(EnvConfig(scenario="formation_keeping"), batch_size=bad)


# ------------------------------------------------------------------ nested option dicts
def test_nested_option_dicts_equal_their_instances():
    gym_id = get_task("close_formation").gym_id
    env = gym.make(gym_id, randomisation={"turbulence_sigma_mps": 1.0})
    assert env.unwrapped.config.randomisation == Randomisation(turbulence_sigma_mps=1.0)
    env = gym.make(gym_id, reward={"slot": 2.0})
    assert env.unwrapped.config.reward == RewardWeights(slot=2.0)
    par = formation_env.parallel_env("close_formation", randomisation={"initial_offset_m": 2.0})
    assert par.config.randomisation == Randomisation(initial_offset_m=2.0)
    assert EnvConfig(reward={"slot": 3.0}) == EnvConfig(reward=RewardWeights(slot=3.0))


@pytest.mark.parametrize("name", ["randomisation", "reward"])
def test_nested_option_dicts_are_refused_naming_the_field(name):
    gym_id = get_task("close_formation").gym_id
    with pytest.raises(TypeError, match=f"{name} has no option 'bogus'.*{name} options"):
        gym.make(gym_id, **{name: {"bogus": 1.0}})
    field = "turbulence_sigma_mps" if name == "randomisation" else "slot"
    with pytest.raises(ValueError, match=f"{field} must be"):
        gym.make(gym_id, **{name: {field: -1.0}})
    with pytest.raises(ValueError, match=f"{name} must be a"):
        formation_env.parallel_env("close_formation", **{name: 3.0})


# ------------------------------------------------------------------ after the end
def _short(batch_size=2, **kw):
    return Simulation(EnvConfig(scenario="formation_keeping", duration_s=0.2, **kw), batch_size=batch_size)


def test_a_finished_formation_is_frozen_with_zero_reward_and_its_flags_held():
    s = _short()
    s.reset(seeds=[0, 1])
    out = s.step()
    out = s.step()  # 0.2 s = 2 decisions at 10 Hz
    assert out.truncated.tolist() == [True, True]
    kept = {k: np.copy(getattr(s.state, k)) for k in ("aircraft", "step", "episode_return", "episode_decisions")}
    obs = out.observation.copy()
    for _ in range(3):
        out = s.step(np.ones((2, s.n_agents, 4)))
        assert out.truncated.tolist() == [True, True] and not out.terminated.any()
        assert np.all(out.reward == 0.0) and np.all(s.output.reward_terms == 0.0)
        assert np.array_equal(out.observation, obs)
        for k, v in kept.items():
            assert np.array_equal(getattr(s.state, k), v), k
    assert s.time_s.tolist() == [0.2, 0.2]
    s.reset([0], [5])  # a reset thaws it
    out = s.step()
    assert s.time_s.tolist() == [0.1, 0.2] and not out.truncated[0] and out.truncated[1]
    assert np.all(out.reward[1] == 0.0) and np.any(out.reward[0] != 0.0)


def test_a_frozen_formation_leaves_the_others_as_they_would_fly_alone():
    s, alone = _short(), _short(batch_size=1)
    s.reset(seeds=[0, 1])
    s.step()
    s.reset([1], [7])  # formation 1 starts a decision later
    alone.reset(seeds=[7])
    s.step()  # formation 0 ends
    alone.step()
    assert s.output.truncated.tolist() == [True, False]
    out, ref = s.step(), alone.step()  # formation 0 frozen, formation 1 ends
    assert out.truncated.tolist() == [True, True]
    assert np.array_equal(out.reward[1], ref.reward[0]) and np.array_equal(out.observation[1], ref.observation[0])
    assert np.all(out.reward[0] == 0.0)


def test_a_list_with_a_bool_among_numbers_is_refused_by_every_adapter():
    par = formation_env.parallel_env("close_formation")
    par.reset(seed=0)
    with pytest.raises(ValueError, match="uav_1.*boolean"):
        par.step({"uav_0": np.zeros(4), "uav_1": [0, True, 0, 0]})
    venv = FormationVecEnv(1, scenario="close_formation")
    venv.reset()
    with pytest.raises(ValueError, match="booleans"):
        venv.step([[0, 0, 0, 0], [0, 0, np.True_, 0]])


def test_after_the_end_in_each_adapter():
    kw = dict(duration_s=0.2)
    par = formation_env.parallel_env("formation_keeping", learning="followers", **kw)
    par.reset(seed=0)
    for _ in range(2):
        _, rew, _, trunc, _ = par.step({a: np.zeros(4) for a in par.agents})
    assert all(trunc.values()) and par.agents == []
    with pytest.raises(RuntimeError, match="finished episode; call reset"):
        par.step({"uav_1": np.zeros(4)})
    aec = formation_env.env("formation_keeping", learning="followers", **kw)
    aec.reset(seed=0)
    for agent in aec.agent_iter(max_iter=10):
        *_, term, trunc, _ = aec.last()
        aec.step(None if term or trunc else np.zeros(4))
    assert aec.agents == []
    genv = gym.make(get_task("formation_keeping").gym_id, **kw)
    genv.reset(seed=0)
    genv.step(np.zeros(4, np.float32))
    *_, trunc, _ = genv.step(np.zeros(4, np.float32))
    assert trunc
    with pytest.raises(RuntimeError, match="finished episode"):
        genv.unwrapped.step(np.zeros(4, np.float32))
    for venv_cls in (FormationVecEnv, FormationVectorEnv):
        venv = venv_cls(2, scenario="formation_keeping", learning="followers", seed=0, **kw)
        venv.reset() if venv_cls is FormationVecEnv else venv.reset(seed=0)
        step = (lambda a: venv.step(a)[:3]) if venv_cls is FormationVecEnv else (lambda a: venv.step(a)[:4:3])
        for k in range(5):  # auto-reset: every episode flies 2 decisions, none past its end
            step(np.zeros((2, 4), np.float32))
            assert venv.batch.sim.time_s.tolist() == ([0.0, 0.0] if k % 2 else [0.1, 0.1])
            assert not venv.batch.sim._any_ended
