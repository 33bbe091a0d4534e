"""agents.station_keeper: the decomposition onto the thesis loops, signs, bounds, validation, and the
closed loop in close_formation (calm-air precision; beats pid_formation across the track at sigma 1)."""

import math

import numpy as np
import pytest

from agents.pid_formation import PIDFormation
from agents.station_keeper import TRIM_THETA_RAD, StationKeeper, StationKeeperGains
from formation_env.control.gains import AutopilotGains, TrackerGains
from formation_env.envs.observations import group_sizes, observation_size, slog

N_VEHICLES = 2


SLOT_LEADER_M = (5.8, -2.8, -0.3)  # the leader relative to a follower in the slot (slot frame, m)


def _obs(err=(0.0, 0.0, 0.0), derr=(0.0, 0.0, 0.0), wind=(0.0, 0.0, 0.0), leader=SLOT_LEADER_M, n=1, phi=0.0,
         theta=TRIM_THETA_RAD, dv_air=0.0):
    """A 2-UAV observation with the given slot errors (m), velocity errors (m/s), ambient wind (m/s), the
    leader's position relative to the follower (m), bank and pitch (rad) and airspeed minus trim (m/s)."""
    obs = np.zeros((n, observation_size(N_VEHICLES)))
    k = 0
    for name, size in group_sizes(N_VEHICLES).items():
        if name == "air_data":
            obs[:, k] = dv_air / 5.0
        elif name == "attitude":
            obs[:, k:k + 2] = np.array([phi, theta]) / 0.5
        elif name == "slot_position_error":
            obs[:, k:k + size] = slog(np.asarray(err, float), 1.0)
        elif name == "slot_velocity_error":
            obs[:, k:k + size] = slog(np.asarray(derr, float), 1.0)
        elif name == "ambient_wind":
            obs[:, k:k + size] = slog(np.asarray(wind, float), 1.0)
        elif name == "neighbours":
            obs[:, k:k + 3] = slog(np.asarray(leader, float), 3.0)
        k += size
    return obs


def _thesis_gains(airspeed=25.0):
    """Gains whose total law equals the thesis loops' own, no leads (so every offset is zero): bank =
    -kd (kp e_y + de_y) is the tracker's off-track PD through the heading loop on the ground track."""
    tr, ap = TrackerGains(), AutopilotGains()
    kd = ap.Kp_heading * (tr.Kd_offtrack + 1.0 / airspeed)
    return StationKeeperGains(kp_lateral=ap.Kp_heading * tr.Kp_offtrack / kd, kd_lateral=kd, ki_lateral=0.0,
                              v_lateral_max=100.0, bank_max=10.0, k_roll=0.0,
                              kp_vertical=-ap.Kp_altitude, kd_vertical=-ap.Kd_altitude, ki_vertical=0.0, k_pitch=0.0,
                              kw_vertical=0.0, wind_feedforward=0.0, kp_along=0.0, kd_along=0.0, ki_along=0.0,
                              k_energy=0.0)


def test_thesis_gains_command_no_offset():
    # the total laws minus the thesis's own: with the thesis gains nothing is left to command
    agent = StationKeeper(_thesis_gains())
    a = agent.act(_obs(err=(0.0, 0.7, -0.4), derr=(0.0, 0.3, 0.2)))
    np.testing.assert_allclose(a, 0.0, atol=1e-6)


