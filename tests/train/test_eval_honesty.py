"""An episode that ends early is scored as a failure in every summary metric, never as a short, accurate run
(issue 22): the old evaluation gave an immediate crash an RMS slot error of a few mm and 100 % time within 1 m."""

from __future__ import annotations

import numpy as np

from formation_env.rollout import FunctionPolicy, ZeroPolicy
from train.evaluation.episodes import FAILURE_SLOT_ERROR_M, eval_env_config, run_episodes
from train.evaluation.summary import summarise


def _crash(obs):
    a = np.zeros((obs.shape[0], 4))
    a[:, 0] = a[:, 1] = 1.0  # full elevator and aileron: out of the envelope within a second
    return a


def test_a_crash_never_scores_better_than_flying_to_the_end():
    seeds = [100, 101]
    crash_cfg = eval_env_config("formation_keeping", "surfaces", turbulence_sigma_mps=0.0, duration_s=20.0)
    crashed = run_episodes(FunctionPolicy(_crash), crash_cfg, seeds)
    flown = run_episodes(ZeroPolicy(), eval_env_config("formation_keeping", "setpoints", duration_s=20.0), seeds)
    for c, f in zip(crashed, flown):
        assert c["crashed"] and c["duration_s"] < 2.0 and not f["crashed"]
        assert c["rms_slot_error_m"] > 0.9 * FAILURE_SLOT_ERROR_M > f["rms_slot_error_m"]
        assert c["max_slot_error_m"] >= FAILURE_SLOT_ERROR_M
        assert c["time_within_1m_frac"] < 0.1 <= f["time_within_1m_frac"]
    sc, sf = summarise(crashed, n_boot=50), summarise(flown, n_boot=50)
    assert sc["rms_slot_error_m"] > sf["rms_slot_error_m"] and sc["time_within_1m_frac"] < sf["time_within_1m_frac"]


def test_a_crash_earns_no_saving_for_the_time_it_did_not_fly():
    from train.evaluation.task_eval import fly

    cfg = eval_env_config("wake_surfing", "surfaces", duration_s=20.0)
    ep = fly("wake_surfing", FunctionPolicy(_crash), [7], config=cfg)[0]
    assert ep["crashed"] and ep["duration_s"] < 2.0
    assert ep["box_outside_frac"] > 0.9 and ep["saving"] < 0.02 and ep["saving_ratio"] < 0.05


def test_the_safe_box_saving_counts_no_decision_outside_the_box_as_the_task_metric_does():
    """Model selection in a safe-box task (issue 24) ranks by ``induced_drag_saving_in_box``: each decision's
    saving, none outside the box and none for the time not flown. It is the wake-surfing metric's ``saving``
    (:mod:`formation_env.tasks.wake_surfing.metrics`), episode by episode, and not the saving as measured
    whenever the follower left the box (outside, the ELL's saving may be an artefact, or negative)."""
    import pytest

    from train.evaluation.summary import selection_score
    from train.evaluation.task_eval import fly

    cfg = eval_env_config("wake_surfing", "setpoints", turbulence_sigma_mps=1.0, duration_s=30.0)
    seeds = [5, 6, 7]
    eps = run_episodes(ZeroPolicy(), cfg, seeds)
    task = fly("wake_surfing", ZeroPolicy(), seeds, config=cfg)
    assert any(e["box_outside_frac"] > 0.05 for e in eps)  # the thesis PID leaves the box at sigma 1
    for e, t in zip(eps, task):
        assert e["induced_drag_saving_in_box"] == pytest.approx(t["saving"], abs=1e-12)
        if e["box_outside_frac"] > 0:
            assert abs(e["induced_drag_saving_in_box"] - e["induced_drag_saving"]) > 1e-4
    s = summarise(eps, n_boot=50)
    clean = {**s, "collisions": 0, "crashes": 0}  # (the PID may collide at sigma 1: that disqualifies)
    assert selection_score(clean) == pytest.approx(-s["induced_drag_saving_in_box"])
    assert selection_score({**clean, "collisions": 1}) == float("inf")
