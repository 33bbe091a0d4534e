"""The energy tasks' training recipes pay the saving up to their task's optimum (train/hyperparams/ppo.yml): the
caps are copies of the cached optima, so a regenerated cache that moves an optimum must move its cap too."""

import pytest

from formation_env.tasks.close_formation import optimum as cf
from formation_env.tasks.close_formations import optimum as cfs
from train.config import HYPERPARAMS_DIR, load_yaml


def test_the_caps_are_the_cached_optima():
    ppo = load_yaml(HYPERPARAMS_DIR / "ppo.yml")
    assert ppo["close_formation"]["env_kwargs"]["reward"]["benefit_cap"] == pytest.approx(cf.optimum_saving(), abs=1e-4)
    # one cap for every N-UAV formation: the vee5 followers' mean saving at its joint optimum, to 0.01
    for name in ("echelon3", "vee5", "vee9"):
        assert ppo[name]["env_kwargs"]["reward"]["benefit_cap"] == pytest.approx(
            cfs.optimum("vee5")["slot_follower_saving"], abs=0.005)