def test_signs_and_magnitudes():
    agent = StationKeeper()
    g = agent.gains
    tr, ap = TrackerGains(), AutopilotGains()
    # 0.02 m starboard of the slot, wings level: bank to port, -kd kp e, sent with the roll lead (1 + k_roll)
    # through the heading loop and the tracker's off-track P: a port position-demand offset
    a = agent.act(_obs(err=(0.0, 0.02, 0.0)))[0]
    bank_sent = -(1.0 + g.k_roll) * g.kd_lateral * g.kp_lateral * 0.02
    expect_dy = 0.02 + bank_sent / (ap.Kp_heading * tr.Kp_offtrack)
    assert a[1] == pytest.approx(expect_dy / 5.0, rel=1e-4)
    assert a[1] < 0
    # already banked as designed: the lead adds nothing
    agent.reset(1)
    banked = agent.act(_obs(err=(0.0, 0.02, 0.0), phi=-g.kd_lateral * g.kp_lateral * 0.02))[0]
    assert banked[1] == pytest.approx((0.02 + bank_sent / (1.0 + g.k_roll) / (ap.Kp_heading * tr.Kp_offtrack)) / 5.0,
                                      rel=1e-4)
    # the track-angle demand saturates at 40 deg: a large error saturates the offset, never flips its sign
    agent.reset(1)
    assert agent.act(_obs(err=(0.0, 3.0, 0.0)))[0, 1] < 0
    # 0.1 m below the slot (z down > 0): pitch up = demand a higher point (negative down offset)
    agent.reset(1)
    a = agent.act(_obs(err=(0.0, 0.0, 0.1)))[0]
    expect_dz = ((1.0 + g.k_pitch) * g.kp_vertical + ap.Kp_altitude) * 0.1 / ap.Kp_altitude
    assert a[2] == pytest.approx(expect_dz / 5.0, rel=1e-4)
    assert a[2] < 0
    # a 1 m/s downdraft: pitch up by w/V (with the pitch lead) before it sinks the aircraft
    agent.reset(1)
    a = agent.act(_obs(wind=(0.0, 0.0, 1.0)))[0]
    assert a[2] == pytest.approx((1.0 + g.k_pitch) * g.kw_vertical * (1.0 / 25.0) / ap.Kp_altitude / 5.0, rel=1e-4)
    # a head wind of 1 m/s (wind along -x): more airspeed demanded
    agent.reset(1)
    assert agent.act(_obs(wind=(-1.0, 0.0, 0.0)))[0, 3] == pytest.approx(g.wind_feedforward / 2.0, rel=1e-4)
    # far behind the slot: descend (energy trade) beyond the dead band only
    agent.reset(1)
    near = agent.act(_obs(err=(-0.5 * g.lag_deadband_m, 0.0, 0.0)))[0, 2]
    agent.reset(1)
    far = agent.act(_obs(err=(-g.lag_deadband_m - 1.0, 0.0, 0.0)))[0, 2]
    assert near == pytest.approx(0.0, abs=1e-6)
    assert far == pytest.approx(g.k_energy / 5.0, rel=1e-4)


def test_separation_guard_moves_away_from_an_overtaken_leader():
    """Each case against the same slot error with the leader far ahead (no guard): the guard's own effect. The
    leader's position is consistent with the slot error (the slot is 5.8 m behind, 2.8 m starboard of it)."""
    g = StationKeeper().gains
    tr, ap = TrackerGains(), AutopilotGains()
    clear = StationKeeper().act(_obs())[0]
    np.testing.assert_allclose(clear[:3], 0.0, atol=1e-6)  # on the slot, the leader 5.8 m ahead: no guard

    def guarded(ahead_m, lateral_m=-2.8):  # follower ahead of its slot, leader ahead_m ahead of the follower
        err = (5.8 - ahead_m, 0.0, 0.0)
        a = StationKeeper().act(_obs(err=err, leader=(ahead_m, lateral_m, -0.3)))[0]
        free = StationKeeper().act(_obs(err=err, leader=(30.0, lateral_m, -0.3)))[0]
        return a - free

    # the leader only 4 m ahead and 2.8 m to port: the target moves to starboard by guard_lateral_m and down
    # by guard_vertical_m, times the ramp (depth / guard_m)^2, and the speed demand drops
    close = guarded(4.0)
    ramp = ((g.guard_m - 4.0) / g.guard_m) ** 2
    bank_sent = (1.0 + g.k_roll) * g.kd_lateral * g.kp_lateral * g.guard_lateral_m * ramp
    assert close[1] == pytest.approx(bank_sent / (ap.Kp_heading * tr.Kp_offtrack) / 5.0, rel=1e-4)
    pitch = -(1.0 + g.k_pitch) * g.kp_vertical * g.guard_vertical_m * ramp
    assert close[2] == pytest.approx(pitch / ap.Kp_altitude / 5.0, rel=1e-4)
    assert close[1] > 0 and close[2] > 0 and close[3] < 0
    # mirrored: a leader to starboard pushes the demand to port (and still down)
    port = guarded(4.0, 2.8)
    assert port[1] == pytest.approx(-close[1], rel=1e-4) and port[2] == pytest.approx(close[2], rel=1e-4)
    # beside the leader: the full shift, further away still (the speed demand is saturated there either way)
    beside = guarded(-1.0)
    assert beside[1] > close[1] and beside[2] > close[2]


