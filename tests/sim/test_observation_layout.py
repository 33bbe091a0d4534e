"""The observation layout (formation_env.sim.layout): one declaration of the groups, the sizes the compiled kernel
writes, slicing, the sidecar form and the layout of sidecars written before it was recorded."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from formation_env.sim.layout import GROUPS, OPTIONS, ObservationLayout

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("scenario, n_vehicles", [("tracking", 1), ("formation_keeping", 2), ("echelon3", 3),
                                                  ("vee5", 5)])
@pytest.mark.parametrize("neighbour_count", [None, 1, 2])
def test_the_declaration_gives_the_sizes_the_kernel_fills(scenario, n_vehicles, neighbour_count):
    """Every switch combination: the compiled observation fills exactly the declared length (an output prefilled
    with NaN has none left after a reset; the values are the oracle's, tests/tasks/test_n_uav_formations.py)."""
    from formation_env.sim import EnvConfig, Simulation

    for bits in range(2 ** len(OPTIONS)):
        switches = {o: bool(bits >> i & 1) for i, o in enumerate(OPTIONS)}
        layout = ObservationLayout.of(n_vehicles, neighbour_count, switches)
        assert layout.options == {o: True for o, on in switches.items() if on}
        assert layout.switches() == switches
        if n_vehicles == 1 and (neighbour_count or any(switches.values())):
            continue  # one UAV has no neighbours to observe
        sim = Simulation(EnvConfig(scenario=scenario, neighbour_count=neighbour_count, **switches), batch_size=1)
        if neighbour_count is not None:  # None: the scenario's own count (vee5's 2 nearest)
            assert sim.observation_layout == layout
        layout = sim.observation_layout
        assert layout.switches() == switches and sim.obs_size == layout.size
        sim.output.observation[:] = np.nan
        obs = sim.reset(seeds=[0]).observation
        assert obs.shape == (1, n_vehicles, layout.size) and np.isfinite(obs).all()


def test_a_simulation_owns_the_layout_of_its_observations():
    from formation_env.sim import EnvConfig, Simulation

    sim = Simulation(EnvConfig(scenario="echelon3", neighbour_attitude=True), batch_size=1)
    layout = sim.observation_layout
    assert layout == ObservationLayout(2, ("neighbour_attitude",)) == ObservationLayout.for_config(sim.config)
    out = sim.reset(seeds=[0])
    assert out.observation.shape[-1] == layout.size == sim.obs_size == 47 + 9 * 2
    groups = layout.split(out.observation[0, 1])
    assert list(groups) == list(layout.groups) and groups["neighbour_attitude"].shape == (6,)
    np.testing.assert_array_equal(out.observation[0, 1, layout.slice("ambient_wind")], groups["ambient_wind"])


def test_slices_tile_the_observation_in_declaration_order():
    layout = ObservationLayout(3, ("neighbour_attitude", "neighbour_wind"))  # any order given, declared order kept
    assert layout.optional == ("neighbour_wind", "neighbour_attitude")
    names = [g.name for g in GROUPS]
    assert list(layout.groups) == names
    stop = 0
    for name, size in layout.groups.items():
        s = layout.slice(name)
        assert (s.start, s.stop) == (stop, stop + size)
        stop = s.stop
    assert stop == layout.size == 47 + 12 * 3
    with pytest.raises(KeyError, match="not in this layout"):
        ObservationLayout(3).slice("neighbour_wind")
    alone = ObservationLayout.of(1)  # one UAV: an empty neighbours group, left out of the split
    assert alone.groups["neighbours"] == 0 and "neighbours" not in alone.split(np.zeros(alone.size))


def test_the_sidecar_form_round_trips_and_refuses_another_declaration():
    layout = ObservationLayout.of(5, 2, neighbour_wind=True)
    data = json.loads(json.dumps(layout.to_dict()))
    assert data["neighbours"] == 2 and ["neighbour_wind", 6] in data["groups"]
    assert ObservationLayout.from_dict(data) == layout
    data["groups"][0][1] = 4
    with pytest.raises(ValueError, match="differs from this version's"):
        ObservationLayout.from_dict(data)
    with pytest.raises(ValueError, match="does not declare"):
        ObservationLayout.from_dict({"neighbours": 2, "groups": [["sonar", 3], ["air_data", 3]]})
    with pytest.raises(ValueError, match="differs from this version's"):  # a task's group, the compiled ones missing
        ObservationLayout.from_dict({"neighbours": 2, "groups": [["sonar", 3]]})
    # a task's Python groups come after the compiled ones and round-trip as its extra groups
    task_layout = ObservationLayout.of(3, 2).with_extra([("fuel_saving", 1)])
    back = ObservationLayout.from_dict(task_layout.to_dict())
    assert back == task_layout and back.extra == (("fuel_saving", 1),)
    assert back.size == ObservationLayout.of(3, 2).size + 1 == back.compiled_size + 1
    assert back.slice("fuel_saving") == slice(back.size - 1, back.size)
    assert ObservationLayout(None, (), (("fuel_saving", 1),)).fit(back.size) == back
    with pytest.raises(ValueError, match="new names"):
        ObservationLayout.of(3, 2).with_extra([("air_data", 3)])
    with pytest.raises(ValueError, match="not an optional observation group"):
        ObservationLayout(2, ("air_data",))
    with pytest.raises(TypeError, match="unknown observation switch"):
        ObservationLayout.of(3, neighbor_wind=True)


def test_a_sidecar_without_a_layout_gets_the_one_its_options_give():
    old = {"algo": "ppo", "scenario": "echelon3", "neighbour_wind": True}
    assert ObservationLayout.from_dict(None, old) == ObservationLayout(None, ("neighbour_wind",))
    assert ObservationLayout.from_dict(None, {"algo": "ppo"}) == ObservationLayout()


def test_the_committed_policies_load_with_the_plain_layout():
    """Every committed policy observes the plain groups (no optional one, no task group): a sidecar without a recorded
    layout reads as the unfixed plain layout; one with it (``observation``) as that layout, the task's own."""
    from train.evaluation.policy_loader import policy_layout, policy_metadata

    zips = sorted((REPO / "train" / "policies").glob("*.zip"))
    assert zips
    for z in zips:
        meta = policy_metadata(z)
        layout = policy_layout(meta)
        recorded = meta.get("observation")
        if recorded is None:
            assert layout == ObservationLayout(), z.name
        else:
            assert layout.optional == () and layout.extra == () and layout.to_dict() == recorded, z.name


def test_fit_finds_the_neighbours_from_the_length():
    plain, told = ObservationLayout(), ObservationLayout(optional=("neighbour_wind",))
    assert plain.fit(47 + 6 * 2) == ObservationLayout(2)
    assert told.fit(47 + 9 * 2) == ObservationLayout(2, ("neighbour_wind",))
    assert plain.fit(47 + 9 * 2) == ObservationLayout(3)  # the length alone cannot tell: the agent must be told
    with pytest.raises(ValueError, match="x.act: observation length 50 matches no formation size"):
        plain.fit(50, "x.act")
    with pytest.raises(ValueError, match=r"with neighbour_wind \(47 \+ 9 k, k >= 1\)"):
        told.fit(47)
    with pytest.raises(ValueError, match="not fixed to a formation"):
        told.size


def test_the_layout_is_plain_python_and_its_switches_are_config_options():
    """Editing the declaration recompiles nothing (no kernel depends on it); every switch is an EnvConfig option a
    hyperparameter file may set, checked like the others."""
    import dataclasses

    from formation_env import kernel_cache
    from formation_env.sim.config import EnvConfig
    from train.config import ENV_KEYS

    layout_file = REPO / "formation_env" / "sim" / "layout.py"
    assert layout_file not in kernel_cache._sources(kernel_cache.PACKAGE_DIR)
    assert "numba" not in layout_file.read_text()
    fields = {f.name for f in dataclasses.fields(EnvConfig)}
    for o in OPTIONS:
        assert o in fields and o in ENV_KEYS
        with pytest.raises(ValueError, match=f"{o} must be True or False"):
            EnvConfig(**{o: 1})


def test_the_kernel_reads_each_switch_at_its_place_in_the_declared_order():
    """The compiled observation reads an optional group's switch by its place in layout.OPTIONS (the tuple
    StepParams carries), so adding a group passes through the step's parameters and stages unchanged."""
    from formation_env.sim import EnvConfig, Simulation, observe

    assert OPTIONS.index("neighbour_wind") == observe.NEIGHBOUR_WIND_SWITCH
    assert OPTIONS.index("neighbour_attitude") == observe.NEIGHBOUR_ATTITUDE_SWITCH
    layout = ObservationLayout(2, ("neighbour_attitude",))
    assert layout.switch_flags() == tuple(o == "neighbour_attitude" for o in OPTIONS)
    sim = Simulation(EnvConfig(scenario="echelon3", neighbour_attitude=True), batch_size=1)
    assert sim.params.observation_switches == sim.observation_layout.switch_flags() == (False, True)
