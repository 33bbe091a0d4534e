"""The ceilings of issue 24 (train/evaluation/ceilings.py): a preview of 0 s is the plain station keeper bit for bit,
and the slot preview's first pass predicts the second pass's leader path."""

import numpy as np
import pytest

from agents.station_keeper import StationKeeper
from train.evaluation.ceilings import _keeper_policy, slot_preview_keeper, wind_preview_keeper
from train.evaluation.episodes import eval_env_config, run_episodes

SEEDS = [41_500_000_000 + i for i in range(3)]
KEYS = ("harvest_ratio", "rms_lateral_m", "rms_vertical_m", "rms_along_track_m", "min_separation_m", "return")


@pytest.fixture(scope="module")
def cfg():
    return eval_env_config("close_formation", "setpoints", turbulence_sigma_mps=1.0, compute_benefit=True, duration_s=6.0)


@pytest.fixture(scope="module")
def plain(cfg):
    k = StationKeeper()
    return run_episodes(_keeper_policy("station_keeper", k.act, k.reset), cfg, SEEDS)


def test_a_preview_of_nothing_is_the_plain_keeper(cfg, plain):
    told_wind = wind_preview_keeper(cfg, SEEDS, 0.0)
    told_slot, _ = slot_preview_keeper(cfg, SEEDS, 0.0)
    for eps in (told_wind, told_slot):
        for a, b in zip(eps, plain):
            assert [a[k] for k in KEYS] == [b[k] for k in KEYS]


def test_the_previews_change_the_flight_and_the_slot_path_is_predicted(cfg, plain):
    told_wind = wind_preview_keeper(cfg, SEEDS, 1.0)
    told_slot, stray = slot_preview_keeper(cfg, SEEDS, 0.5)
    for eps in (told_wind, told_slot):
        assert any(a["rms_lateral_m"] != b["rms_lateral_m"] for a, b in zip(eps, plain))
        assert all(np.isfinite([e[k] for k in KEYS]).all() for e in eps)
    assert stray < 0.1  # m: the leader's path hardly depends on what the follower does
