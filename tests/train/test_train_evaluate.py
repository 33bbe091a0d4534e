"""Evaluation: the committed policies (short episodes) against the PID, the output files, the
intervals, paired comparisons and seed groups, and the validation episodes of training."""

import inspect
import json
import math
import sys
import types
from pathlib import Path

import numpy as np
import pytest

import train.evaluation.evaluate as ev
from formation_env.cli import main
from train.config import TEST_SEED_BASE, VALIDATION_SEED_BASE
from formation_env.rollout import ZeroPolicy
from train.evaluation.evaluate import EvalPolicy, eval_env_config, evaluate, load_policy, run_episodes

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
    eps = run_episodes(ZeroPolicy(), cfg, [0])
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


# ------------------------------------------------------------------ intervals, comparisons, seed groups
class _FakePIDFormation:
    """Stands in for agents.pid_formation.PIDFormation: zero residual (so it flies the thesis PID), and
    it checks that run_episodes resets it with the right number of rows before acting."""

    instances = []

    def __init__(self):
        self.action_mode, self.control_hz, self.resets, self.rows = "residual", 10.0, [], None
        _FakePIDFormation.instances.append(self)

    def reset(self, n_rows: int) -> None:
        self.resets.append(n_rows)
        self.rows = n_rows

    def act(self, obs):
        assert self.rows == obs.shape[0], "act before reset, or with another number of rows"
        return np.zeros((obs.shape[0], 4), dtype=np.float32)


@pytest.fixture
def fake_pid_formation(monkeypatch):
    mod = types.ModuleType("agents.pid_formation")
    mod.PIDFormation = _FakePIDFormation
    monkeypatch.setitem(sys.modules, "agents.pid_formation", mod)
    _FakePIDFormation.instances.clear()
    return _FakePIDFormation


@pytest.fixture
def fake_candidates(seeded_candidates):
    """Policies 'cand_seed<k>': the PID plus a constant throttle residual of 0.2 k (a different
    controller per seed)."""
    seeded_candidates(0.2)


def test_evaluate_defaults_to_100_episodes_and_pid_formation_is_a_policy(fake_pid_formation):
    assert inspect.signature(evaluate).parameters["episodes"].default == 100
    pol = load_policy("pid_formation")
    assert (pol.name, pol.action_mode, pol.control_hz) == ("pid_formation", "residual", 10.0)
    assert pol.reset is not None


def test_evaluate_intervals_comparisons_and_groups(tmp_path, fake_pid_formation, fake_candidates):
    rep = evaluate(["pid", "pid_formation", "cand_seed1", "cand_seed2", "pid"], scenario="reconfiguration",
                   episodes=3, duration_s=2.0, n_boot=2000, out_dir=tmp_path / "ev", plots=False,
                   groups={"first": ["cand_seed1"]})
    pols = rep["policies"]
    assert list(pols) == ["pid", "pid_formation", "cand_seed1", "cand_seed2", "pid-2"]
    assert fake_pid_formation.instances[0].resets == [3]  # 3 formations x 1 follower, reset once
    assert pols["pid_formation"]["policy"] == "pid_formation" and pols["pid"]["policy"] == "pid"
    s = pols["cand_seed1"]["summary"]
    lo, hi = s["rms_slot_error_m_ci"]
    assert lo <= s["rms_slot_error_m"] <= hi
    assert s["collision_rate"] == s["collisions"] / 3 and len(s["collision_rate_ci"]) == 2
    assert s["reconfig_success_rate_ci"][0] <= s["reconfig_success_rate"] <= s["reconfig_success_rate_ci"][1]
    assert s["min_separation_m_p05"] >= s["min_separation_m"]
    # comparisons: every non-baseline policy against both baselines, pid_formation against pid
    comps = rep["comparisons"]
    assert set(comps) == {"cand_seed1", "cand_seed2", "pid_formation"}
    assert set(comps["cand_seed1"]) == {"pid", "pid_formation"} and set(comps["pid_formation"]) == {"pid"}
    for name in ("cand_seed1", "cand_seed2"):
        c = comps[name]["pid"]["rms_slot_error_m"]
        assert c["n"] == 3
        assert c["mean_reduction"] == pytest.approx(pols["pid"]["summary"]["rms_slot_error_m"]
                                                    - pols[name]["summary"]["rms_slot_error_m"])
        assert c["mean_reduction_ci"][0] <= c["mean_reduction"] <= c["mean_reduction_ci"][1]
        assert c["n_better"] + c["n_worse"] + c["n_ties"] == 3
        assert "reconfig_success" in comps[name]["pid"]
    same = comps["pid_formation"]["pid"]["rms_slot_error_m"]  # the fake flies the PID exactly
    assert same["mean_reduction"] == 0.0 and tuple(same["mean_reduction_ci"]) == (0.0, 0.0)
    assert same["n_ties"] == 3 and same["sign_test_p"] == 1.0
    # seed groups: automatic for <name>_seed<k>, and given explicitly
    assert set(rep["groups"]) == {"cand", "first"}
    g = rep["groups"]["cand"]
    assert g["policies"] == ["cand_seed1", "cand_seed2"] and g["n_seeds"] == 2
    per_seed = [pols[n]["summary"]["rms_slot_error_m"] for n in g["policies"]]
    spread = g["summary"]["rms_slot_error_m"]
    assert spread["mean"] == pytest.approx(np.mean(per_seed)) and spread["std"] == pytest.approx(np.std(per_seed, ddof=1))
    assert (spread["min"], spread["max"], spread["n"]) == (min(per_seed), max(per_seed), 2)
    gc = g["comparisons"]["pid"]["rms_slot_error_m"]
    assert gc["mean_reduction"] == pytest.approx(pols["pid"]["summary"]["rms_slot_error_m"] - np.mean(per_seed))
    assert rep["groups"]["first"]["n_seeds"] == 1
    # results.json keeps policies.<name>.summary / .episodes and adds the rest
    saved = json.loads((tmp_path / "ev" / "results.json").read_text())
    assert saved["policies"]["cand_seed2"]["summary"]["rms_slot_error_m_ci"] == \
        list(pols["cand_seed2"]["summary"]["rms_slot_error_m_ci"])
    assert len(saved["policies"]["pid"]["episodes"]) == 3
    assert saved["comparisons"]["cand_seed1"]["pid_formation"]["rms_slot_error_m"]["n"] == 3
    assert saved["groups"]["cand"]["comparisons"]["pid"]["rms_slot_error_m"]["mean_reduction"] == pytest.approx(
        gc["mean_reduction"])
    md = (tmp_path / "ev" / "results.md").read_text()
    assert "| collisions | 0/3 |" in md and "reduction of the median" in md and "cand (mean of 2 seeds)" in md


