"""The wake_surfing reference optimum (formation_env.tasks.wake_surfing.optimum): crab-angle geometry,
mirror symmetry, agreement with the close-formation optimum, the crosswind rotation checked against the
compiled env's ELL benefit, and the cached table."""

import math
import re

import numpy as np
import pytest

from formation_env.scenarios import get_scenario
from formation_env.tasks.close_formation import optimum as cfm
from formation_env.tasks.wake_surfing import optimum as ws

B = 2.9  # span, m


@pytest.fixture(scope="module")
def cache():
    return ws.load_cache()


@pytest.fixture(scope="module")
def calm():
    return ws.optimum_in_box(0.0)


# ---------------------------------------------------------------- crab angle

def test_crab_angle_sign_and_vectorisation():
    w = np.array([0.0, 4.0, 0.0])  # blowing toward the east
    assert ws.crab_angle_rad(w, 0.0, 25.0) == pytest.approx(math.asin(4 / 25), rel=1e-12)  # track north: starboard
    assert ws.crab_angle_rad(w, math.pi, 25.0) == pytest.approx(-math.asin(4 / 25), rel=1e-12)  # track south
    assert ws.crab_angle_rad(w, math.pi / 2, 25.0) == pytest.approx(0.0, abs=1e-12)  # tailwind
    chi = np.array([[0.0, math.pi / 6], [-math.pi / 6, math.pi / 2]])
    va = np.array([23.0, 27.0])
    c = ws.crab_angle_rad(w, chi, va)
    assert c.shape == (2, 2)
    np.testing.assert_allclose(c, np.arcsin(4.0 * np.cos(chi) / va), rtol=1e-12)
    with pytest.raises(ValueError, match="airspeed"):
        ws.crab_angle_rad(np.array([0.0, 30.0, 0.0]), 0.0, 25.0)
    with pytest.raises(ValueError, match="finite"):
        ws.crab_angle_rad(w, float("nan"), 25.0)


# ---------------------------------------------------------------- optimum in the box

def test_port_and_starboard_optima_mirror(calm):
    """Mirror images to the tolerance of the converged wake's residual table, whose y -> -y mirror is taken in the
    source's heading axes and so ignores the trim's sideslip (the wake trails along the air velocity): measured
    0.0064 b across the track, 3e-4 b vertically and 8e-4 of saving between the sides (the lattice alone: 1e-4)."""
    port = ws.optimum_in_box(0.0, side="port")
    assert port["offset_b"][0] == calm["offset_b"][0] == -2.0
    assert port["offset_b"][1] == pytest.approx(-calm["offset_b"][1], abs=1e-2)
    assert port["offset_b"][2] == pytest.approx(calm["offset_b"][2], abs=1e-3)
    assert port["saving"] == pytest.approx(calm["saving"], abs=1.5e-3)
    c = math.radians(8.0)
    stb, prt = ws.optimum_in_box(c), ws.optimum_in_box(-c, side="port")
    assert prt["offset_b"][1] == pytest.approx(-stb["offset_b"][1], abs=1e-2)
    assert prt["offset_b"][2] == pytest.approx(stb["offset_b"][2], abs=1e-3)
    assert prt["saving"] == pytest.approx(stb["saving"], abs=1.5e-3)
    lattice = [ws.optimum_in_box(0.0, side=side, wake=cfm.LATTICE_WAKE, z_exclusion_b=cfm.LATTICE_Z_EXCLUSION_B)
               for side in ("starboard", "port")]
    assert lattice[1]["saving"] == pytest.approx(lattice[0]["saving"], abs=1e-4)  # the lattice mirrors exactly
    assert stb["offset_b"][1] > calm["offset_b"][1] + 0.2  # the wake trails downwind: to starboard
    for o in (calm, port, stb, prt):
        assert 0 < o["n_evaluations"] < 1000


def test_calm_optimum_is_close_formations_converged_optimum_on_the_wake_plane(calm):
    """wake_surfing flies the converged wake (issue 23 part 7): its calm optimum is close_formation's pair optimum
    (found by the 2-UAV search over another region), on the leader's wake plane, inside the box."""
    cf = cfm.load_cache()["optimum"]
    assert calm["offset_b"][1] == pytest.approx(cf["offset_b"][1], abs=2e-3)
    assert calm["offset_b"][2] == pytest.approx(cf["offset_b"][2], abs=2e-3)
    assert abs(calm["offset_b"][2]) < 0.01  # on the wake plane
    assert calm["saving"] == pytest.approx(cf["saving"], abs=1e-4)
    assert calm["saving"] == pytest.approx(0.5608, abs=1e-3)
    box = get_scenario("wake_surfing").safe_box_b
    assert ws.SAFE_BOX_B == box and box[2][0] < calm["offset_b"][2] - 0.3


