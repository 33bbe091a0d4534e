"""optimum_saving() of the energy tasks (the denominator of a harvest ratio): the cached optimum's saving,
the best of the cached map in the task's allowed region, and the ELL's saving at the cached optimum."""

import numpy as np

from formation_env.tasks.close_formation import optimum as cf
from formation_env.tasks.wake_surfing import optimum as ws


def test_close_formation_optimum_saving_is_the_best_allowed_slot():
    c = cf.load_cache()
    s = cf.optimum_saving()
    assert s == c["optimum"]["saving"]
    m = c["map"]
    z = np.asarray(m["z_b"])
    allowed = np.abs(z) >= c["z_exclusion_b"] - 1e-9
    assert s >= np.asarray(m["follower_saving"])[:, allowed].max() - 1e-4  # no allowed map point beats it
    np.testing.assert_allclose(cf.slot_savings(np.asarray(c["optimum"]["offset_b"]))[1], s, atol=1e-4)


def test_wake_surfing_optimum_saving_is_the_calm_air_box_optimum():
    t = ws.load_cache()
    s = ws.optimum_saving()
    assert s == ws.reference_optimum(0.0)[2]
    assert s >= np.max(t["map"]["follower_saving"]) - 1e-4  # the crab-0 map over the box never beats it
    y, z, _ = ws.reference_optimum(0.0)
    np.testing.assert_allclose(ws.saving_in_crosswind(np.array([ws.X_B, y, z]), 0.0), s, atol=1e-4)