def test_evaluate_groups_must_name_evaluated_policies():
    with pytest.raises(ValueError, match="unknown policy name"):
        evaluate(["pid"], scenario="formation_keeping", episodes=1, groups={"g": ["nope_seed0"]})


def test_cli_episodes_and_seeds(tmp_path, capsys, monkeypatch):
    code = main(["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--episodes", "5", "--seeds", "1",
                 "2", "3", "--out", str(tmp_path / "a")])
    err = capsys.readouterr().err
    assert code == 2 and "--episodes 5" in err and "3 seeds" in err and "--seeds" in err
    assert not (tmp_path / "a").exists()
    calls = []

    def fake(policies, **kw):
        calls.append((policies, kw))
        return {"table_markdown": "", "comparison_markdown": "", "groups_markdown": ""}

    monkeypatch.setattr(ev, "evaluate", fake)
    for argv, episodes in ((["--seeds", "1", "2", "3"], 3), ([], 100), (["--episodes", "4", "--seeds", "7"], 4),
                           (["--episodes", "2", "--seeds", "1", "2"], 2)):
        assert main(["evaluate", "--policy", "pid_formation", "--scenario", "formation_keeping", "--no-plots",
                     "--out", str(tmp_path / "b"), *argv]) == 0
        assert calls[-1][0] == ["pid_formation"] and calls[-1][1]["episodes"] == episodes


def test_validation_episodes_are_drawn_like_the_test_set():
    from train.sb3.callbacks import build_callbacks as _callbacks
    from train.sb3.config import TrainConfig

    env_kwargs = {"wake": False, "control_hz": 10.0, "randomisation": {"turbulence_sigma_mps": 0.3, "initial_offset_m": 1.0}}
    cfg = TrainConfig(scenario="reconfiguration", algo="ppo", action_mode="residual", seed=0, n_timesteps=100,
                      env_kwargs=env_kwargs)
    assert cfg.eval_episodes == 32
    logs = []
    _, val = _callbacks(cfg, Path("unused"), {"start_steps": 0, "total": 100}, logs.append, True)
    assert val.config == eval_env_config("reconfiguration", "residual")  # the test set's conditions
    assert val.config.duration_s is None and val.config.wake is True
    assert val.config.randomisation.turbulence_sigma_mps == 1.0 and val.config.randomisation.initial_offset_m == 0.0
    assert val.seeds == [VALIDATION_SEED_BASE + i for i in range(32)]
    assert max(val.seeds) < TEST_SEED_BASE and not logs
    # shorter training episodes (development runs, the tests): the same episodes, cut to that length
    cfg = TrainConfig(scenario="reconfiguration", algo="ppo", action_mode="residual", seed=0, n_timesteps=100,
                      eval_episodes=2, env_kwargs={**env_kwargs, "duration_s": 3.0})
    _, val = _callbacks(cfg, Path("unused"), {"start_steps": 0, "total": 100}, logs.append, True)
    assert val.config == eval_env_config("reconfiguration", "residual", duration_s=3.0)
    assert any("< 32" in m for m in logs) and any("cut to 3 s" in m for m in logs)


def test_real_pid_formation_when_present():
    pytest.importorskip("agents.pid_formation")
    pol = load_policy("pid_formation")
    assert pol.name == "pid_formation" and pol.action_mode in ("surfaces", "residual", "setpoints")
    assert pol.control_hz > 0 and callable(pol.reset)
