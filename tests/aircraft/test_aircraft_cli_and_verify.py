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
    """The figures the bench reports, on a clock whose every RK4 step takes 4 ms: 250 steps/s
    exactly, 4000 us per step, batch x 250 aircraft steps/s, the warm-up step not timed."""
    import types

    import numpy as np

    from formation_env.aircraft import bench

    clock = {"t": 100.0}
    calls = []

    def fake_step(state, controls):
        calls.append((state.shape, controls.shape))
        clock["t"] += 4e-3
        return state

    monkeypatch.setattr(bench, "step", fake_step)
    monkeypatch.setattr(bench, "time", types.SimpleNamespace(perf_counter=lambda: clock["t"]))
    d = bench.run_benchmarks(quick=True)
    for key, batch, n_steps in (("batch_1", 1, 100), ("batch_1024", 1024, 10)):
        r = d[key]
        assert r["batch"] == batch and r["repeats"] == 3 and r["steps_per_repeat"] == n_steps
        assert r["steps_per_s"] == pytest.approx(250.0, rel=1e-9)
        assert r["us_per_step"] == pytest.approx(4000.0, rel=1e-9)
        assert r["us_per_step"] * r["steps_per_s"] == pytest.approx(1e6, rel=1e-12)
        assert r["aircraft_steps_per_s"] == pytest.approx(250.0 * batch, rel=1e-9)
    # one untimed warm-up plus repeats x steps per batch, on (batch, 16) states
    assert len(calls) == (1 + 3 * 100) + (1 + 3 * 10)
    assert calls[0][0] == (1, 16) and calls[-1][0] == (1024, 16)
    assert calls[0][1][0] == 1 and calls[-1][1][0] == 1024
    assert np.isfinite(d["batch_1"]["steps_per_s"])


def test_bench_rate_matches_a_direct_timing_of_the_step():
    """The real bench on a tiny batch agrees with timing ``aircraft.step`` directly (within a factor
    of 4: a shared 2-core machine is noisy, a wrong formula or unit is off by far more)."""
    import time

    import numpy as np

    from formation_env.aircraft import bench
    from formation_env.aircraft.eom import step
    from formation_env.aircraft.trim import trim

    batch, n = 8, 40
    r = bench._steps_per_s(batch, n, 3)
    assert r["us_per_step"] * r["steps_per_s"] == pytest.approx(1e6, rel=1e-9)
    assert r["aircraft_steps_per_s"] == pytest.approx(r["steps_per_s"] * batch, rel=1e-12)
    t = trim()
    s, c = np.repeat(t.state, batch, axis=0), np.repeat(t.controls, batch, axis=0)
    step(s, c)
    rates = []
    for _ in range(3):
        x, t0 = s, time.perf_counter()
        for _ in range(n):
            x = step(x, c)
        rates.append(n / (time.perf_counter() - t0))
    direct = float(np.median(rates))
    assert direct / 4 < r["steps_per_s"] < direct * 4, (r["steps_per_s"], direct)
