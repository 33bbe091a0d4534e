"""The environment benchmark's cases and table (speed is reported by `formation-env bench`, never asserted)."""

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
