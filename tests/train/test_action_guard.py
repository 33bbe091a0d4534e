"""The separation guard as part of a trained policy: a guarded run trains through GuardedVecEnv, its sidecars
say so, and load_policy flies the loaded model through the same filter (and an unguarded run's policy without)."""

import json
import shutil

import numpy as np

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

    for guard in (True, False):
        out = tmp_path / f"g{guard}"
        over = {**tiny("ppo"), "action_guard": guard}
        train(scenario="close_formation", algo="ppo", action_mode="setpoints", seed=0, steps=128, out_dir=out,
              overrides=over, progress_bar=False, log=lambda m: None)
        meta = json.loads((out / "best_model.json").read_text())
        assert meta.get("action_guard", False) is guard
        pol = load_policy(str(out / "best_model.zip"))
        raw = PPO.load(str(out / "best_model.zip"), device="cpu").predict(_overtaking(), deterministic=True)[0]
        want = SeparationGuard().filter(_overtaking(), raw) if guard else raw
        np.testing.assert_array_equal(pol.act(_overtaking()), want)
        assert guard == (not np.array_equal(want, raw))
        # without a sidecar the run's config.yaml speaks (its TrainConfig sits under "config")
        bare = out / "checkpoints" / "bare.zip"
        bare.parent.mkdir(exist_ok=True)
        shutil.copy(out / "best_model.zip", bare)
        meta = policy_metadata(bare)
        assert meta["algo"] == "ppo" and meta["action_mode"] == "setpoints" and meta["action_guard"] is guard
