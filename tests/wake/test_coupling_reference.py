"""The load-weighted coupling against an independent code: AeroSandbox's vortex-lattice method on two Aerosonde
wings (the committed table tests/data/coupling_aerosandbox.json, written by tests/oracles/aerosandbox_coupling.py),
the follower's lift, induced-drag and rolling-moment increments on the lateral (y 0.6-1.4 b, z 0.1 b) and vertical
(z -0.3-0.5 b, y 0.9 b) sweeps at x = -2 b. A live comparison reruns AeroSandbox where it is installed."""

from __future__ import annotations

import importlib.util
import json
import math
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from formation_env.aircraft import AEROSONDE
from formation_env.geometry import aerosonde
from formation_env.verification.coupling_sweeps import (AIRSPEED_MPS, ALTITUDE_M, SPAN_M, TRIM_ALPHA_RAD, CouplingCase,
                                                         formation_state)
from formation_env.wake import isolated_loads
from formation_env.wake.coupling import lift_matched_incidence_rad

TABLE = Path(__file__).resolve().parents[1] / "data" / "coupling_aerosandbox.json"
ORACLE = Path(__file__).resolve().parents[1] / "oracles" / "aerosandbox_coupling.py"
# max |coupling - AeroSandbox| / max |AeroSandbox| of the sweep, (lift, drag, roll), outside the wake-plane band
# |z| < 0.1 b, measured with nseg 10: lateral 0.060 / 0.066 / 0.083, vertical 0.041 / 0.048 / 0.079 (of which
# the ELL's own lattice error is 0.046 / 0.077 / 0.069 and 0.019 / 0.008 / 0.092; with nseg 40 the coupling is
# within 0.05 / 0.06 / 0.02). Tolerance 0.12 on every quantity; the thesis's uniform effective wind is off by
# 0.39 / 0.41 / 0.32 laterally.
TOL = 0.12
# In the band (z = 0: the leader's wake plane) the nseg-10 ELL itself is off by up to 0.31 of the peak (roll);
# the coupling follows it (docs/ell.md; the lattice's convergence there is issue 23 part 6).
TOL_BAND = 0.35


@lru_cache(maxsize=None)
def _table() -> dict:
    return json.loads(TABLE.read_text())


@lru_cache(maxsize=None)
def _case(coupling: str) -> CouplingCase:
    return CouplingCase(coupling)


def _rows(sweep: str) -> list[dict]:
    return [r for r in _table()["rows"] if r["sweep"] == sweep]


def _reference(rows) -> np.ndarray:
    return np.array([[r["dlift_n"], r["ddrag_n"], r["droll_nm"]] for r in rows])


def _coupling(coupling: str, rows) -> np.ndarray:
    case = _case(coupling)
    return np.array([case.sixdof(formation_state(r["y_b"], r["z_b"], r["x_b"])) for r in rows])


def test_table_is_the_projects_geometry_and_trim():
    t = _table()
    g, op = t["geometry"], t["operating_point"]
    wing = aerosonde().surfaces[0]
    assert g["span_m"] == pytest.approx(wing.span_m) == pytest.approx(SPAN_M)
    assert g["aspect_ratio"] == pytest.approx(wing.aspect_ratio)
    assert g["taper"] == pytest.approx(wing.taper)
    assert g["sweep_deg"] == pytest.approx(math.degrees(wing.sweep_rad))
    assert g["dihedral_deg"] == pytest.approx(math.degrees(wing.dihedral_rad))
    assert g["incidence_deg"] == pytest.approx(math.degrees(lift_matched_incidence_rad(AEROSONDE)), rel=1e-12)
    assert op["alpha_deg"] == pytest.approx(math.degrees(TRIM_ALPHA_RAD), rel=1e-12)
    assert op["airspeed_mps"] == AIRSPEED_MPS and op["altitude_m"] == ALTITUDE_M
    assert [r["y_b"] for r in _rows("lateral")] == pytest.approx(np.arange(0.6, 1.41, 0.1).tolist())
    assert [r["z_b"] for r in _rows("vertical")] == pytest.approx(np.arange(-0.3, 0.51, 0.1).tolist())


@pytest.mark.parametrize("sweep", ["lateral", "vertical"])
def test_load_weighted_coupling_matches_aerosandbox(sweep):
    rows = _rows(sweep)
    ref = _reference(rows)
    got = _coupling("load_weighted", rows)
    peak = np.abs(ref).max(axis=0)
    band = np.array([abs(r["z_b"]) < 0.1 - 1e-9 for r in rows])
    err = np.abs(got - ref) / peak
    assert np.all(err[~band] <= TOL), (sweep, err[~band].max(axis=0))
    assert np.all(err[band] <= TOL_BAND), (sweep, err[band])
    # signs where the increment is clear of zero: the lift gain, the drag saving and the roll direction
    clear = np.abs(ref) > 0.2 * peak
    assert np.all(np.sign(got[clear]) == np.sign(ref[clear]))


def test_thesis_effective_wind_misses_aerosandbox():
    """The check above discriminates: the thesis's uniform average (same lift-matched wing) fails it."""
    rows = _rows("lateral")
    ref = _reference(rows)
    err = np.abs(_coupling("effective_wind", rows) - ref) / np.abs(ref).max(axis=0)
    assert np.all(err.max(axis=0) > 2 * TOL), err.max(axis=0)


def test_isolated_near_field_drag_is_below_aerosandbox():
    """e > 1: the ELL's isolated near-field induced drag with 10 horseshoes (one chordwise) is 9 % below the
    converged VLM's (span efficiency 1.12 against 0.99), while its lift is within 2 %: the ELL's relative
    saving is inflated by that much (docs/ell.md)."""
    r = _rows("lateral")[0]
    s = formation_state(r["y_b"], r["z_b"], r["x_b"])
    alone = isolated_loads(_case("load_weighted").model, s, _table()["operating_point"]["density_kg_m3"])
    ratio_d = alone.drag_n[0, 1] / r["drag_alone_n"]
    ratio_l = alone.lift_n[0, 1] / r["lift_alone_n"]
    assert 0.88 < ratio_d < 0.94, ratio_d
    assert abs(ratio_l - 1.0) < 0.02, ratio_l


@pytest.mark.skipif(importlib.util.find_spec("aerosandbox") is None, reason="aerosandbox is not installed")
def test_live_aerosandbox_reproduces_the_table():
    spec = importlib.util.spec_from_file_location("aerosandbox_coupling", ORACLE)
    oracle = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(oracle)
    for r in (_rows("lateral")[3], _rows("vertical")[1]):
        live = oracle.follower_increments(r["y_b"], r["z_b"], r["x_b"])
        for key in ("dlift_n", "ddrag_n", "droll_nm", "drag_alone_n"):
            assert live[key] == pytest.approx(r[key], rel=1e-6, abs=1e-9), key
