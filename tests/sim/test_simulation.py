"""The public engine formation_env.sim.Simulation: reset infos (never stale), reset options (the steady
wind), step before reset, and that a batch of formations flies each formation as a batch of one would."""

import copy
import math

import numpy as np
import pytest

import formation_env
from formation_env.control.observation import ned_to_track_frame
from formation_env.envs.observations import slog, to_dict
from formation_env.sim import EnvConfig, Randomisation, Simulation
from formation_env.sim.observe import WIND_SCALE_MPS
from formation_env.sim.params import slot_error_axes
from formation_env.sim.simulation import INFO_REWARD_KEYS, RESET_OPTIONS

STALE_RANDOM = Randomisation(initial_offset_m=3.0, slot_offset_b=0.1, turbulence_sigma_mps=1.0)


def _slot_error_definition(sim, i=0):
    """(V,) the step's slot error of formation ``i`` recomputed here: position minus demand in the slot
    frame (x along the leader's demanded track, y starboard, z down), weighted by the scenario's axes."""
    err = sim.aircraft[i, :, 10:13] - sim.position_demand[i]
    vd = sim.velocity_demand[i, 0]
    chi = math.atan2(vd[1], vd[0])
    axes = slot_error_axes(sim.scenario)
    return np.array([np.sqrt(np.sum((axes * ned_to_track_frame(e, chi)) ** 2)) for e in err])


def _assert_infos_equal(a, b):
    assert a.keys() == b.keys()
    for agent in a:
        assert a[agent].keys() == b[agent].keys(), agent
        for key, value in a[agent].items():
            other = b[agent][key]
            if isinstance(value, np.ndarray):
                assert isinstance(other, np.ndarray) and np.array_equal(value, other), (agent, key, value, other)
            else:
                assert type(value) is type(other) and value == other, (agent, key, value, other)


# ------------------------------------------------------------------ (a) reset infos are never stale
@pytest.mark.parametrize("scenario", ["formation_keeping", "wake_surfing"])
def test_reset_infos_are_the_new_episodes_not_the_last_steps(scenario):
    """Regression: the infos of a reset described the previous episode's last decision (slot_error_m
    stale at a second reset) or, at the first reset, the plain NED norm of the slot error instead of the
    step's definition (slot-frame components weighted by the scenario's axes)."""
    env = formation_env.parallel_env(scenario, action_mode="setpoints", randomisation=STALE_RANDOM)
    _, first = env.reset(seed=0)
    first = copy.deepcopy(first)
    err0 = first["uav_1"]["slot_error_m"]
    assert err0 > 0.0
    definition = _slot_error_definition(env.sim)
    assert err0 == pytest.approx(definition[1], rel=1e-12, abs=1e-12)
    if scenario == "wake_surfing":  # along-track only: the NED norm is not the slot error (not vacuous)
        assert abs(err0 - np.linalg.norm(first["uav_1"]["slot_error_ned_m"])) > 1e-3
    for agent in first:
        assert all(first[agent][k] == 0.0 for k in INFO_REWARD_KEYS), agent

    zero = {a: np.zeros(4, np.float32) for a in env.agents}
    for _ in range(30):
        _, _, _, _, infos = env.step(zero)
    # the step reports the same definition (the reset's infos measure what the step measures)
    assert infos["uav_1"]["slot_error_m"] == pytest.approx(_slot_error_definition(env.sim)[1], rel=1e-9, abs=1e-9)
    assert infos["uav_1"]["slot_error_m"] != err0
    assert any(infos[a][k] != 0.0 for a in infos for k in INFO_REWARD_KEYS)

    _, second = env.reset(seed=0)
    _assert_infos_equal(first, second)
    assert second["uav_1"]["slot_error_m"] == err0 > 0.0
    assert second["uav_1"]["slot_error_m"] == pytest.approx(_slot_error_definition(env.sim)[1], rel=1e-12, abs=1e-12)
    for agent in second:
        assert all(second[agent][k] == 0.0 for k in INFO_REWARD_KEYS), agent


# ------------------------------------------------------------------ (b) reset options: the steady wind
def _ambient_groups(sim, i=0):
    return np.stack([to_dict(sim.output.observation[i, v], sim.n_vehicles)["ambient_wind"]
                     for v in range(sim.n_vehicles)])


def _ambient_definition(sim, i=0):
    """(V, 3) the ambient-wind group from the state: the ambient wind in each UAV's slot frame (its
    demanded track), signed-log scaled."""
    wind = sim.ambient_wind()[i]
    vd = sim.velocity_demand[i]
    chi = np.arctan2(vd[:, 1], vd[:, 0])
    return slog(ned_to_track_frame(wind, chi), WIND_SCALE_MPS)


