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


@pytest.fixture
def seeded_candidates(monkeypatch):
    """``seeded_candidates(step)``: ``load_policy('cand_seed<k>')`` gives the PID plus a constant throttle
    residual of ``step * k`` (a different controller per seed); every other spec loads as usual."""
    import numpy as np

    import train.evaluation.evaluate as ev
    from train.evaluation.evaluate import EvalPolicy

    real = ev.load_policy

    def install(step):
        def load(spec, **kw):
            if spec.startswith("cand_seed"):
                k = int(spec[len("cand_seed"):])
                return EvalPolicy(spec, "residual", lambda o: np.tile([0.0, 0.0, 0.0, step * k], (o.shape[0], 1)))
            return real(spec, **kw)

        monkeypatch.setattr(ev, "load_policy", load)

    return install