# ---------------------------------------------------------------- the crosswind rotation in the env

@pytest.fixture(scope="module")
def env_saving():
    """Follower saving from the env's compiled ``formation_benefit`` with both aircraft trimmed in a
    steady wind (air-relative velocities of the calm trim, heading rotated by the crab so that the
    ground track is north) and the follower at track-frame offsets (spans)."""
    from formation_env import frames
    from formation_env.aircraft import trim
    from formation_env.sim import Simulation
    from formation_env.tasks import make_config
    from formation_env.sim.step import formation_benefit

    eng = Simulation(make_config(scenario="wake_surfing", learning="followers"), batch_size=1)
    eng.reset([0], [0])
    tr = trim(25.0, 1000.0)

    def run(w_e, offsets_b):
        wind = np.array([0.0, w_e, 0.0])
        c = float(ws.crab_angle_rad(wind, 0.0, 25.0))
        x = tr.state[0].copy()
        e = frames.euler_from_quaternion(x[6:10])
        e[2] -= c  # heading = track - crab
        x[6:10] = frames.quaternion_from_euler(e)
        r = frames.dcm_body_to_ned_from_quaternion(x[6:10])
        x[0:3] = tr.state[0, 0:3] + r.T @ wind  # ground velocity = air-relative (trim) + wind
        x[10:13] = (0.0, 0.0, -1000.0)
        ground = r @ x[0:3]
        assert abs(ground[1]) < 1e-9 and ground[0] > 20.0  # the ground track is north
        assert np.linalg.norm(r @ tr.state[0, 0:3]) == pytest.approx(25.0, rel=1e-9)  # airspeed 25
        out = []
        for o in np.atleast_2d(offsets_b):
            st = np.repeat(x[None], 2, axis=0)
            st[1, 10:13] += np.asarray(o, float) * B
            eng.state.aircraft[0] = st
            eng.state.steady_wind[0] = wind
            sav = np.zeros(2)
            formation_benefit(eng.params, eng.state, 0, np.repeat(wind[None], 2, axis=0), sav)
            out.append(sav[1])
        return c, e[2], np.array(out)

    return run


@pytest.mark.parametrize("w_e", [4.0, -4.0])
def test_crosswind_optimum_holds_in_the_compiled_env(env_saving, w_e):
    c = float(ws.crab_angle_rad(np.array([0.0, w_e, 0.0]), 0.0, 25.0))
    y, z, s = (float(v) for v in ws.reference_optimum(c))
    y_wrong = float(ws.reference_optimum(-c)[0])  # the optimum for the wrong sign of the rotation
    y_calm = float(ws.reference_optimum(0.0)[0])
    pts = [(-2, y, z), (-2, y - 0.15, z), (-2, y + 0.15, z), (-2, y_wrong, z), (-2, y_calm, z), (-2, y, z + 0.15)]
    c_env, heading, sv = env_saving(w_e, pts)
    assert c_env == pytest.approx(c)
    assert np.sign(heading) == -np.sign(w_e)  # a wind toward the east: the leader heads west of north
    assert np.sign(y - y_calm) == np.sign(w_e)  # ... and its wake trails east, to starboard
    assert abs(y - y_calm) > 0.3
    assert sv[0] == pytest.approx(s, abs=5e-3)
    assert sv[1] < sv[0] - 0.01 and sv[2] < sv[0] - 0.01  # 0.15 b either way laterally loses saving
    assert sv[5] < sv[0] - 0.01  # and so does 0.15 b further below
    assert sv[3] < sv[0] - 0.15  # the wrong-sign rotation: far off the optimum
    assert sv[4] < sv[0] - 0.1  # not rotating at all (the calm slot) is also much worse
    # the module's rotated calm-air savings are the env's at any offset, not only the optimum (with the env's
    # ELL model: the task flies the load-weighted coupling's lift-matched wing)
    np.testing.assert_allclose(ws.saving_in_crosswind(np.array(pts, float), c), sv, atol=1e-5)


# ---------------------------------------------------------------- the cache

