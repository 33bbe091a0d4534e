"""Evaluation: the committed policies (short episodes) against the PID, and the output files."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from formation_env.cli import main
from train.evaluate import eval_env_config, evaluate, load_policy, run_episodes

POLICIES = Path(__file__).resolve().parents[2] / "train" / "policies"
COMMITTED = sorted(POLICIES.glob("*.zip"))


def test_evaluate_pid_is_zero_residual():
    pol = load_policy("pid")
    assert pol.action_mode == "residual"
    assert np.all(pol.act(np.ones((3, 33), dtype=np.float32)) == 0)


def test_evaluate_metrics_and_outputs(tmp_path, capsys):
    out = tmp_path / "ev"
    code = main(["evaluate", "--policy", "pid", "--policy", "pid", "--scenario", "reconfiguration", "--episodes", "2",
                 "--duration", "3", "--seeds", "5", "--out", str(out)])
    assert code == 0
    for name in ("results.json", "results.md", "metrics.png", "slot_error.png"):
        assert (out / name).is_file(), name
    rep = json.loads((out / "results.json").read_text())
    assert rep["seeds"] == [5, 6] and rep["wake"] is True and rep["turbulence_sigma_mps"] == 1.0
    a, b = rep["policies"]["pid"]["summary"], rep["policies"]["pid-2"]["summary"]
    assert a == {**b, "wall_s": a["wall_s"]}  # same episodes -> same numbers
    for key in ("rms_slot_error_m", "max_slot_error_m", "time_within_1m_frac", "min_separation_m", "collisions",
                "reconfig_success_rate", "control_effort_rad", "fuel_saving_pct"):
        assert key in a, key
    assert 0.0 <= a["reconfig_success_rate"] <= 1.0
    assert "| RMS slot error (m) |" in (out / "results.md").read_text()
    # never overwritten
    assert main(["evaluate", "--policy", "pid", "--scenario", "reconfiguration", "--episodes", "1", "--duration", "1",
                 "--out", str(out)]) == 2


def test_evaluate_success_definition():
    cfg = eval_env_config("reconfiguration", "residual", turbulence_sigma_mps=0.0)
    eps = run_episodes(lambda o: np.zeros((o.shape[0], 4)), cfg, [0])
    # no turbulence: the thesis run, the PID ends on its final slot
    assert eps[0]["reconfig_success"] and not eps[0]["collision"]
    assert 35.0 < eps[0]["reconfig_time_s"] < 50.0


@pytest.mark.skipif(not COMMITTED, reason="no committed policies")
@pytest.mark.parametrize("path", COMMITTED, ids=[p.stem for p in COMMITTED])
def test_evaluate_committed_policy_short(path, tmp_path):
    meta = json.loads(path.with_suffix(".json").read_text())
    rep = evaluate([str(path), "pid"], scenario=meta["env"]["scenario"], episodes=2, duration_s=5.0,
                   out_dir=tmp_path / "ev", plots=False)
    s = rep["policies"][path.stem]["summary"]
    assert s["collisions"] == 0 and s["crashes"] == 0
    assert math.isfinite(s["rms_slot_error_m"]) and s["rms_slot_error_m"] < 10.0
    assert s["action_rms"] > 0  # it is not the PID
    for key in ("command", "seed", "num_timesteps", "wall_s", "evaluation"):
        assert key in meta, key
