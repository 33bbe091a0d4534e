"""Physics of the RK4-integrated model: trimmed hold, wind, symmetry, batching, errors, divergence."""

import numpy as np
import pytest

from formation_env import frames
from formation_env.aircraft import make_state, step
from formation_env.aircraft.eom import ModelOptions, air_data_of, outputs
from formation_env.aircraft.envelope import Status, check_envelope
from formation_env.aircraft.state import ALPHA_PREV, QUAT, altitude, euler_angles
from formation_env.aircraft.trim import trim
from formation_env.atmosphere import DrydenConfig, DrydenTurbulence, WindInput, thesis_gust_40s

DT = 0.02


def _run(state, controls, n, wind_fn=None, options=ModelOptions()):
    s = state
    for k in range(n):
        wind = wind_fn(k, s) if wind_fn else None
        s = step(s, controls, wind, DT, options=options)
    return s


def test_trimmed_flight_holds_for_60_s(trim_a5):
    s = _run(trim_a5.state, trim_a5.controls, int(60 / DT))
    assert abs(altitude(s)[0] - 1000.0) < 1.0
    assert abs(air_data_of(s)["airspeed_raw"][0] - 25.0) < 0.2
    assert np.all(check_envelope(s) == 0)
    # ~1500 m north, fuel burnt at the trim fuel flow
    assert s[0, 10] == pytest.approx(1500.0, rel=1e-3)
    assert s[0, 13] == pytest.approx(2.0 - 60 * trim_a5.extras["fuel_flow"], rel=1e-4)


def test_quaternion_stays_unit(trim_a5):
    c = trim_a5.controls + np.array([[0.02, 0.03, -0.02, 0.1]])
    s = _run(trim_a5.state, c, 300)
    assert np.linalg.norm(s[0, QUAT]) == pytest.approx(1.0, abs=1e-12)


def test_steady_wind_moves_ground_track_not_air_data(trim_a5):
    w_ned = np.array([4.0, -3.0, 0.0])  # horizontal, so the altitude history is unchanged
    s0 = trim_a5.state.copy()
    s_w = s0.copy()
    c_bn = frames.dcm_body_to_ned_from_quaternion(s0[0, QUAT]).T
    s_w[0, 0:3] += c_bn @ w_ned  # same air-relative velocity, ground velocity + wind
    wind = WindInput(wind_ned=w_ned)
    c = trim_a5.controls + np.array([[-0.01, 0.005, 0.0, 0.05]])  # manoeuvre a little
    n = 500
    a, b = s0, s_w
    for _ in range(n):
        a = step(a, c, None, DT)
        b = step(b, c, wind, DT)
    ad_a, ad_b = air_data_of(a), air_data_of(b, wind)
    for key in ("airspeed_raw", "alpha_raw", "beta_raw"):
        assert ad_b[key][0] == pytest.approx(ad_a[key][0], abs=1e-9)
    assert np.allclose(euler_angles(b), euler_angles(a), atol=1e-9)
    assert np.allclose(b[:, 3:6], a[:, 3:6], atol=1e-9)
    # the ground track is displaced by exactly wind * t
    assert np.allclose(b[0, 10:13] - a[0, 10:13], w_ned * n * DT, atol=1e-6)


def test_ell_translational_wind_acts_as_wind(trim_a5):
    w = np.array([[0.3, 1.2, -0.8]])
    a = _run(trim_a5.state, trim_a5.controls, 50, lambda k, s: WindInput(wind_ned=w))
    b = _run(trim_a5.state, trim_a5.controls, 50, lambda k, s: WindInput(ell_translational_ned=w))
    assert np.array_equal(a, b)


