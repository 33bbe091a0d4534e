"""The committed four-level held-out record of the close_formation policies (train/policies/
close_formation_ppo_setpoints_levels.json, docs/close_formation.md) is what the committed zips fly: the
policies through the separation guard their sidecars name, on the wake fidelity the record names."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.train.record_refly import POLICIES, refly

RECORD = POLICIES / "close_formation_ppo_setpoints_levels.json"


@pytest.mark.skipif(not RECORD.is_file(), reason="no committed close_formation record")
@pytest.mark.parametrize("level", ["sigma_1", "sigma_1.5"])
def test_the_committed_record_is_what_the_guarded_policy_flies(level):
    """Two of the record's held-out episodes of seed 0 flown again give the recorded harvest ratio, lateral RMS
    and least separation (the record rounds to 6 digits); each seed's summary is the mean of its 100 episodes and
    its collision count their sum."""
    rec = json.loads(RECORD.read_text())["by_level"][level]
    eps, cols = refly(rec, "close_formation", "close_formation_ppo_setpoints_seed0")
    for key in ("harvest_ratio", "rms_lateral_m", "min_separation_m"):
        assert [e[key] for e in eps] == pytest.approx(cols[key][:2], rel=1e-5, abs=1e-6)
    for k in range(3):
        seed_cols = rec["episodes"][f"close_formation_ppo_setpoints_seed{k}"]
        assert len(seed_cols["harvest_ratio"]) == 100
        summary = rec["summaries"][f"close_formation_ppo_setpoints_seed{k}"]
        assert summary["harvest_ratio"] == pytest.approx(np.mean(seed_cols["harvest_ratio"]), abs=1e-6)
        assert summary["collisions"] == sum(seed_cols["collision"])
