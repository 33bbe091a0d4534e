"""``formation-env replay --policy``: a committed SB3 zip and pid_formation fly a seeded, reproducible
episode and write the ACMI, the log, the 3D figure and the GIF; frame limits."""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pytest

from formation_env.cli import main
from formation_env.replay import EpisodeLog, parse_acmi

ROOT = Path(__file__).resolve().parents[2]
ZIP = ROOT / "train" / "policies" / "close_formation_ppo_setpoints_seed0.zip"


def _replay(argv, capsys) -> dict:
    assert main(["replay", *argv]) == 0
    return json.loads(capsys.readouterr().out)


def test_replay_sb3_zip_is_seeded_and_reproducible(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    if not ZIP.is_file():
        pytest.skip("no committed close_formation policy")
    a = _replay(["--policy", str(ZIP), "--duration", "2", "--seed", "5", "--gif", "--max-frames", "3",
                 "--no-progress", "--out", str(tmp_path / "a")], capsys)
    # the scenario and action mode come from the zip's sidecar JSON
    assert a["scenario"] == "close_formation" and a["action_mode"] == "setpoints" and a["seed"] == 5
    assert a["policy"] == ZIP.stem and a["status"] == "completed"
    names = sorted(p.name for p in (tmp_path / "a").iterdir())
    assert names == ["close_formation.gif", "close_formation.txt.acmi", "close_formation_log.npz",
                     "close_formation_trajectory_3d.png"]
    from PIL import Image

    with Image.open(tmp_path / "a" / "close_formation.gif") as im:
        assert im.n_frames == 3
    rec = parse_acmi((tmp_path / "a" / "close_formation.txt.acmi").read_text())
    assert len(rec.frames) == a["samples"] == 21  # reset + 20 decisions at 10 Hz
    b = _replay(["--policy", str(ZIP), "--duration", "2", "--seed", "5", "--out", str(tmp_path / "b")], capsys)
    c = _replay(["--policy", str(ZIP), "--duration", "2", "--seed", "6", "--out", str(tmp_path / "c")], capsys)
    la, lb, lc = (EpisodeLog.load_npz(tmp_path / d / "close_formation_log.npz") for d in "abc")
    np.testing.assert_array_equal(la.position_ned, lb.position_ned)
    assert b["samples"] == a["samples"]
    assert not np.array_equal(la.position_ned, lc.position_ned)  # another seed, another episode


def test_replay_pid_formation(tmp_path, capsys):
    pytest.importorskip("train.evaluation.policy_loader")
    r = _replay(["--policy", "pid_formation", "--scenario", "formation_keeping", "--duration", "1",
                 "--seed", "3", "--turbulence", "0", "--out", str(tmp_path / "p")], capsys)
    assert r["policy"] == "pid_formation" and r["turbulence_sigma_mps"] == 0.0 and r["samples"] >= 2
    log = EpisodeLog.load_npz(tmp_path / "p" / "formation_keeping_log.npz")
    assert np.all(np.isfinite(log.position_ned))


def test_progress_plain_lines(monkeypatch):
    from formation_env.cli import replay

    err = io.StringIO()
    monkeypatch.setattr("sys.stderr", err)
    step, close = replay._progress(None, 20, "x.gif")  # not a terminal: plain lines every 10 %
    for i in range(20):
        step(i)
    close()
    lines = err.getvalue().splitlines()
    assert len(lines) == 10 and lines[-1] == "x.gif: frame 20/20 (100 %)"
    step, close = replay._progress(False, 20, "x.gif")
    step(0)
    assert len(err.getvalue().splitlines()) == 10


def test_frame_cap():
    from formation_env.replay.animation import MAX_FRAMES, frame_indices

    log = EpisodeLog(np.arange(5000) * 0.02, *(np.zeros((5000, 2, 3)),) * 7)
    assert len(frame_indices(log, 10.0, 0.02, None)) == MAX_FRAMES
    assert len(frame_indices(log, 10.0, 4.0, 1)) == 1
    for bad in (0, -1, MAX_FRAMES + 1, 2.5):
        with pytest.raises(ValueError, match="max_frames"):
            frame_indices(log, 10.0, 4.0, bad)
