"""Replay: the ACMI file parses back (header, object ids, time frames) and its positions and
attitudes match the episode log; the recorder on the environment equals the log of the runner;
GIF; CLI."""

import numpy as np
import pytest

from formation_env.runs.runner import run_scenario
from formation_env.cli import main
from formation_env.replay import EpisodeLog, EpisodeRecorder, acmi_text, parse_acmi, write_acmi
from formation_env.replay.acmi import geodetic_to_ned, ned_to_geodetic, object_id


@pytest.fixture(scope="module")
def log():
    return EpisodeLog.from_scenario_run(run_scenario("reconfiguration", None, 3.0))


def test_acmi_parses_back_and_positions_match(log, tmp_path):
    path = write_acmi(log, tmp_path / "ep.txt.acmi")
    rec = parse_acmi(path.read_text())
    assert rec.header == {"FileType": "text/acmi/tacview", "FileVersion": "2.1"}
    assert rec.globals["ReferenceTime"].endswith("Z")
    assert sorted(rec.objects) == [object_id(i) for i in range(log.n_vehicles)] == ["101", "102"]
    assert rec.objects["101"]["Type"] == "Air+FixedWing"
    np.testing.assert_allclose(rec.times, log.time_s, atol=5e-4)
    lat0, lon0 = float(rec.globals["ReferenceLatitude"]), float(rec.globals["ReferenceLongitude"])
    for i in range(log.n_vehicles):
        t, lla = rec.positions(object_id(i))
        assert t.size == log.n_samples
        n, e = geodetic_to_ned(lla[:, 1], lla[:, 0], lat0, lon0)
        np.testing.assert_allclose(n, log.position_ned[:, i, 0], atol=5e-3)
        np.testing.assert_allclose(e, log.position_ned[:, i, 1], atol=5e-3)
        np.testing.assert_allclose(lla[:, 2], -log.position_ned[:, i, 2], atol=1e-3)
        att = np.array([f[1][object_id(i)]["T"][3:6] for f in rec.frames])
        np.testing.assert_allclose(att, np.degrees(log.euler_rad[:, i]), atol=1e-3)
        wind = np.array([[float(f[1][object_id(i)][k]) for k in ("InducedWindN", "InducedWindE", "InducedWindD")]
                         for f in rec.frames])
        np.testing.assert_allclose(wind, log.induced_wind_ned[:, i], rtol=1e-5, atol=1e-9)
    assert np.abs(log.induced_wind_ned[:, 1]).max() > 1e-3  # the follower is in the wake: the property carries data


def test_acmi_stride_keeps_last_sample_and_refuses_overwrite(log, tmp_path):
    rec = parse_acmi(acmi_text(log, stride=7))
    assert rec.times[-1] == pytest.approx(log.time_s[-1], abs=5e-4)
    assert len(rec.frames) == len(range(0, log.n_samples, 7)) + (1 if (log.n_samples - 1) % 7 else 0)
    write_acmi(log, tmp_path / "a.txt.acmi")
    with pytest.raises(FileExistsError):
        write_acmi(log, tmp_path / "a.txt.acmi")


def test_geodetic_round_trip_and_scale():
    lat, lon = ned_to_geodetic(np.array([0.0, 1000.0]), np.array([0.0, 1000.0]), 52.0, -0.6)
    assert 1000.0 / 111_300 < lat[1] - 52.0 < 1000.0 / 111_100  # ~111.2 km per degree of latitude at 52 N
    n, e = geodetic_to_ned(lat, lon, 52.0, -0.6)
    np.testing.assert_allclose([n, e], [[0, 1000], [0, 1000]], atol=1e-9)


@pytest.mark.parametrize("bad", ["", "FileType=text/acmi/tacview\n", "FileType=x\nFileVersion=2.1\n",
                                 "FileType=text/acmi/tacview\nFileVersion=2.1\n101,T=1|2|3\n",
                                 "FileType=text/acmi/tacview\nFileVersion=2.1\n#0\nzz,T=1|2|3\n"])
def test_parser_rejects_malformed(bad):
    with pytest.raises(ValueError):
        parse_acmi(bad)


def test_parser_handles_escapes_and_removal():
    text = ("\ufeffFileType=text/acmi/tacview\nFileVersion=2.1\n0,Comments=a\\, b\n// comment\n#1.5\n"
            "a1,T=1|2|3,Name=x\\,y\n#2\na1,T=|2.5|\n-a1\n")
    rec = parse_acmi(text)
    assert rec.globals["Comments"] == "a, b" and rec.objects["a1"]["Name"] == "x,y"
    t, lla = rec.positions("a1")
    np.testing.assert_allclose(lla, [[1, 2, 3], [1, 2.5, 3]])
    assert rec.removed == ["a1"]


def test_recorder_on_the_env_matches_the_runner(log):
    import formation_env

    from formation_env.sim.config import Randomisation

    env = formation_env.parallel_env("reconfiguration", randomisation=Randomisation())  # as the runner: calm, no jitter
    env.reset(seed=0)
    rec = EpisodeRecorder(env.sim)
    rec.record()
    n = 20
    for _ in range(n):  # PID everywhere: the env's zero-override step (baseline flies)
        if not env.agents:
            break
        env.step({a: np.zeros(env.action_space(a).shape, dtype=env.action_space(a).dtype) for a in env.agents})
        rec.record()
    elog = rec.log()
    assert elog.n_vehicles == 2 and elog.n_samples == n + 1
    steps = np.diff(elog.time_s)  # one sample per env step (a whole decision interval of physics steps)
    assert steps[0] >= env.sim.dt - 1e-12
    np.testing.assert_allclose(steps, steps[0])
    assert np.all(np.isfinite(elog.position_ned)) and np.abs(elog.induced_wind_ned[:, 1]).max() > 1e-3
    # same start as the runner's log
    np.testing.assert_allclose(elog.position_ned[0], log.position_ned[0], atol=1e-9)
    rec2 = parse_acmi(acmi_text(elog))
    assert len(rec2.frames) == elog.n_samples


def test_gif_and_npz(log, tmp_path):
    from formation_env.replay import write_animation

    p = write_animation(log, tmp_path / "ep.gif", max_frames=3)
    assert p.read_bytes()[:4] == b"GIF8"
    from PIL import Image

    with Image.open(p) as im:
        assert im.n_frames == 3
    with pytest.raises(ValueError):
        write_animation(log, tmp_path / "ep.avi")
    q = log.save_npz(tmp_path / "ep.npz")
    back = EpisodeLog.load_npz(q)
    np.testing.assert_array_equal(back.position_ned, log.position_ned)
    assert back.scenario == "reconfiguration"


def test_replay_cli(tmp_path):
    out = tmp_path / "r"
    assert main(["replay", "--scenario", "formation_keeping", "--duration", "1", "--out", str(out), "--gif",
                 "--max-frames", "2"]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == ["formation_keeping.gif", "formation_keeping.txt.acmi", "formation_keeping_log.npz",
                     "formation_keeping_trajectory_3d.png"]
    rec = parse_acmi((out / "formation_keeping.txt.acmi").read_text())
    assert len(rec.frames) == 50
    assert main(["replay", "--scenario", "nope", "--out", str(tmp_path / "n")]) == 2
    assert main(["replay", "--scenario", "formation_keeping", "--duration", "1", "--out", str(out)]) == 2