def test_cache_matches_fresh_optima_and_the_first_order_shift(cache):
    assert ws.CACHE_PATH.stat().st_size < 200_000
    deg = np.asarray(cache["crab_deg"])
    np.testing.assert_allclose(deg, np.arange(-15.0, 15.5, 1.0))
    assert cache["parameters"]["box_b"] == [list(b) for b in ws.SAFE_BOX_B]
    for d in (-12.0, 7.0):
        i = int(np.argmin(np.abs(deg - d)))
        fresh = ws.optimum_in_box(math.radians(d))
        assert fresh["offset_b"][1] == pytest.approx(cache["optimum"]["y_b"][i], abs=1e-3)
        assert fresh["offset_b"][2] == pytest.approx(cache["optimum"]["z_b"][i], abs=1e-3)
        assert fresh["saving"] == pytest.approx(cache["optimum"]["saving"][i], abs=1e-4)
    y = np.asarray(cache["optimum"]["y_b"])
    assert np.all(np.diff(y) > 0)  # the optimum moves monotonically downwind with the crab
    np.testing.assert_allclose(y, cache["first_order_y_b"], atol=5e-3)  # (y_calm + 2 sin c) / cos c
    np.testing.assert_allclose(cache["optimum"]["z_b"], 0.0, atol=3e-3)  # the wake plane
    # the crab-0 map: shape, peak beside the optimum, a few points re-evaluated
    m = cache["map"]
    f = np.asarray(m["follower_saving"])
    assert f.shape == (len(m["y_b"]), len(m["z_b"])) == (41, 49)
    iy, iz = np.unravel_index(np.argmax(f), f.shape)
    assert abs(m["y_b"][iy] - y[deg == 0][0]) <= 0.05 and m["z_b"][iz] == pytest.approx(0.0)
    assert f.max() <= cache["optimum"]["saving"][int(np.flatnonzero(deg == 0)[0])] + 1e-5
    iy, iz = np.array([0, 19, 30, 40]), np.array([0, 16, 20, 48])
    fresh = ws.saving_in_crosswind(np.stack([np.full(4, -2.0), np.asarray(m["y_b"])[iy], np.asarray(m["z_b"])[iz]], -1),
                                   0.0)
    np.testing.assert_allclose(fresh, f[iy, iz], atol=2e-5)


def test_reference_optimum_interpolates_and_rejects_out_of_range(cache):
    deg = np.asarray(cache["crab_deg"])
    y, z, s = ws.reference_optimum(np.radians(deg))
    np.testing.assert_allclose(y, cache["optimum"]["y_b"], atol=1e-12)
    np.testing.assert_allclose(s, cache["optimum"]["saving"], atol=1e-12)
    ym, _, _ = ws.reference_optimum(math.radians(3.5))
    assert ym == pytest.approx(0.5 * (y[deg == 3][0] + y[deg == 4][0]), abs=1e-12)
    assert np.shape(ws.reference_optimum(np.zeros((2, 3)))[2]) == (2, 3)
    ws.reference_optimum(math.radians(15.0))  # the edge is inside
    for bad in (math.radians(15.5), -math.radians(20.0), float("nan"), float("inf")):
        with pytest.raises(ValueError, match=re.escape(repr(bad))):
            ws.reference_optimum(bad)
    with pytest.raises(ValueError, match="outside"):
        ws.reference_optimum(np.array([0.0, 0.1, 0.3]))


def test_episode_reference_follows_wind_track_and_airspeed():
    t = np.linspace(0.0, 90.0, 91)
    chi = np.radians(np.where(t < 30.0, 0.0, 30.0))  # a 30 deg turn to starboard
    va = np.where(t < 30.0, 25.0, 23.0)
    wind = np.array([0.0, 5.0, 0.0])
    ref = ws.episode_reference(wind, chi, va)
    assert ref["y_b"].shape == ref["z_b"].shape == ref["saving"].shape == t.shape
    np.testing.assert_allclose(ref["crab_rad"], np.arcsin(5.0 * np.cos(chi) / va), rtol=1e-12)
    y_expect, _, s_expect = ws.reference_optimum(np.arcsin(5.0 * np.cos(chi) / va))
    np.testing.assert_allclose(ref["y_b"], y_expect)
    assert ref["mean_saving"] == pytest.approx(float(np.mean(s_expect)))
    assert np.all(ref["y_b"] > ws.reference_optimum(0.0)[0])  # the wind blows toward starboard throughout
    calm = ws.episode_reference(np.zeros(3), chi, va)
    np.testing.assert_allclose(calm["y_b"], ws.reference_optimum(0.0)[0])
