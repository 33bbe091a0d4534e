"""The environment benchmark's cases and table (speed is reported by `formation-env bench`, never asserted)."""

from pathlib import Path

import numpy as np

from formation_env.envs import bench
from formation_env.envs.bench_cases import run_case


def test_bench_cases_measure_through_the_public_api():
    single = run_case({"kind": "single", "mode": "setpoints", "learning": "followers"}, budget_s=0.005, repeats=1)
    vector = run_case({"kind": "vector", "formations": 3, "mode": "setpoints", "learning": "followers",
                       "benefit": True}, budget_s=0.0005, repeats=1)
    assert single["physics_steps_per_s"] > 0 and np.isclose(single["uav_physics_steps_per_s"],
                                                             2 * single["physics_steps_per_s"])
    assert vector["uav_physics_steps_per_s"] > 0 and vector["formations"] == 3 and vector["benefit"]


def test_table_lists_every_case_and_ratio():
    res = {"configurations": {"threads=2": {"single surfaces learning=all": {"new": 20000.0, "old": 8000.0, "ratio": 2.5}},
                              "threads=1 busy": {"single surfaces learning=all": {"new": 15000.0}}}}
    table = bench.format_table(res)
    assert "| single surfaces learning=all | 20,000 (2.5x) | 15,000 |" in table
    assert table.splitlines()[0].count("|") == 4


def test_turbulence_cases_run_and_an_unknown_option_is_reported_not_raised():
    """The turbulence cost cases build the field they name; a case the code under test cannot build (an older
    checkout without the option) comes back marked unsupported, so a --baseline run still compares the rest."""
    turb = run_case({"kind": "vector", "formations": 2, "mode": "setpoints", "learning": "followers",
                     "turbulence": "von_karman"}, budget_s=0.0005, repeats=1)
    assert turb["uav_physics_steps_per_s"] > 0 and "unsupported" not in turb
    bad = run_case({"kind": "vector", "formations": 2, "mode": "setpoints", "learning": "followers",
                    "turbulence": "no_such_field"}, budget_s=0.0005, repeats=1)
    assert "turbulence_field" in bad["unsupported"]
    assert set(bench.TURBULENCE_CASES) <= {"von_karman", "dryden", "lanes", "independent"}


def test_decision_spread_is_measured_and_tabled_beside_the_machines():
    """Issue 26: each vector case times 40 consecutive decisions one by one (min <= median <= max, max/min >= 1),
    the machine case the same for a fixed numpy workload; the table shows B = 1,024's spread and the machine's."""
    from formation_env.envs import bench_cases

    vector = run_case({"kind": "vector", "formations": 2, "mode": "setpoints", "learning": "followers"},
                      budget_s=0.0005, repeats=1)
    assert vector["decision_ms_min"] <= vector["decision_ms_median"] <= vector["decision_ms_max"]
    assert np.isclose(vector["decision_max_over_min"], vector["decision_ms_max"] / vector["decision_ms_min"])
    machine = run_case({"kind": "machine", "products": 1})
    assert machine["decision_max_over_min"] >= 1.0 and machine["decision_ms_min"] > 0
    assert bench_cases.SPREAD_DECISIONS == 40
    key = "vector B=1024 setpoints learning=followers"
    res = {"configurations": {"threads=2": {key: {"new": 1.0e5, "spread": 1.42, "spread_old": 2.31}}},
           "machine_spread": {"threads=2": {"new": {"decision_max_over_min": 1.27}}}}
    table = bench.format_table(res)
    assert f"| {key}: max/min of 40 decisions | 1.42 (old 2.31) |" in table
    assert "| the machine: max/min of 40 runs of a fixed numpy workload | 1.27 |" in table


def test_formation_size_cases_count_every_uav_and_table_their_scaling():
    """Issues 25/26: a vector case of a vee of 5 counts 5 UAVs per formation physics step and 4 follower rows; the
    table divides its UAV physics steps/s by the 2-UAV case's at the same B."""
    vee = run_case({"kind": "vector", "formations": 2, "mode": "setpoints", "learning": "followers",
                    "scenario": "vee5"}, budget_s=0.0005, repeats=1)
    assert vee["uavs"] == 5 and np.isclose(vee["uav_physics_steps_per_s"], 5 * vee["formation_physics_steps_per_s"])
    # 4 follower rows per formation, 5 physics steps per decision
    assert np.isclose(vee["agent_decisions_per_s"], 4 * vee["formation_physics_steps_per_s"] / 5)
    assert set(bench.FORMATION_SIZE_CASES) == {"close_formation", "echelon3", "vee5", "vee9"}
    two = "vector B=256 setpoints learning=followers"
    head = (f"| {two} vee5: UAV physics steps/s over 2 UAVs' (formation_keeping; in brackets over close_formation's, "
            "the same wake), follower decisions/s |")
    res = {"configurations": {"threads=2": {
        two: {"new": 1.0e5, "uavs": 2, "agent_decisions_per_s": 1.0e4},
        two + " vee5": {"new": 4.0e4, "uavs": 5, "agent_decisions_per_s": 3.2e3}}}}
    assert f"{head} 0.40x, 3,200 decisions/s |" in bench.format_table(res)
    # with the same-wake 2-UAV case (close_formation: 2 UAVs, not a line of its own) the ratio to it too
    res["configurations"]["threads=2"][two + " close_formation"] = {"new": 8.0e4, "uavs": 2, "agent_decisions_per_s": 8e3}
    table = bench.format_table(res)
    assert f"{head} 0.40x (0.50x close_formation's), 3,200 decisions/s |" in table
    assert "close_formation: UAV physics steps/s over" not in table


