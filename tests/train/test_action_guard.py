"""The separation guard as part of a trained policy: a guarded run trains through GuardedVecEnv, its sidecars
say so, and load_policy flies the loaded model through the same filter (and an unguarded run's policy without)."""

import json
import shutil

import numpy as np
import pytest

from agents.separation_guard import SeparationGuard
from train.evaluation.policy_loader import load_policy, policy_metadata
from train.sb3.train import train
from formation_env.envs.observations import group_sizes, observation_size, slog


def _overtaking(n=4):
    """Followers 1.8 m ahead of their slot with the leader 4 m ahead and 2.8 m to port (inside the guard)."""
    obs = np.zeros((n, observation_size(2)), np.float32)
    k = 0
    for name, size in group_sizes(2).items():
        if name == "slot_position_error":
            obs[:, k:k + size] = slog(np.array([1.8, 0.0, 0.0]), 1.0)
        elif name == "neighbours":
            obs[:, k:k + 3] = slog(np.array([4.0, -2.8, 0.0]), 3.0)
        k += size
    return obs


def test_guarded_run_and_its_loaded_policy(tmp_path, tiny):
    from stable_baselines3 import PPO

    from agents.separation_guard import GuardGains

    for k, guard in enumerate((True, False, {"clip_ramp": 0.25})):
        out = tmp_path / f"g{k}"
        over = {**tiny("ppo"), "action_guard": guard}
        train(scenario="close_formation", algo="ppo", action_mode="setpoints", seed=0, steps=128, out_dir=out,
              overrides=over, progress_bar=False, log=lambda m: None)
        meta = json.loads((out / "best_model.json").read_text())
        assert meta.get("action_guard", False) == guard
        pol = load_policy(str(out / "best_model.zip"))
        raw = PPO.load(str(out / "best_model.zip"), device="cpu").predict(_overtaking(), deterministic=True)[0]
        gains = GuardGains(**guard) if isinstance(guard, dict) else GuardGains()
        want = SeparationGuard(gains).filter(_overtaking(), raw) if guard else raw
        np.testing.assert_array_equal(pol.act(_overtaking()), want)
        assert bool(guard) == (not np.array_equal(want, raw))
        # without a sidecar the run's config.yaml speaks (its TrainConfig sits under "config")
        bare = out / "checkpoints" / "bare.zip"
        bare.parent.mkdir(exist_ok=True)
        shutil.copy(out / "best_model.zip", bare)
        meta = policy_metadata(bare)
        assert meta["algo"] == "ppo" and meta["action_mode"] == "setpoints" and meta["action_guard"] == guard


def test_a_sidecar_names_the_guards_gains(tmp_path):
    """The committed close_formation sidecars fly their zips through the guard with the lateral clip
    (``env.action_guard: {"clip_ramp": 0.25}``); a sidecar naming a gain the guard lacks is refused."""
    from pathlib import Path

    from stable_baselines3 import PPO

    from agents.separation_guard import GuardGains

    src = Path(__file__).resolve().parents[2] / "train" / "policies" / "close_formation_ppo_setpoints_seed0"
    meta = json.loads(src.with_suffix(".json").read_text())
    assert meta["env"]["action_guard"] == {"clip_ramp": 0.25}
    pol = load_policy(str(src.with_suffix(".zip")))
    obs = _overtaking(8)
    k = 0
    # deeper in the guard: 4.8 m ahead of the slot and 1 m starboard of it, the leader 1 m ahead and 2.8 m to port;
    # a policy steering back to its slot steers toward the leader's side there, which the clip must hold
    for name, size in group_sizes(2).items():
        if name == "slot_position_error":
            obs[4:, k:k + size] = slog(np.array([4.8, 1.0, 0.0]), 1.0)
        elif name == "neighbours":
            obs[4:, k:k + 3] = slog(np.array([1.0, -2.8, 0.0]), 3.0)
        k += size
    obs[:, :3] += np.linspace(-0.5, 0.5, 8)[:, None].astype(np.float32)  # varied air data: varied raw actions
    raw = PPO.load(str(src.with_suffix(".zip")), device="cpu").predict(obs, deterministic=True)[0]
    np.testing.assert_array_equal(pol.act(obs), SeparationGuard(GuardGains(clip_ramp=0.25)).filter(obs, raw))
    assert not np.array_equal(pol.act(obs), SeparationGuard().filter(obs, raw))  # the clip acted on a deep row
    bad = tmp_path / "p.zip"
    shutil.copy(src.with_suffix(".zip"), bad)
    meta["env"]["action_guard"] = {"clip": 0.25}
    bad.with_suffix(".json").write_text(json.dumps(meta))
    with pytest.raises(ValueError, match=r"action_guard: unknown separation-guard gain\(s\) \['clip'\]"):
        load_policy(str(bad))
