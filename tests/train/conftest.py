import pytest

# Tiny runs: 2 formations, 3 s episodes, one-layer nets; a few hundred steps each.
TINY = {
    "ppo": {"n_formations": 2, "n_steps": 32, "batch_size": 32, "n_epochs": 1, "eval_freq": 128, "eval_episodes": 2,
            "checkpoint_freq": 128, "policy_kwargs": {"net_arch": [16]}, "env_kwargs": {"duration_s": 3.0}},
    "sac": {"n_formations": 2, "buffer_size": 2000, "learning_starts": 64, "batch_size": 32, "gradient_steps": 1,
            "eval_freq": 128, "eval_episodes": 2, "checkpoint_freq": 128, "policy_kwargs": {"net_arch": [16]},
            "env_kwargs": {"duration_s": 3.0}},
    "td3": {"n_formations": 2, "buffer_size": 2000, "learning_starts": 64, "batch_size": 32, "gradient_steps": 1,
            "eval_freq": 128, "eval_episodes": 2, "checkpoint_freq": 128, "policy_kwargs": {"net_arch": [16]},
            "env_kwargs": {"duration_s": 3.0}},
}


@pytest.fixture
def tiny():
    import copy

    return lambda algo: copy.deepcopy(TINY[algo])
