"""Validation at the boundary (issue 22, item 8): every option typed and within a physical range, unknown reset
options a TypeError, actions checked at the step that receives them (AEC too), bounded vector envs, and
step() before reset() saying so. The docs' "Option ranges" table is the code's table."""

from __future__ import annotations

import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import formation_env
from formation_env.envs import EnvConfig, Randomisation, RewardWeights
from formation_env.sim import config as _config

OPTION_RANGES = getattr(_config, "OPTION_RANGES", {})  # (imported so; each test fails on its own without it)

DOCS = Path(__file__).resolve().parents[2] / "docs" / "environments.md"


# ---------------------------------------------------------------- options: types and ranges
@pytest.mark.parametrize("make, option, value", [
    (lambda v: EnvConfig(compute_benefit=v), "compute_benefit", "no"),
    (lambda v: EnvConfig(compute_benefit=v), "compute_benefit", 1),
    (lambda v: EnvConfig(wake=v), "wake", "yes"),
    (lambda v: EnvConfig(learning=v), "learning", {0: 1}),
    (lambda v: EnvConfig(learning=v), "learning", {1}),
    (lambda v: EnvConfig(learning=v), "learning", 1),
    (lambda v: EnvConfig(control_hz=v), "control_hz", 5e-5),
    (lambda v: EnvConfig(control_hz=v), "control_hz", 100.0),
    (lambda v: EnvConfig(control_hz=v), "control_hz", True),
    (lambda v: EnvConfig(collision_separation_b=v), "collision_separation_b", 1e9),
    (lambda v: EnvConfig(wake_update_every=v), "wake_update_every", 10**9),
    (lambda v: EnvConfig(wake_update_every=v), "wake_update_every", 2.0),
    (lambda v: EnvConfig(throttle_max=v), "throttle_max", 0.5),
    (lambda v: EnvConfig(throttle_max=v), "throttle_max", float("inf")),
    (lambda v: EnvConfig(throttle_max=v), "throttle_max", True),
    (lambda v: EnvConfig(duration_s=v), "duration_s", 1e9),
    (lambda v: EnvConfig(duration_s=v), "duration_s", 1e-4),
    (lambda v: EnvConfig(duration_s=v), "duration_s", 10**400),
    (lambda v: EnvConfig(action_mode=v), "action_mode", ["surfaces"]),
    (lambda v: RewardWeights(slot=v), "slot", 1e308),
    (lambda v: RewardWeights(box=v), "box", 1e300),
    (lambda v: RewardWeights(collision=v), "collision", 1e12),
    (lambda v: RewardWeights(slot_scale_m=v), "slot_scale_m", 1e-300),
    (lambda v: RewardWeights(box_scale_b=v), "box_scale_b", 1e-300),
    (lambda v: RewardWeights(shaping_gamma=v), "shaping_gamma", 1.5),
    (lambda v: RewardWeights(effort=v), "effort", True),
    (lambda v: Randomisation(turbulence_sigma_mps=v), "turbulence_sigma_mps", 1e6),
    (lambda v: Randomisation(steady_wind_mps=v), "steady_wind_mps", 1e4),
    (lambda v: Randomisation(crosswind_mps=v), "crosswind_mps", 1e4),
    (lambda v: Randomisation(initial_offset_m=v), "initial_offset_m", 1e6),
    (lambda v: Randomisation(slot_offset_b=v), "slot_offset_b", 1e3),
    (lambda v: Randomisation(leader_turn_deg=v), "leader_turn_deg", 1e5),
    (lambda v: Randomisation(leader_climb_m=v), "leader_climb_m", 1e6),
    (lambda v: Randomisation(leader_speed_mps=v), "leader_speed_mps", 1e3),
])
def test_nonsense_option_is_a_value_error_naming_option_value_and_range(make, option, value):
    with pytest.raises(ValueError) as exc:
        make(value)
    msg = str(exc.value)
    assert option in msg and "\n" not in msg, msg
    assert repr(value)[:20] in msg or option in ("action_mode",), msg
    if f"EnvConfig.{option}" in OPTION_RANGES or f"RewardWeights.{option}" in OPTION_RANGES \
            or f"Randomisation.{option}" in OPTION_RANGES:
        assert re.search(r"\[[-0-9.e+]+, [-0-9.e+]+\]", msg), msg  # the range