def test_ell_rotational_wind_is_subtracted_from_aero_rates(trim_a5):
    """Thesis Eq. 4.9: the aerodynamics see p - p_w. A body roll rate of 0.2 in still air must give
    the same aerodynamic roll moment as zero roll rate in a rotational wind of -0.2."""
    s_rate = trim_a5.state.copy()
    s_rate[0, 3] = 0.2
    o_rate = outputs(s_rate, trim_a5.controls)
    o_wind = outputs(trim_a5.state, trim_a5.controls, WindInput(ell_rotational_body=[[-0.2, 0.0, 0.0]]))
    assert o_wind["Cl"][0] == pytest.approx(o_rate["Cl"][0], abs=1e-14)
    assert o_wind["Cn"][0] == pytest.approx(o_rate["Cn"][0], abs=1e-14)
    o_still = outputs(trim_a5.state, trim_a5.controls)
    # the increment is the roll-damping term Clp p b / 2V with p_aero = +0.2
    assert o_wind["Cl"][0] - o_still["Cl"][0] == pytest.approx(-0.5051 * 0.2 * 2.8956 / 50.0, rel=1e-9)


def test_symmetric_inputs_give_no_lateral_motion():
    """With the engine reaction torque (the only asymmetry of the data) switched off, elevator and
    throttle inputs from a symmetric trim leave v, p, r, phi, psi and east exactly zero."""
    opts = ModelOptions(engine_reaction_torque=False)
    t = trim(options=opts)
    s = t.state
    for k in range(600):
        c = t.controls.copy()
        c[0, 0] += 0.05 * np.sin(0.5 * k * DT)
        c[0, 3] += 0.2 if k < 300 else -0.3
        s = step(s, c, WindInput(wind_ned=[2.0, 0.0, 0.5 * np.sin(0.1 * k * DT)]), DT, options=opts)
    e = euler_angles(s)[0]
    lateral = [s[0, 1], s[0, 3], s[0, 5], e[0], e[2], s[0, 11]]
    assert np.max(np.abs(lateral)) < 1e-12
    assert abs(s[0, 0] - t.state[0, 0]) > 0.1  # the longitudinal motion did happen


def test_batch_equals_single_runs():
    t = trim()
    B = 4
    rng = np.random.default_rng(7)
    s0 = np.repeat(t.state, B, axis=0)
    s0[:, 0:3] += rng.normal(0, 0.5, (B, 3))
    s0[:, 3:6] += rng.normal(0, 0.05, (B, 3))
    ctrl = np.repeat(t.controls, B, axis=0) + rng.normal(0, 0.01, (B, 4))
    seeds = [11, 22, 33, 44]
    cfg = DrydenConfig.low_altitude(300.0, 8.0)
    gust = thesis_gust_40s()
    ell = rng.normal(0, 0.2, (B, 3))
    ell_rot = rng.normal(0, 0.02, (B, 3))

    def run(idx):
        turb = DrydenTurbulence(cfg, [seeds[i] for i in idx])
        s = s0[idx].copy()
        for k in range(250):
            wind = WindInput(np.repeat(gust.wind_ned(10.0 + k * DT)[None], len(idx), 0),
                             turb.step(), ell[idx], ell_rot[idx])
            s = step(s, ctrl[idx], wind, DT)
        return s

    batch = run(list(range(B)))
    singles = np.concatenate([run([i]) for i in range(B)])
    assert np.array_equal(batch, singles)


def test_first_step_has_zero_alpha_dot_and_later_steps_use_it(trim_a5):
    s = trim_a5.state.copy()
    s[0, 2] += 1.0  # pitch-up disturbance: alpha jumps
    s = make_state(s[0, 0:3], s[0, 3:6], euler_angles(s)[0], s[0, 10:13], 2.0, s[0, 14])
    a1 = step(s, trim_a5.controls)
    b1 = step(s, trim_a5.controls, options=ModelOptions(alpha_dot=False))
    assert np.array_equal(a1, b1)  # alpha-dot memory initialised by make_state
    a2 = step(a1, trim_a5.controls)
    b2 = step(b1, trim_a5.controls, options=ModelOptions(alpha_dot=False))
    assert not np.allclose(a2[:, 3:6], b2[:, 3:6], atol=1e-9)
    assert a1[0, ALPHA_PREV] == pytest.approx(air_data_of(s)["alpha_raw"][0], abs=0)


