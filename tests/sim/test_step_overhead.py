"""The decision's Python-side shortcuts (issue 26, single env): each must give exactly what the general path
gives. The packed structs and the compiled entry point resolved once per Simulation
(formation_env.sim.dispatch.EntryPoints) against numba's dispatcher; the infos' compiled separations against
separation_each; the adapters' fast action check against the general one."""

import numpy as np
import pytest

import formation_env
import formation_env.sim.step as step_mod
from formation_env.envs.parallel import check_action
from formation_env.sim import EnvConfig, Randomisation, Simulation
from formation_env.sim.dispatch import EntryPoints, StepStructs, pack_structs
from formation_env.sim.infos import separation_each

DECIDE = step_mod.decide_packed


def _sim():
    cfg = EnvConfig(scenario="echelon3", action_mode="setpoints", learning="followers",
                    randomisation=Randomisation(turbulence_sigma_mps=1.0))
    return Simulation(cfg, batch_size=2)


def _step_three(a, b, c, act):
    """a through the resolved entry point with the first thread's packed structs, c with the last thread's
    (structs of their own), b through numba's dispatcher on structs packed anew: bit for bit the same."""
    for sim in (a, b, c):
        sim._actions[:, sim.agent_mask] = act
    kernel, args = step_mod.ENTRY_POINTS.get(DECIDE, a.params, a.state, a.output, (a._actions,), 2)
    assert kernel is not DECIDE and args[0][1] is a._actions
    kernel(*args[0], 0, 2)
    kernel, args = step_mod.ENTRY_POINTS.get(DECIDE, c.params, c.state, c.output, (c._actions,), 2)
    kernel(*args[-1], 0, 2)
    DECIDE(pack_structs(b.params, b.state, b.output), b._actions, 0, 2)
    for other in (b, c):
        for name in ("observation", "reward", "terminated", "truncated", "separation_m", "slot_error_m"):
            assert np.array_equal(getattr(a.output, name), getattr(other.output, name)), name
        assert np.array_equal(a.state.aircraft, other.state.aircraft)


def test_entry_points_step_bit_for_bit_as_the_dispatcher():
    a, b, c = _sim(), _sim(), _sim()
    for sim in (a, b, c):
        sim.reset(seeds=[11, 12])
    rng = np.random.default_rng(3)
    for _ in range(6):
        _step_three(a, b, c, rng.uniform(-1, 1, size=(2, a.n_agents, 4)))
    kernel, args = step_mod.ENTRY_POINTS.get(DECIDE, a.params, a.state, a.output, (a._actions,), 2)
    assert isinstance(args[0][0], StepStructs)
    again = step_mod.ENTRY_POINTS.get(DECIDE, a.params, a.state, a.output, (a._actions,), 2)
    assert again[0] is kernel and again[1][0][0] is args[0][0]  # packed and resolved once
    two = step_mod.ENTRY_POINTS.structs(a.params, a.state, a.output, 2)
    assert len(two) >= 2 and two[0] is not two[1] and two[0] is args[0][0]  # a thread's structs are its own
    # the packed structs share the Simulation's arrays: what Python writes afterwards (a reset of one formation,
    # the state written in place) is what the packed step reads, and what it writes is what Python reads
    for sim in (a, b, c):
        sim.reset(indices=[1], seeds=[99])
    for _ in range(4):
        _step_three(a, b, c, rng.uniform(-1, 1, size=(2, a.n_agents, 4)))
    assert step_mod.ENTRY_POINTS.get(DECIDE, a.params, a.state, a.output, (a._actions,), 2)[1][0][0] is args[0][0]
    # Simulation.step itself (serial or threaded, whichever this machine's settings give) agrees too, and so does
    # step() given actions of another layout (converted to the kernel's one array type)
    d = _sim()
    d.reset(seeds=[11, 12])
    e = _sim()
    e.reset(seeds=[11, 12])
    for _ in range(3):
        act = rng.uniform(-1, 1, size=(2, d.n_agents, 4))
        d.step(act)
        e._actions[:, e.agent_mask] = act
        step_mod.step(e.params, e.state, np.asfortranarray(e._actions), e.output)
        assert np.array_equal(d.state.aircraft, e.state.aircraft) and np.array_equal(d.output.reward, e.output.reward)