def test_every_numeric_option_is_in_the_table_and_the_defaults_inside_it():
    names = {f"{cls.__name__}.{f}" for cls in (RewardWeights, Randomisation) for f in cls.__dataclass_fields__}
    names |= {f"EnvConfig.{f}" for f in ("control_hz", "collision_separation_b", "duration_s", "wake_update_every", "throttle_max")}
    assert names == set(OPTION_RANGES)
    for cls in (RewardWeights, Randomisation):
        obj = cls()
        for f in cls.__dataclass_fields__:
            lo, hi, _, why = OPTION_RANGES[f"{cls.__name__}.{f}"]
            assert lo <= getattr(obj, f) <= hi and why


def test_boundary_values_and_numpy_scalars_are_accepted():
    for name, (lo, hi, _, _) in OPTION_RANGES.items():
        owner, field = name.split(".")
        if owner == "EnvConfig":
            continue
        cls = {"RewardWeights": RewardWeights, "Randomisation": Randomisation}[owner]
        assert getattr(cls(**{field: hi}), field) == hi
        assert getattr(cls(**{field: np.float32(lo)}), field) == pytest.approx(lo)
    assert EnvConfig(control_hz=0.5, duration_s=0.02, wake_update_every=50, collision_separation_b=2.0).control_hz == 0.5
    assert EnvConfig(control_hz=np.float64(25.0), learning=[1], compute_benefit=np.bool_(True)).learning == (1,)
    with pytest.raises(ValueError, match="divide the physics rate 50 Hz"):
        EnvConfig(control_hz=3.0)


def test_the_option_ranges_in_docs_are_the_code_table():
    text = DOCS.read_text(encoding="utf-8")
    section = text.split("## Option ranges", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| `([A-Za-z]+\.[a-z_]+)` \| ([^|]+) \| ([^|]+) \| ([^|]*) \| ([^|]+) \|$", section, re.M)
    table = {name: (float(lo), float(hi), unit.strip(), why.strip()) for name, lo, hi, unit, why in rows}
    assert table == {k: (float(lo), float(hi), unit, why) for k, (lo, hi, unit, why) in OPTION_RANGES.items()}


def test_every_config_in_the_repository_lies_inside_the_ranges():
    from formation_env.tasks import TASKS, make_config
    from train.sb3.config import ALGOS, TrainConfig, load_hyperparams
    from formation_env.scenarios import scenario_names

    for task in TASKS.values():
        make_config(scenario=task.scenario_name)
    for algo in ALGOS:
        for scenario in scenario_names():
            TrainConfig.from_hyperparams(load_hyperparams(algo, scenario), scenario=scenario, algo=algo,
                                         action_mode="setpoints", seed=0)


# ---------------------------------------------------------------- Gymnasium ids fix their scenario
def test_a_registered_id_refuses_another_scenario():
    with pytest.raises(ValueError, match=r"'formation_keeping'.*'vee'.*formation_env/Vee-v1.*parallel_env"):
        gym.make("formation_env/FormationKeeping-v1", scenario="vee")
    with pytest.raises(ValueError, match="flies scenario 'gust'"):
        gym.make("formation_env/Gust-v1", scenario="tracking")
    env = gym.make("formation_env/Vee-v1", scenario="vee", duration_s=1.0)  # its own scenario: fine
    assert env.unwrapped.config.scenario == "vee"


# ---------------------------------------------------------------- reset options
@pytest.mark.parametrize("maker", ["parallel", "gym", "aec"])
def test_unknown_reset_options_are_a_type_error_listing_the_valid_ones(maker):
    make = {"parallel": lambda: formation_env.parallel_env("formation_keeping", duration_s=1.0),
            "gym": lambda: gym.make("formation_env/FormationKeeping-v1", duration_s=1.0),
            "aec": lambda: formation_env.env("formation_keeping", duration_s=1.0)}[maker]
    for bad in ({"scenario": "vee"}, {"duration_s": 1}):
        with pytest.raises(TypeError, match=rf"{next(iter(bad))}.*steady_wind_ned"):
            make().reset(seed=0, options=bad)


def test_reset_options_reach_the_simulation():
    env = formation_env.parallel_env("formation_keeping", duration_s=1.0)
    env.reset(seed=0, options={"steady_wind_ned": [0.0, 3.0, 0.0]})
    assert env.sim.state.steady_wind[0].tolist() == [0.0, 3.0, 0.0]
    with pytest.raises(ValueError, match="steady_wind_ned"):
        env.reset(seed=0, options={"steady_wind_ned": [0.0, 1e9, 0.0]})
    genv = gym.make("formation_env/FormationKeeping-v1", duration_s=1.0)
    genv.reset(seed=0, options={"steady_wind_ned": [1.0, 0.0, 0.0]})
    assert genv.unwrapped._par.sim.state.steady_wind[0].tolist() == [1.0, 0.0, 0.0]
    env.reset(seed=0, options={"options": 1})  # PettingZoo's api tests' placeholder: accepted and ignored


# ---------------------------------------------------------------- actions
def test_bool_actions_are_rejected_everywhere():
    from formation_env.envs import FormationVecEnv, FormationVectorEnv

    env = formation_env.parallel_env("formation_keeping", duration_s=1.0)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="uav_0.*boolean"):
        env.step({a: np.ones(4, bool) for a in env.agents})
    with pytest.raises(ValueError, match="uav_1.*boolean"):
        env.step({"uav_0": np.zeros(4), "uav_1": [True, False, True, False]})
    genv = gym.make("formation_env/FormationKeeping-v1", duration_s=1.0)
    genv.reset(seed=0)
    with pytest.raises(ValueError, match="boolean"):
        genv.unwrapped.step(np.ones(4, bool))
    for venv in (FormationVecEnv(1, scenario="formation_keeping", learning="followers", duration_s=1.0),
                 FormationVectorEnv(1, scenario="formation_keeping", learning="followers", duration_s=1.0)):
        venv.reset()
        with pytest.raises(ValueError, match="boolean"):
            venv.step(np.ones((1, 4), bool))