@pytest.mark.parametrize(
    "controls",
    [np.array([[np.nan, 0, 0, 0.5]]), np.array([[0, np.inf, 0, 0.5]]), np.zeros((1, 3)),
     np.zeros((2, 4)), np.zeros((1, 6))],
)
def test_bad_controls_raise(trim_a5, controls):
    with pytest.raises(ValueError, match="controls"):
        step(trim_a5.state, controls)


def test_bad_state_and_dt_raise(trim_a5):
    with pytest.raises(ValueError, match="state"):
        step(trim_a5.state[:, :10], trim_a5.controls)
    with pytest.raises(ValueError, match="dt"):
        step(trim_a5.state, trim_a5.controls, dt=0.0)
    with pytest.raises(ValueError, match="wind"):
        step(trim_a5.state, trim_a5.controls, WindInput(wind_ned=np.zeros((3, 3))))


def test_divergence_is_flagged_per_aircraft(trim_a5):
    s = np.repeat(trim_a5.state, 3, axis=0)
    c = np.repeat(trim_a5.controls, 3, axis=0)
    s[1, 14] = np.nan  # a non-finite state
    c[2, 0] = 0.35  # full nose-down elevator: dives, overspeeds, loses altitude
    s[2, 12] = -150.0
    flags = np.zeros(3, dtype=np.int64)
    with np.errstate(all="raise"):  # step itself must not warn on the bad rows
        for _ in range(600):
            s = step(s, c)
            flags |= check_envelope(s)
    assert flags[0] == 0
    assert flags[1] & Status.NON_FINITE
    assert flags[2] & (Status.ALTITUDE_LOW | Status.AIRSPEED_HIGH | Status.ATTITUDE)
    # the healthy aircraft is exactly the single run
    single = trim_a5.state
    for _ in range(600):
        single = step(single, trim_a5.controls)
    assert np.array_equal(s[0], single[0])


def test_envelope_flags_airspeed_and_attitude(trim_a5):
    s = np.repeat(trim_a5.state, 3, axis=0)
    s[0, 0] = 8.0
    s[1, 0] = 70.0
    s[2, QUAT] = frames.quaternion_from_euler(np.array([np.deg2rad(85.0), 0.0, 0.0]))
    flags = check_envelope(s)
    assert flags[0] & Status.AIRSPEED_LOW
    assert flags[1] & Status.AIRSPEED_HIGH
    assert flags[2] & Status.ATTITUDE
    # a headwind raises the airspeed that the check uses
    assert check_envelope(s[:1], WindInput(wind_ned=[-20.0, 0, 0]))[0] == 0


def test_downdraft_gust_costs_altitude_and_turbulence_stays_in_envelope(trim_a5):
    """Open loop, the 40 s preset's downward component pushes the aircraft down relative to still
    air; light Dryden turbulence perturbs it without leaving the envelope in 20 s."""
    gust = thesis_gust_40s(amplitude_ned=(0.0, 0.0, 1.5))
    t0 = 10.0
    n = int(10.0 / DT)
    still = _run(trim_a5.state, trim_a5.controls, n)
    gusty = _run(trim_a5.state, trim_a5.controls, n, lambda k, s: WindInput(wind_ned=gust.wind_ned(t0 + k * DT)))
    assert altitude(gusty)[0] < altitude(still)[0] - 1.0
    turb = DrydenTurbulence(DrydenConfig.low_altitude(300.0, 8.0), [123])
    s = trim_a5.state
    vas = []
    for _ in range(int(20.0 / DT)):
        wind = WindInput(turbulence_body=turb.step())
        s = step(s, trim_a5.controls, wind, DT)
        vas.append(air_data_of(s, wind)["airspeed_raw"][0])
        assert check_envelope(s, wind)[0] == 0
    assert np.std(vas) > 0.1  # the turbulence did reach the aircraft