def test_separation_guard_ignores_a_follower_abeam_or_behind():
    """In a vee the inner followers fly 1.8 spans (5.2 m) abeam of each other and the outer ones 2 spans behind:
    neither is a UAV to brake for (the guard did, and the vee's inner followers lagged their slots by 4.7 m); the
    leader ahead and in line still is."""
    def act(neighbours):
        obs = np.zeros((1, observation_size(1 + len(neighbours))))
        k = observation_size(1)
        obs[0, 4] = TRIM_THETA_RAD / 0.5  # trim pitch (attitude: phi, theta, psi from index 3), as _obs
        for j, rel in enumerate(neighbours):
            obs[0, k + 6 * j:k + 6 * j + 3] = slog(np.asarray(rel, float), 3.0)
        return StationKeeper().act(obs)[0]

    leader = (5.8, -2.6, -0.3)
    alone = act([leader])
    np.testing.assert_allclose(act([leader, (0.3, -5.2, 0.0), (-5.8, 2.7, 0.3)]), alone, atol=1e-7)
    # the same UAV abeam but in line with the slot (as an overtaken leader would be) is guarded
    assert act([leader, (0.3, -2.6, 0.0)])[1] > alone[1] + 0.05


def test_airspeed_floor_stops_the_brakes():
    g = StationKeeper().gains
    ahead = (g.lag_deadband_m + 1.0, 0.0, 0.0)  # ahead of the slot beyond the dead band: slow down, climb
    normal = StationKeeper().act(_obs(err=ahead))[0]
    slow = StationKeeper().act(_obs(err=ahead, dv_air=-(g.speed_floor_mps + 1.0)))[0]
    assert normal[3] < 0 and normal[2] < 0
    assert slow[3] - normal[3] == pytest.approx(g.k_stall / 2.0, rel=1e-4)
    assert slow[2] - normal[2] == pytest.approx(g.k_stall / 5.0, rel=1e-4)
    # above the floor nothing changes
    assert StationKeeper().act(_obs(err=ahead, dv_air=-(g.speed_floor_mps - 0.5)))[0] == pytest.approx(normal)


def test_bounded_finite_and_integrators_unwind():
    rng = np.random.default_rng(3)
    agent = StationKeeper()
    obs = rng.normal(0.0, 3.0, size=(64, observation_size(N_VEHICLES)))
    obs[0] = np.nan  # a diverged aircraft's row
    for _ in range(50):
        a = agent.act(obs)
        assert a.shape == (64, 4) and a.dtype == np.float32
        assert np.all(np.isfinite(a)) and np.all(np.abs(a) <= 1.0)
    # a saturated channel stops integrating (anti-windup): 50 s far off the slot
    agent.reset(1)
    for _ in range(500):
        agent.act(_obs(err=(0.0, 30.0, 0.0)))
    assert abs(agent.integral[0, 1]) < 1.0


@pytest.mark.parametrize("bad", [dict(kp_lateral=-0.1), dict(kd_vertical=math.nan), dict(ki_along=math.inf),
                                 dict(k_energy=True), dict(lag_deadband_m="3")])
def test_bad_gains_raise(bad):
    with pytest.raises(ValueError, match=next(iter(bad))):
        StationKeeperGains(**bad)


