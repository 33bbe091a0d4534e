"""train.publish.records (for wake_surfing, the task with records of its own evaluation): a group's levels from saved per-controller episodes (the baselines flown once
for every group), the per-episode columns and the summaries agreeing, the task group's level kept in full, and bad
input refused with one line."""

import json

import numpy as np
import pytest

from formation_env.cli import main
from formation_env.tasks import get_task
from train.publish.records import group_levels

EPISODE_COLUMNS = get_task("wake_surfing").evaluator.records.episode_columns

CONTROLLERS = ("pid", "pid_formation", "extremum_seeking", "oracle_keeper_margin0", "oracle_keeper_margin0.05")


def _episodes(rng, level: float, n: int = 12) -> list[dict]:
    out = []
    for i in range(n):
        ratio = float(np.clip(level + 0.05 * rng.standard_normal(), 0.0, 1.0))
        out.append({"seed": 20000000000 + i, "duration_s": 90.0, "saving": 0.56 * ratio, "saving_measured": 0.56 * ratio,
                    "reference_saving": 0.56, "saving_ratio": ratio, "time_to_80_s": float("nan") if ratio < 0.8 else 3.0,
                    "drag_saving_pct_ell": 5.0 * ratio, "drag_saving_pct_6dof": 5.5 * ratio, "box_outside_frac": 0.0,
                    "box_outside_longest_s": 0.0, "min_separation_m": 3.0, "collision": bool(i == 0 and level < 0.2),
                    "crashed": False, "crosswind_mps": 1.0, "leader_mass_kg": 10.5, "leader_airspeed_mps": 25.0,
                    "reference_factor": 1.0})
    return out


@pytest.mark.parametrize("group", ["wake_surfing_ppo_setpoints", "other_group"])
def test_group_levels_from_saved_episodes(tmp_path, group):
    rng = np.random.default_rng(0)
    d = tmp_path / "wake_surfing_sigma_0.25"
    d.mkdir()
    levels = {"pid": 0.1, "pid_formation": 0.12, "extremum_seeking": 0.4, "oracle_keeper_margin0": 0.86,
              "oracle_keeper_margin0.05": 0.75, f"{group}_seed0": 0.93, f"{group}_seed1": 0.95}
    for name, level in levels.items():
        (d / f"{name}.json").write_text(json.dumps(_episodes(rng, level)))
    out, full = group_levels("wake_surfing", tmp_path, group, settings=(("wake_surfing", 0.25),))
    lv = out["wake_surfing_sigma_0.25"]
    assert lv["wake_fidelity"] == "converged" and lv["seeds"] == [20000000000, 20000000011]
    assert set(lv["summaries"]) == set(levels)
    for name in (f"{group}_seed0", f"{group}_seed1"):
        assert lv["comparisons"][name]["extremum_seeking"]["saving_ratio"]["mean_gain"] > 0.4
    if group == "wake_surfing_ppo_setpoints":  # the task group's task level: every episode in the evaluation record
        assert isinstance(lv["episodes"], str) and full is not None
        assert set(full["controllers"]) == set(levels)
    else:  # another group keeps its policies' columns, the summaries are their means
        assert full is None and set(lv["episodes"]) == {f"{group}_seed0", f"{group}_seed1"}
        cols = lv["episodes"][f"{group}_seed1"]
        assert set(cols) == set(EPISODE_COLUMNS)
        assert lv["summaries"][f"{group}_seed1"]["saving_ratio"] == pytest.approx(np.mean(cols["saving_ratio"]), abs=1e-5)
    with pytest.raises(ValueError, match="no episodes of policy group"):
        group_levels("wake_surfing", tmp_path, "absent_group", settings=(("wake_surfing", 0.25),))


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert main(["publish", "records", "wake_surfing", str(tmp_path), str(tmp_path / "none_seed0.zip")]) == 2
    with pytest.raises(SystemExit) as exc:  # argparse's own exit, after its one line
        main(["publish", "records", "wake_surfing", str(tmp_path), str(tmp_path / "none_seed0.zip"), "--episodes", "0"])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and "does not exist" in err[0] and "--episodes" in err[1] and "Traceback" not in "".join(err)