def test_steady_wind_reset_option_sets_the_state_and_the_observation():
    cfg = EnvConfig(scenario="formation_keeping", action_mode="setpoints")
    sim = Simulation(cfg)
    sim.reset(seeds=[0])
    calm = sim.output.observation.copy()
    np.testing.assert_array_equal(sim.state.steady_wind[0], [0.0, 0.0, 0.0])
    np.testing.assert_allclose(_ambient_groups(sim), 0.0, atol=1e-12)

    out = sim.reset(seeds=[0], options={"steady_wind_ned": (0, 3, 0)})
    np.testing.assert_array_equal(sim.state.steady_wind[0], [0.0, 3.0, 0.0])
    np.testing.assert_array_equal(out.info.steady_wind_ned_mps[0], [0.0, 3.0, 0.0])
    groups = _ambient_groups(sim)
    np.testing.assert_allclose(groups, _ambient_definition(sim), rtol=0, atol=1e-12)
    # the leader flies north at the start: an east wind is a starboard crosswind in every slot frame
    np.testing.assert_allclose(groups, np.tile([0.0, math.log1p(3.0), 0.0], (sim.n_vehicles, 1)), atol=1e-6)
    assert not np.array_equal(out.observation, calm)
    np.testing.assert_array_equal(out.observation, sim.output.observation)


def test_steady_wind_option_equals_writing_the_state_then_observing():
    """Bit for bit the former route (write the wind into the state arrays, then ``observe()``), at the
    reset and along the episode, with the seed's other draws (turbulence, offsets, drawn wind) unchanged."""
    rnd = Randomisation(initial_offset_m=2.0, slot_offset_b=0.1, steady_wind_mps=4.0, turbulence_sigma_mps=1.0)
    cfg = EnvConfig(scenario="formation_keeping", action_mode="setpoints", randomisation=rnd)
    wind = np.array([0.0, 3.0, 0.0])
    option, manual = Simulation(cfg), Simulation(cfg)
    option.reset(seeds=[7], options={"steady_wind_ned": (0, 3, 0)})
    manual.reset(seeds=[7])
    assert not np.array_equal(manual.state.steady_wind[0], wind)  # the drawn wind, replaced below
    manual.state.steady_wind[0] = wind
    manual.observe()
    np.testing.assert_array_equal(option.state.steady_wind, manual.state.steady_wind)
    np.testing.assert_array_equal(option.output.observation, manual.output.observation)
    np.testing.assert_array_equal(option.aircraft, manual.aircraft)
    np.testing.assert_array_equal(option.state.gust_ned, manual.state.gust_ned)
    rng = np.random.default_rng(3)
    for _ in range(10):
        a = rng.uniform(-1, 1, (1, option.n_agents, 4))
        o1, o2 = option.step(a), manual.step(a)
        np.testing.assert_array_equal(o1.observation, o2.observation)
        np.testing.assert_array_equal(o1.reward, o2.reward)
    np.testing.assert_array_equal(option.aircraft, manual.aircraft)


def test_steady_wind_option_per_formation():
    sim = Simulation(EnvConfig(scenario="formation_keeping"), batch_size=2)
    winds = np.array([[1.0, -2.0, 0.0], [0.0, 3.0, 0.5]])
    sim.reset(seeds=[0, 1], options={"steady_wind_ned": winds})
    np.testing.assert_array_equal(sim.state.steady_wind, winds)
    for i in range(2):
        np.testing.assert_allclose(_ambient_groups(sim, i), _ambient_definition(sim, i), rtol=0, atol=1e-12)
    sim.reset([1], [1], options={"steady_wind_ned": (4.0, 0.0, 0.0)})  # only the formations reset
    np.testing.assert_array_equal(sim.state.steady_wind, [[1.0, -2.0, 0.0], [4.0, 0.0, 0.0]])


def test_bad_reset_options_raise():
    sim = Simulation(EnvConfig(scenario="formation_keeping"))
    assert RESET_OPTIONS == ("steady_wind_ned",)
    with pytest.raises(TypeError, match="steady_wind"):
        sim.reset(seeds=[0], options={"steady_wind": (0, 3, 0)})
    with pytest.raises(TypeError, match="gravity"):
        sim.reset(seeds=[0], options={"steady_wind_ned": (0, 3, 0), "gravity": 9.8})
    for bad in [(0.0, np.nan, 0.0), (0.0, np.inf, 0.0), (0.0, 3.0), (0.0, 3.0, 0.0, 1.0), [[0, 3, 0], [0, 3, 0]]]:
        with pytest.raises(ValueError, match="steady_wind_ned"):
            sim.reset(seeds=[0], options={"steady_wind_ned": bad})


# ------------------------------------------------------------------ (c) step before reset
def test_step_before_reset_raises():
    sim = Simulation(EnvConfig(scenario="formation_keeping"), batch_size=2)
    with pytest.raises(RuntimeError, match="reset"):
        sim.step()
    with pytest.raises(RuntimeError, match="reset"):
        sim.step(np.zeros((2, sim.n_agents, 4)))
    sim.reset([0], [0])  # formation 1 still never reset
    with pytest.raises(RuntimeError, match="reset"):
        sim.step()
    sim.reset([1], [1])
    sim.step()
    assert sim.state.step.tolist() == [sim.substeps] * 2