def test_entry_point_cache_is_bounded_and_checks_identity():
    cache = EntryPoints()
    sims = [_sim() for _ in range(cache.SIZE + 2)]
    for s in sims:
        s.reset(seeds=[1, 2])
        cache.get(DECIDE, s.params, s.state, s.output, (s._actions,), 2)
    assert len(cache.cache) == cache.SIZE
    s = sims[-1]
    key = (id(s.params), id(s.state), id(s.output))
    packs, params, state, out, entries = cache.cache[key]
    assert params is s.params and state is s.state and out is s.output
    entry, args = cache.get(DECIDE, s.params, s.state, s.output, (s._actions,), 1)
    assert entry is entries[DECIDE] and args == [(packs[0], s._actions)]
    # an object at a cached id but not the cached object (as after garbage collection) is packed anew
    cache.cache[key] = (["stale"], object(), state, out, {})
    entry, args = cache.get(DECIDE, s.params, s.state, s.output, (s._actions,), 1)
    assert isinstance(args[0][0], StepStructs) and entry is not DECIDE


def test_info_separations_equal_separation_each_bit_for_bit():
    env = formation_env.parallel_env("vee5", action_mode="setpoints", learning="followers")
    env.reset(seed=5)
    rng = np.random.default_rng(0)
    for _ in range(8):
        acts = {a: rng.uniform(-1, 1, 4).astype(np.float32) for a in env.agents}
        _, _, _, _, infos = env.step(acts)
        x = env.sim.state.aircraft[0]
        ref = separation_each(x, env.sim.output.separation_m[0])
        got = [infos[a]["min_separation_m"] for a in env.possible_agents]
        assert [float(ref[int(a.split("_")[1])]) for a in env.possible_agents] == got
        assert all(type(v) is float for v in got)


@pytest.mark.parametrize("action", [
    np.array([0.3, -0.7, 1.5, -2.0], np.float32), np.array([-0.0, 0.0, 1.0, -1.0]),
    np.array([1e-8, 0.99999994, -3e38, 7.0], np.float32), np.array([0.1, 0.2, 0.3, 0.4], np.float16)])
def test_fast_action_check_equals_the_general_path(action):
    got = check_action("uav_1", action)
    ref = np.clip(np.asarray(action, dtype=float), -1.0, 1.0)
    assert got.dtype == np.float64 and got.shape == (4,)
    assert np.array_equal(got, ref) and np.array_equal(np.signbit(got), np.signbit(ref))


@pytest.mark.parametrize("bad", [np.array([0.0, np.nan, 0.0, 0.0], np.float32), np.array([np.inf, 0, 0, 0.0])])
def test_fast_action_check_still_rejects_non_finite(bad):
    with pytest.raises(ValueError, match="uav_1.*NaN or inf"):
        check_action("uav_1", bad)


def test_separations_if_finite_flags_any_non_finite_element():
    """The infos' one compiled call: True and min_separation_each's distances for a finite state; False for a
    NaN or inf in any element (not only the positions: the infos of such a formation are cleaned)."""
    from formation_env.sim.kernels import min_separation_each, separations_if_finite

    rng = np.random.default_rng(7)
    for _ in range(20):
        x = rng.normal(size=(int(rng.integers(2, 6)), 16)) * 10.0
        got, ref = np.empty(x.shape[0]), np.empty(x.shape[0])
        assert separations_if_finite(x, got)
        min_separation_each(x, ref)
        assert np.array_equal(got, ref)
        i, k = int(rng.integers(x.shape[0])), int(rng.integers(16))
        x[i, k] = [np.nan, np.inf, -np.inf][int(rng.integers(3))]
        assert not separations_if_finite(x, got)


def test_the_adapters_whole_dict_path_equals_the_per_agent_check():
    """Every agent acting (the whole-dict fast path of FormationParallelEnv._validate_actions): the same (A, 4)
    float64 array as check_action per agent, for float arrays of every width, lists and out-of-range values; a
    bad value among them is still the per-agent error naming the agent."""
    env = formation_env.parallel_env("formation_keeping", action_mode="setpoints", learning="all")
    env.reset(seed=1)
    rng = np.random.default_rng(2)
    for dtype in (np.float16, np.float32, np.float64, list):
        acts = {a: rng.uniform(-1.5, 1.5, 4) for a in env.possible_agents}
        acts = {a: (v.tolist() if dtype is list else v.astype(dtype)) for a, v in acts.items()}
        got = env._validate_actions(acts)
        ref = np.stack([check_action(a, acts[a]) for a in env.possible_agents])
        assert got.dtype == np.float64 and np.array_equal(got, ref)
    acts["uav_1"] = np.array([0.0, np.nan, 0.0, 0.0])
    with pytest.raises(ValueError, match="uav_1.*NaN or inf"):
        env._validate_actions(acts)
