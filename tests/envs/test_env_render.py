"""Rendering of the vector envs (SB3 ``get_images``/``render``, Gymnasium ``render``) and of the
parallel env: each frame must show its own formation's aircraft where their state puts them."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from matplotlib.colors import to_rgb

import formation_env
from formation_env.envs.vector import FormationVecEnv, FormationVectorEnv
from formation_env.replay.view import vehicle_colour


def _colour_near(frame: np.ndarray, ax, east: float, north: float, colour: str, radius: int = 3) -> bool:
    """Whether a pixel of ``colour`` lies within ``radius`` px of data point (east, north) of ``ax``."""
    x, y = ax.transData.transform((east, north))
    h = frame.shape[0]
    col, row = int(round(x)), int(round(h - y))
    patch = frame[max(row - radius, 0):row + radius + 1, max(col - radius, 0):col + radius + 1].astype(float)
    target = 255.0 * np.asarray(to_rgb(colour))
    return bool(np.any(np.linalg.norm(patch - target, axis=-1) < 40.0))


def _diverged_vec_env():
    """Two formations flown with different actions, so their states (and frames) differ."""
    venv = FormationVecEnv(2, scenario="formation_keeping", render_mode="rgb_array", seed=0)
    venv.reset()
    a = venv.batch.agents_per_formation
    act = np.zeros((venv.num_envs, 4), dtype=np.float32)
    act[a] = [1.0, -1.0, 1.0, 1.0]  # formation 1's first agent only: its relative geometry changes
    for _ in range(10):
        venv.step(act)
    return venv


def test_vec_env_get_images_one_frame_per_index_each_formation_its_own():
    venv = _diverged_vec_env()
    eng, a = venv.batch.sim, venv.batch.agents_per_formation
    assert venv.render_mode == "rgb_array"
    images = venv.get_images()
    assert len(images) == venv.num_envs
    for img in images:
        assert img.ndim == 3 and img.shape[2] == 3 and img.dtype == np.uint8
        assert img.shape == images[0].shape
    for f in range(venv.batch.n_formations):  # the agents of a formation share its frame
        for k in range(1, a):
            assert np.array_equal(images[f * a], images[f * a + k])
    # the follower's relative position differs between the formations, so must their frames
    rel = eng.aircraft[:, 1, 10:13] - eng.aircraft[:, 0, 10:13]
    assert np.linalg.norm(rel[0] - rel[1]) > 0.5
    assert not np.array_equal(images[0], images[a])

    r = venv._renderer
    for f in range(venv.batch.n_formations):
        frame = r.draw(f)
        assert np.array_equal(frame, images[f * a])  # get_images() drew formation f for its indices
        pos = eng.aircraft[f, :, 10:13]  # NED
        for i in range(pos.shape[0]):
            assert _colour_near(frame, r.ax_top, pos[i, 1], pos[i, 0], vehicle_colour(i)), (f, i)
            for j in range(pos.shape[0]):  # nobody else's colour at a vehicle's centre when apart
                if j != i and np.linalg.norm(pos[i, :2] - pos[j, :2]) > 3.0:
                    assert not _colour_near(frame, r.ax_top, pos[i, 1], pos[i, 0], vehicle_colour(j), radius=1), (f, i, j)
            # side view: (north, altitude)
            assert _colour_near(frame, r.ax_side, pos[i, 0], -pos[i, 2], vehicle_colour(i)), (f, i)
        # absolute altitude without a "+1e3" offset
        assert r.ax_side.yaxis.get_offset_text().get_text() == ""
    venv.close()


def test_vec_env_frames_follow_the_flight():
    venv = FormationVecEnv(1, scenario="formation_keeping", render_mode="rgb_array", seed=0)
    venv.reset()
    eng = venv.batch.sim
    before = venv.get_images()[0]
    north0 = eng.aircraft[0, :, 10].copy()
    for _ in range(5):
        venv.step(np.zeros((venv.num_envs, 4), dtype=np.float32))
    after = venv.get_images()[0]
    assert np.all(eng.aircraft[0, :, 10] > north0 + 5.0)  # flying north
    r = venv._renderer
    # the view follows the formation: its north limits moved north by the distance flown
    lo, hi = r.ax_top.get_ylim()
    centre = eng.aircraft[0, :, 10].mean()
    assert lo < centre < hi and abs((lo + hi) / 2 - centre) < 1e-6
    assert not np.array_equal(before, after)
    venv.close()


def test_vec_env_render_tiles_the_frames():
    venv = FormationVecEnv(2, scenario="formation_keeping", render_mode="rgb_array", seed=0)
    venv.reset()
    big = venv.render()
    h, w, _ = venv.get_images()[0].shape
    n = venv.num_envs  # SB3 tiles n images on a ceil(sqrt(n)) x ceil(n / cols) grid
    cols = int(np.ceil(np.sqrt(n)))
    rows = int(np.ceil(n / cols))
    assert big.shape == (rows * h, cols * w, 3) and big.dtype == np.uint8
    assert np.array_equal(big[:h, :w], venv.get_images()[0])
    assert venv.render(mode="rgb_array").shape == big.shape
    venv.close()


def test_vec_env_without_render_mode_renders_nothing():
    venv = FormationVecEnv(1, scenario="formation_keeping", seed=0)
    venv.reset()
    assert venv.render_mode is None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert venv.render() is None
    with pytest.raises(ValueError, match="render_mode"):
        FormationVecEnv(1, scenario="formation_keeping", render_mode="human")


def test_gymnasium_vector_env_render_returns_a_tuple_of_frames():
    env = FormationVectorEnv(2, scenario="formation_keeping", render_mode="rgb_array")
    env.reset(seed=0)
    frames = env.render()
    assert isinstance(frames, tuple) and len(frames) == env.num_envs
    assert all(f.shape == frames[0].shape and f.dtype == np.uint8 for f in frames)
    env.close()
    plain = FormationVectorEnv(1, scenario="formation_keeping")
    plain.reset(seed=0)
    assert plain.render() is None


def test_parallel_env_rgb_frame_shows_the_aircraft_where_they_are():
    env = formation_env.parallel_env("formation_keeping", render_mode="rgb_array", duration_s=2.0)
    env.reset(seed=0)
    frame = env.render()
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8
    r, pos = env._renderer, env.sim.aircraft[0, :, 10:13]
    for i in range(pos.shape[0]):
        assert _colour_near(frame, r.ax_top, pos[i, 1], pos[i, 0], vehicle_colour(i)), i
        assert _colour_near(frame, r.ax_side, pos[i, 0], -pos[i, 2], vehicle_colour(i)), i
    env.close()


def test_parallel_env_human_render_returns_none():
    env = formation_env.parallel_env("formation_keeping", render_mode="human", duration_s=2.0)
    env.reset(seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert env.render() is None
    env.close()


def test_sb3_video_recorder_writes_a_video(tmp_path):
    pytest.importorskip("moviepy")
    from stable_baselines3.common.vec_env import VecVideoRecorder

    venv = FormationVecEnv(1, scenario="formation_keeping", render_mode="rgb_array", seed=0)
    rec = VecVideoRecorder(venv, str(tmp_path), record_video_trigger=lambda s: s == 0, video_length=4, name_prefix="t")
    rec.reset()
    for _ in range(6):
        rec.step(np.zeros((venv.num_envs, 4), dtype=np.float32))
    rec.close()
    videos = list(tmp_path.glob("t-*.mp4"))
    assert videos and videos[0].stat().st_size > 0


def test_figures_and_frames_name_vehicles_uav_i_and_show_full_altitudes():
    """One vehicle naming (``uav_<i>``, the agent names) in the render frame and the figures, and
    absolute altitudes (~1000 m) written in full, without a "+1e3" offset."""
    from formation_env.plotting import scenario_figures as sf
    from formation_env.runs.runner import run_scenario

    env = formation_env.parallel_env("formation_keeping", render_mode="rgb_array", duration_s=2.0)
    env.reset(seed=0)
    env.render()
    r = env._renderer
    assert {t.get_text() for t in r.ax_top.texts} == {f"uav_{i}" for i in range(env.sim.n_vehicles)}
    alt_ticks = [float(t.get_text().replace("\u2212", "-")) for t in r.ax_side.get_yticklabels() if t.get_text()]
    assert alt_ticks and all(900.0 < v < 1100.0 for v in alt_ticks)
    env.close()

    run = run_scenario("reconfiguration", None, 2.0)
    fig = sf._strip({"wake_on": run}, "t", [("h (m)", lambda h, i: -h["position_ned"][:, i, 2]),
                                            ("V (m/s)", lambda h, i: h["airspeed"][:, i])])
    fig.canvas.draw()
    ax = fig.axes[0]
    assert [ln.get_label() for ln in ax.get_lines()] == [f"uav_{i}" for i in range(run.h["airspeed"].shape[1])]
    assert ax.yaxis.get_offset_text().get_text() == ""
    ticks = [float(t.get_text().replace("\u2212", "-")) for t in ax.get_yticklabels() if t.get_text()]
    assert ticks and all(900.0 < v < 1100.0 for v in ticks)
    import matplotlib.pyplot as plt

    plt.close(fig)