def _fake_peers(monkeypatch):
    """Stand-ins with the peers' APIs (vmas.make_env; PyFlyt.pz_envs.MAFixedwingDogfightEnvV2) counting the steps."""
    import sys
    import types

    import torch

    calls = {"vmas": 0, "pyflyt": 0}

    class VmasEnv:
        agents = [types.SimpleNamespace(u_range=1.0) for _ in range(4)]

        def reset(self):
            return None

        def step(self, actions):
            assert len(actions) == 4 and tuple(actions[0].shape) == (1024, 2)
            calls["vmas"] += 1

    class Dogfight:
        possible_agents = ["uav_0", "uav_1"]

        def __init__(self, team_size, agent_hz):
            assert team_size == 1 and agent_hz == 30
            self.agents = list(self.possible_agents)

        def action_space(self, agent):
            return types.SimpleNamespace(low=-np.ones(4), high=np.ones(4))

        def reset(self, seed=None):
            self.agents = list(self.possible_agents)

        def step(self, actions):
            assert set(actions) == set(self.agents)
            calls["pyflyt"] += 1
            return {}, {}, {a: False for a in self.agents}, {a: False for a in self.agents}, {}

        def close(self):
            pass

    vmas = types.SimpleNamespace(make_env=lambda scenario, **kw: VmasEnv())
    pyflyt = types.ModuleType("PyFlyt")
    pz_envs = types.ModuleType("PyFlyt.pz_envs")
    pz_envs.MAFixedwingDogfightEnvV2 = Dogfight
    monkeypatch.setitem(sys.modules, "vmas", vmas)
    monkeypatch.setitem(sys.modules, "PyFlyt", pyflyt)
    monkeypatch.setitem(sys.modules, "PyFlyt.pz_envs", pz_envs)
    monkeypatch.setattr(torch, "set_num_threads", lambda n: None)
    return calls


def test_peers_are_timed_through_their_own_apis(monkeypatch):
    from formation_env.envs import bench_peers

    calls = _fake_peers(monkeypatch)
    rows = bench_peers.measure(budget_s=0.01, repeats=2, threads=1)
    vm, pf = rows
    assert vm["peer"] == "VMAS flocking" and "unsupported" not in vm and calls["vmas"] > 5
    assert np.isclose(vm["env_steps_per_s"], 1024 * vm["batch_steps_per_s"])
    assert np.isclose(vm["agent_steps_per_s"], 4 * vm["env_steps_per_s"])
    assert pf["peer"] == "PyFlyt fixed-wing dogfight" and pf["aircraft"] == 2 and pf["joint_steps_per_s"] > 0
    assert calls["pyflyt"] > 5
    text = bench.format_peers({"python": "py", "threads=2": rows, "threads=1": rows})
    assert "VMAS flocking" in text and "env-steps/s" in text and "joint steps/s" in text


def test_peers_not_installed_are_reported_not_raised():
    """This interpreter has neither peer (the dev install does not pull them): each row says so, in a real
    subprocess run of the script, as `formation-env bench --peers` would."""
    out = bench.run_peers(quick=True)
    for conf in ("threads=2", "threads=1"):
        rows = out[conf]
        assert [r["peer"] for r in rows] == ["VMAS flocking", "PyFlyt fixed-wing dogfight"]
        for r in rows:
            importable = __import__("importlib").util.find_spec("vmas" if "VMAS" in r["peer"] else "PyFlyt")
            assert ("unsupported" in r) == (importable is None)
    assert "not installed" in bench.format_peers(out)


def test_a_baseline_is_named_by_its_commit_on_the_performance_page(tmp_path):
    import subprocess

    from formation_env.envs.bench import baseline_commit
    from train.publish.results_page import performance_markdown

    root = Path(__file__).resolve().parents[2]
    head = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
    assert baseline_commit(str(root)) == (head.stdout.strip() if head.returncode == 0 else None)
    assert baseline_commit(str(tmp_path)) is None and baseline_commit(None) is None
    bench = {"machine": {"cpus": 2, "python": "3.11", "platform": "x"},
             "envs": {"case": "c", "baseline": "/somewhere", "baseline_commit": "abc1234", "configurations": {
                 "threads=2": {"single setpoints learning=all": {"new": 100.0, "old": 50.0, "ratio": 2.0}}}}}
    assert "code of commit abc1234 (`--baseline`)" in performance_markdown(bench)
    bench["envs"]["baseline"] = None
    assert "--baseline`)," not in performance_markdown(bench)