@pytest.mark.parametrize("bad, match", [(np.full(4, np.nan, np.float32), "NaN"), (np.zeros(3, np.float32), "shape"),
                                        (np.ones(4, bool), "boolean"), ("fast", "real numbers")])
def test_the_aec_env_rejects_a_bad_action_at_the_step_that_receives_it(bad, match):
    aec = formation_env.env("formation_keeping", duration_s=1.0)
    aec.reset(seed=0)
    first = aec.agent_selection
    with pytest.raises(ValueError, match=rf"{first}.*{match}|{match}.*{first}"):
        aec.step(bad)
    assert aec.agent_selection == first  # nothing stored: the same agent acts again
    aec.step(np.zeros(4, np.float32))
    assert aec.agent_selection != first


def test_the_aec_env_still_round_trips_and_ends():
    from pettingzoo.utils.conversions import aec_to_parallel

    aec = formation_env.env("formation_keeping", duration_s=0.2)
    assert isinstance(aec_to_parallel(aec), formation_env.envs.FormationParallelEnv)
    aec.reset(seed=0)
    for agent in aec.agent_iter(20):
        *_, term, trunc, _ = aec.last()
        aec.step(None if term or trunc else np.zeros(4, np.float32))
    assert not aec.agents


# ---------------------------------------------------------------- vector envs and the order of calls
def test_n_formations_is_bounded_with_a_value_error():
    from formation_env.envs import FormationVecEnv, FormationVectorEnv

    for make in (FormationVecEnv, FormationVectorEnv):
        for bad in (10**8, 0, -1, 2.0, True):
            with pytest.raises(ValueError, match=r"n_formations must be an integer in \[1, 65536\]"):
                make(bad, scenario="formation_keeping")


def test_step_before_any_reset_says_call_reset_first():
    from formation_env.envs import FormationVecEnv, FormationVectorEnv

    env = formation_env.parallel_env("formation_keeping", duration_s=1.0)
    with pytest.raises(RuntimeError, match=r"before any reset\(\).*call reset\(\) first"):
        env.step({a: np.zeros(4) for a in env.possible_agents})
    genv = gym.make("formation_env/FormationKeeping-v1", duration_s=1.0).unwrapped
    with pytest.raises(RuntimeError, match=r"before any reset\(\)"):
        genv.step(np.zeros(4, np.float32))
    for venv in (FormationVecEnv(1, scenario="formation_keeping", learning="followers", duration_s=1.0),
                 FormationVectorEnv(1, scenario="formation_keeping", learning="followers", duration_s=1.0)):
        with pytest.raises(RuntimeError, match=r"call reset\(\) first"):
            venv.step(np.zeros((1, 4), np.float32))
    env.reset(seed=0)
    while env.agents:
        env.step({a: np.zeros(4) for a in env.agents})
    with pytest.raises(RuntimeError, match="finished episode"):  # after the end: the old message, still right
        env.step({a: np.zeros(4) for a in env.possible_agents})
