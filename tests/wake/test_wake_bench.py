"""The ELL benchmark's flop count (issue 26: GFLOP/s reported with the count it assumes): it follows the
kernels' loops, so it scales as they do; the benchmark's GFLOP/s is that count over the measured time.
Speed itself is reported by `formation-env bench`, never asserted."""

import pytest

from formation_env.geometry import aerosonde
from formation_env.wake import bench
from formation_env.wake.model import WakeModel


def _flops(n_vehicles, nseg=10, **kw):
    return bench.ell_flops(WakeModel([aerosonde(nseg=nseg)] * n_vehicles, **kw))


def test_flop_count_follows_the_loops_shared_field():
    """The default (evaluation at the control points, viscous AIC): the field is the sum of the AIC's kept
    branch vectors, 6 flops per other-vehicle horseshoe and point, and the AIC pays 3 per other knot and 6
    per other horseshoe to keep them."""
    f = bench.FLOPS
    one, two, three = _flops(1), _flops(2), _flops(3)
    assert one["field"] == 0
    assert two["field"] == 20 * 10 * 6
    assert three["field"] == 30 * 20 * 6
    separate = _flops(2, eval_points="quarter_chord")
    assert two["aic"] - separate["aic"] == 20 * (11 * 3 + 10 * 6)
    assert separate["field"] > 10 * two["field"]  # what sharing saves
    assert two["total"] == two["aic"] + two["lu"] + two["field"]


def test_flop_count_follows_the_loops():
    """The field evaluated separately (evaluation at the quarter chord)."""
    f = bench.FLOPS
    one = _flops(1, eval_points="quarter_chord")
    # one vehicle: no other vehicle's field (its 10 evaluation points are only placed in NED), and each of its
    # 10 control points sees its own 11 knots only
    assert one["field"] == 10 * f["to_ned"]
    per_point = 2 * f["to_ned"] - 3 + 11 * f["knot"] + 11 * (f["leg"] + f["dot"]) + 10 * 3 + 5
    assert one["aic"] == 10 * per_point
    assert one["lu"] == round(2 * 10 ** 3 / 3 + 2 * 10 ** 2)
    two, three = _flops(2, eval_points="quarter_chord"), _flops(3, eval_points="quarter_chord")
    # the cross-vehicle terms grow with the number of pairs: the field of 3 vehicles is 3x that of 2 (6 ordered
    # pairs against 2), and a finer lattice costs about (nseg ratio)^2 in the AIC
    cross = two["field"] - 20 * f["to_ned"]
    assert three["field"] - 30 * f["to_ned"] == 3 * cross
    assert _flops(2, nseg=20, eval_points="quarter_chord")["aic"] / two["aic"] == pytest.approx(4.0, rel=0.1)
    assert two["total"] == two["aic"] + two["lu"] + two["field"]


def test_benchmark_reports_gflops_from_the_count(monkeypatch):
    monkeypatch.setattr(bench, "_median_time", lambda fn, repeats, inner: 1e-3)  # no timing in a test
    res = bench.run_benchmarks(quick=True)
    total = res["flops_per_evaluation"]["total"]
    assert res["gflops_single"] == pytest.approx(total / 1e-3 / 1e9)
    rows = res["batched"]["1024"].values()
    assert {r["kernel"] for r in rows} == {"per_formation", "across_lanes"} and 1 in {r["threads"] for r in rows}
    for r in rows:
        assert r["gflops"] == pytest.approx(total * 1024 / 1e-3 / 1e9)
        assert r["gflops_per_core"] == pytest.approx(r["gflops"] / r["threads"])


def test_the_peak_is_derived_from_the_clock_and_the_vector_width(monkeypatch):
    import io

    cpuinfo = "processor\t: 0\ncpu MHz\t\t: 2500.000\nflags\t\t: fpu sse2 avx avx2 fma\n"
    monkeypatch.setattr("builtins.open", lambda *a, **k: io.StringIO(cpuinfo))
    peak = bench.peak_gflops_per_core()
    assert peak["gflops"] == pytest.approx(2 * 4 * 2 * 2.5)  # AVX2: 4 float64 lanes
    assert "AVX2" in peak["derivation"] and "2.50 GHz" in peak["derivation"]
