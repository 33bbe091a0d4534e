"""The energy tasks' benchmark rewards pay the saving up to their task's optimum (Task.options): the caps are copies
of the cached optima, so a regenerated cache that moves an optimum must move its cap too."""

import pytest

from formation_env.tasks.close_formation import optimum as cf
from formation_env.tasks.n_uav_formations import optimum as cfs
from formation_env.tasks import get_task


def test_the_caps_are_the_cached_optima():
    assert get_task("close_formation").options["reward"].benefit_cap == pytest.approx(cf.optimum_saving(), abs=1e-4)
    # one cap for every N-UAV formation: the vee5 followers' mean saving at its joint optimum, to 0.01
    for name in ("echelon3", "vee5", "vee9"):
        assert get_task(name).options["reward"].benefit_cap == pytest.approx(
            cfs.optimum("vee5")["slot_follower_saving"], abs=0.005)
