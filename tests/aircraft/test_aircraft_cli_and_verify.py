"""CLI subcommands trim/modes, the verify sections and the benchmark entry point."""

import json

import pytest

from formation_env.cli import main
from formation_env.verification import aircraft as va


def test_trim_cli_json(capsys):
    assert main(["trim", "--speed", "25", "--altitude", "1000", "--fuel", "2", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["throttle"] == pytest.approx(0.706, abs=0.005)
    assert d["alpha"] == pytest.approx(0.0564, abs=5e-4)
    assert d["omega"] == pytest.approx(545.4, abs=2)
    assert len(d["state"]) == 16 and len(d["controls"]) == 4


def test_trim_cli_text_and_error(capsys):
    assert main(["trim", "--turn-rate", "5"]) == 0
    assert "shaft speed" in capsys.readouterr().out
    assert main(["trim", "--speed", "3"]) == 2
    assert "airspeed" in capsys.readouterr().err


def test_modes_cli_json(capsys):
    assert main(["modes", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["longitudinal"]["short_period"]["real"] == pytest.approx(-4.45, rel=0.1)
    assert d["lateral"]["spiral"]["real"] == pytest.approx(0.0533, rel=0.1)
    assert main(["modes", "--alpha-dot"]) == 0
    assert "dutch_roll" in capsys.readouterr().out


def test_verify_sections_pass_and_serialise():
    assert set(va.SECTIONS) == {"trim_a5", "modes_open", "modes_closed"}
    for name, fn in va.SECTIONS.items():
        d = fn()
        json.dumps(d)
        assert d["ok"], name


def test_bench_quick_smoke(monkeypatch):
    from formation_env.aircraft import bench

    monkeypatch.setattr(bench, "_steps_per_s", lambda b, n, r: {"batch": b, "steps_per_s": 1.0})
    d = bench.run_benchmarks(quick=True)
    assert d["batch_1"]["batch"] == 1 and d["batch_1024"]["batch"] == 1024
