"""Closed-loop modes of the Appendix A FCS against Tables A.11/A.12 (issue 4: within 15 %)."""

import json

import numpy as np
import pytest

from formation_env.control import FCSStructure
from formation_env.control.closed_loop import THESIS_A11, THESIS_A12, closed_loop_table
from formation_env.aircraft import trim
from formation_env.cli import main


@pytest.fixture(scope="module")
def table():
    return closed_loop_table(trim())


def test_longitudinal_modes_table_a11(table):
    lon = table["longitudinal"]
    assert len(lon) == len(THESIS_A11)
    for name, e in lon.items():
        assert e["relative_error"] <= 0.02, (name, e)  # A.11 reproduces within 2 %
    # the thesis's damping statements: SPPO 0.579, phugoid 0.588
    assert lon["short_period"]["damping"] == pytest.approx(0.579, abs=0.01)
    assert lon["phugoid"]["damping"] == pytest.approx(0.588, abs=0.01)


def test_lateral_modes_table_a12(table):
    lat = table["lateral"]
    assert len(lat) == len(THESIS_A12)
    for name, e in lat.items():
        assert e["relative_error"] <= 0.15, (name, e)
    assert table["worst_relative_error"] < 0.08  # measured 7.6 % (Dutch roll)
    # thesis: Dutch-roll damping 0.800, roll time constant 0.0617 s, every pole stable
    assert lat["dutch_roll"]["damping"] == pytest.approx(0.80, abs=0.06)
    assert lat["roll_subsidence"]["time_constant"] == pytest.approx(0.0617, rel=0.05)
    assert all(e["computed"][0] < 0 for g in ("longitudinal", "lateral") for e in table[g].values())
    assert table["ok"]


@pytest.mark.parametrize("structure", [FCSStructure(interlink_path="direct"),
                                       FCSStructure(washout="pole"),
                                       FCSStructure(interlink_source="total", interlink_path="direct")])
def test_other_structures_miss_table_a12(structure):
    """The alternatives the thesis text allows are >15 % off somewhere: the chosen structure is
    what the table discriminates, not a free pass."""
    t = closed_loop_table(trim(), structure)
    assert t["worst_relative_error"] > 0.15
    assert not t["ok"]


def test_cli_modes_closed_loop_json(capsys):
    assert main(["modes", "--closed-loop", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["source"] == "closed_loop"
    sp = out["longitudinal"]["short_period"]
    assert np.hypot(sp["real"] + 8.04, sp["imag"] - 11.3) < 0.15 * np.hypot(8.04, 11.3)
    assert out["structure"]["interlink_path"] == "yaw_damper"


def test_verify_section_modes_closed(capsys):
    assert main(["verify", "--section", "modes_closed", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)["modes_closed"]
    assert out["ok"] and set(out["lateral"]) >= {"dutch_roll", "roll_subsidence", "spiral"}