# ------------------------------------------------------------------ (d) a batch flies each formation alone
def test_a_batch_equals_its_formations_flown_one_by_one():
    rnd = Randomisation(initial_offset_m=2.0, slot_offset_b=0.1, steady_wind_mps=3.0, turbulence_sigma_mps=1.0)
    cfg = EnvConfig(scenario="formation_keeping", action_mode="setpoints", randomisation=rnd)
    seeds = [4, 5, 6]
    batch = Simulation(cfg, batch_size=3)
    singles = [Simulation(cfg) for _ in seeds]
    out = batch.reset(seeds=seeds)
    for i, (one, seed) in enumerate(zip(singles, seeds)):
        o1 = one.reset(seeds=[seed])
        np.testing.assert_array_equal(out.observation[i], o1.observation[0])
        np.testing.assert_array_equal(batch.aircraft[i], one.aircraft[0])
    assert not np.array_equal(out.observation[0], out.observation[1])  # the seeds differ
    actions = np.random.default_rng(0).uniform(-1, 1, (20, 3, batch.n_agents, 4))
    for k in range(20):
        out = batch.step(actions[k])
        for i, one in enumerate(singles):
            o1 = one.step(actions[k, i:i + 1])
            np.testing.assert_array_equal(out.observation[i], o1.observation[0], err_msg=f"{k} {i}")
            np.testing.assert_array_equal(out.reward[i], o1.reward[0], err_msg=f"{k} {i}")
            assert out.terminated[i] == o1.terminated[0] and out.truncated[i] == o1.truncated[0], (k, i)
    for i, one in enumerate(singles):
        np.testing.assert_array_equal(batch.aircraft[i], one.aircraft[0])
        np.testing.assert_array_equal(batch.state.gust_ned[i], one.state.gust_ned[0])


@pytest.fixture
def one_thread():
    """The whole batch in one kernel call (serial): its first LANES formations solve their ELL as one chunk."""
    import numba

    n = numba.get_num_threads()
    numba.set_num_threads(1)
    yield
    numba.set_num_threads(n)


@pytest.mark.parametrize("scenario,mode,benefit", [("formation_keeping", "setpoints", False),
                                                   ("close_formation", "residual", True),
                                                   ("echelon3", "setpoints", False)])
def test_a_chunk_solved_across_lanes_equals_its_formations_flown_one_by_one(one_thread, scenario, mode, benefit):
    """A batch of LANES + 3 formations: the first LANES solve their ELL across the vector lanes
    (formation_env.wake.across), the other 3 (fewer than CHUNK_MIN) and every batch of one formation by formation;
    the numbers are the same bit for bit, the benefit's kept AIC included."""
    from formation_env.sim.step import CHUNK_MIN
    from formation_env.wake.across import LANES, chunk_pays

    rnd = Randomisation(initial_offset_m=2.0, slot_offset_b=0.1, steady_wind_mps=3.0, turbulence_sigma_mps=1.0)
    cfg = EnvConfig(scenario=scenario, action_mode=mode, randomisation=rnd, compute_benefit=benefit)
    n = LANES + 3
    batch = Simulation(cfg, batch_size=n)
    assert chunk_pays(batch.params.wake.lattice) and 3 < CHUNK_MIN <= LANES  # both paths are flown
    seeds = list(range(10, 10 + n))
    singles = [Simulation(cfg) for _ in seeds]
    batch.reset(seeds=seeds)
    for one, seed in zip(singles, seeds):
        one.reset(seeds=[seed])
    actions = np.random.default_rng(1).uniform(-1, 1, (12, n, batch.n_agents, 4))
    for k in range(12):
        out = batch.step(actions[k])
        for i, one in enumerate(singles):
            o1 = one.step(actions[k, i:i + 1])
            np.testing.assert_array_equal(out.observation[i], o1.observation[0], err_msg=f"{k} {i}")
            np.testing.assert_array_equal(out.reward[i], o1.reward[0], err_msg=f"{k} {i}")
            if benefit:
                assert np.any(one.output.saving[0] != 0.0)
                np.testing.assert_array_equal(batch.output.saving[i], one.output.saving[0], err_msg=f"{k} {i}")
    for i, one in enumerate(singles):
        np.testing.assert_array_equal(batch.aircraft[i], one.aircraft[0])
        np.testing.assert_array_equal(batch.state.circulation[i], one.state.circulation[0])


def test_which_lattices_solve_in_chunks():
    """Two or three Aerosondes with the field read off the solve; not five (its chunk outgrows a core's cache), nor
    a field evaluated at other points than the control points."""
    from formation_env.geometry import aerosonde
    from formation_env.wake import WakeModel
    from formation_env.wake.across import MAX_PANELS, chunk_pays
    from formation_env.wake.arrays import wake_arrays

    def pays(n, **kw):
        return chunk_pays(wake_arrays(WakeModel([aerosonde()] * n, **kw), np.zeros(3)).lattice)

    assert pays(2) and pays(3) and not pays(5)
    assert 3 * 10 <= MAX_PANELS < 5 * 10
    assert not pays(2, eval_points="quarter_chord")