def test_bad_arguments_raise():
    with pytest.raises(ValueError, match="gains"):
        StationKeeper(gains={"kp_lateral": 1.0})
    with pytest.raises(ValueError, match="control_hz"):
        StationKeeper(control_hz=0.0)
    with pytest.raises(ValueError, match="airspeed_mps"):
        StationKeeper(airspeed_mps=-25.0)
    with pytest.raises(ValueError, match="Kp_altitude"):
        StationKeeper(autopilot=AutopilotGains(Kp_altitude=0.03))
    agent = StationKeeper()
    with pytest.raises(ValueError, match="n_rows"):
        agent.reset(0)
    with pytest.raises(ValueError, match="shape"):
        agent.act(np.zeros(observation_size(N_VEHICLES)))
    with pytest.raises(ValueError, match="observation length"):
        agent.act(np.zeros((1, 7)))


def _fly(agent, sigma, seeds, duration_s):
    from train.evaluation.episodes import eval_env_config, run_episodes
    from train.evaluation.policy import EvalPolicy

    import dataclasses

    cfg = eval_env_config("close_formation", "setpoints", turbulence_sigma_mps=sigma, compute_benefit=True,
                          duration_s=duration_s)
    # the start on the slot, as the gains were checked (the test set's 0.3 m start jitter adds a transient)
    cfg = dataclasses.replace(cfg, randomisation=dataclasses.replace(cfg.randomisation, initial_offset_m=0.0))
    return run_episodes(EvalPolicy("x", agent.action_mode, agent.act, agent.control_hz, reset=agent.reset), cfg, seeds)


def test_calm_air_holds_the_slot_across_the_track():
    (ep,) = _fly(StationKeeper(), 0.0, [1], 30.0)
    assert not ep["collision"] and not ep["crashed"]
    # the saving halves within ~0.1 b (0.29 m) across the track: hold it to a few centimetres
    assert ep["rms_lateral_m"] < 0.1
    assert ep["rms_vertical_m"] < 0.05
    assert ep["rms_along_track_m"] < 0.2


def test_beats_pid_formation_across_the_track_in_turbulence():
    seeds = [1, 2, 3, 4]  # training-range seeds
    sk = _fly(StationKeeper(), 1.0, seeds, 40.0)
    pf = _fly(PIDFormation(), 1.0, seeds, 40.0)
    cross = [math.hypot(e["rms_lateral_m"], e["rms_vertical_m"]) for e in sk]
    cross_pf = [math.hypot(e["rms_lateral_m"], e["rms_vertical_m"]) for e in pf]
    assert not any(e["collision"] for e in sk)
    assert np.mean(cross) < 0.5 * np.mean(cross_pf)
    # the attitude leads hold the slot to well inside the saving's 0.29 m half-width across the track
    assert np.mean([e["rms_lateral_m"] for e in sk]) < 0.6
    assert np.mean([e["harvest_ratio"] for e in sk]) > 0.6
    assert np.mean([e["induced_drag_saving"] for e in sk]) > np.mean([e["induced_drag_saving"] for e in pf])


def test_hold_offset_m_displaces_the_slot_the_keeper_holds():
    """With no displacement it is the keeper's own set-point offsets (m); displaced by d it is the keeper's action on
    the error taken to the displaced slot, shifted back by d (so a follower already there is held there); a wrong
    shape is refused."""
    from formation_env.sim.params import SETPOINT_POSITION_SCALE_M

    err = np.array([0.0, 0.4, -0.2])
    obs = _obs(err=err)
    own = StationKeeper().act(obs)[:, 1:3] * SETPOINT_POSITION_SCALE_M
    np.testing.assert_allclose(StationKeeper().hold_offset_m(obs, np.zeros((1, 2))), own, rtol=1e-12, atol=1e-12)
    d = np.array([[0.4, -0.2]])  # the follower sits on the displaced slot: the keeper holds it as it holds its own
    at_slot = StationKeeper().act(_obs(err=np.zeros(3)))[:, 1:3] * SETPOINT_POSITION_SCALE_M
    np.testing.assert_allclose(StationKeeper().hold_offset_m(obs, d), at_slot + d, atol=1e-9)
    with pytest.raises(ValueError, match="offset_m"):
        StationKeeper().hold_offset_m(obs, np.zeros(2))
