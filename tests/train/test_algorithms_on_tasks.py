"""SAC and recurrent PPO on the headline tasks' recipes (train/hyperparams/sac.yml, recurrent_ppo.yml): vee5 trains
every follower as a row of the VecEnv with one shared policy, close_formation with the separation guard in the loop;
the policy flies through ``load_policy`` as it trained (tiny runs, a few hundred steps)."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")


@pytest.mark.parametrize("scenario", ["vee5", "close_formation"])
@pytest.mark.parametrize("algo", ["sac", "recurrent_ppo"])
def test_task_recipe_trains_and_flies(tmp_path, tiny, algo, scenario):
    if algo == "recurrent_ppo":
        pytest.importorskip("sb3_contrib")
    from train.evaluation.episodes import eval_env_config, run_episodes
    from train.evaluation.policy_loader import load_policy
    from train.sb3.config import TrainConfig, load_hyperparams
    from train.sb3.train import build_model, make_train_env, train

    over = {**tiny(algo), "n_formations": 1}
    out = tmp_path / "run"
    steps = 128
    s = train(scenario=scenario, algo=algo, seed=1, steps=steps, out_dir=out, overrides=over, progress_bar=False,
              log=lambda m: None)
    assert s["num_timesteps"] >= steps
    meta = json.loads((out / "final_model.json").read_text())
    rows = 4 if scenario == "vee5" else 1
    # the task's recipe: close_formation's guard in the loop (and in the published policy), vee5's priced collisions
    params = load_hyperparams(algo, scenario)
    assert bool(meta.get("action_guard")) == (scenario == "close_formation") == bool(params.get("action_guard"))
    assert meta["task"] == scenario and meta["departures"] == {"duration_s": 3.0}
    if scenario == "vee5":
        assert params["selection_collision_cost"] == 2.0
    cfg = TrainConfig.from_hyperparams({**params, **over, "env_kwargs": {**params["env_kwargs"], "duration_s": 3.0}},
                                       scenario=scenario, algo=algo, action_mode="setpoints", seed=1)
    env = make_train_env(cfg, 1)
    assert env.num_envs == rows  # every follower a row of one VecEnv, one shared policy
    assert build_model(cfg, env).n_envs == rows
    pol = load_policy(str(out / "final_model.zip"))
    assert (pol.reset is not None) == (algo == "recurrent_ppo")
    eps = run_episodes(pol, eval_env_config(scenario, "setpoints", duration_s=1.0), [3, 4])
    assert len(eps) == 2 and all(np.isfinite(e["rms_slot_error_m"]) for e in eps)


def test_the_committed_runs_script_trains_each_recipe_with_its_files_budget():
    """train/committed_runs_65.sh: 2 algorithms x 3 tasks x 3 seeds, each command's --steps the hyperparameter
    file's n_timesteps, each run written to its own directory."""
    import os
    import subprocess
    from pathlib import Path

    from train.sb3.config import load_hyperparams

    script = Path(__file__).resolve().parents[2] / "train" / "committed_runs_65.sh"
    out = subprocess.run(["bash", str(script), "RUNS"], capture_output=True, text=True, check=True,
                         env={**os.environ, "PRINT": "1", "FE": "formation-env"}).stdout.splitlines()
    assert len(out) == 18 and len(set(out)) == 18
    seen = set()
    for line in out:
        words = line.split()
        arg = {k: words[words.index(k) + 1] for k in ("--scenario", "--algo", "--steps", "--seed", "--out")}
        task, algo, seed = arg["--scenario"], arg["--algo"], int(arg["--seed"])
        assert int(arg["--steps"]) == load_hyperparams(algo, task)["n_timesteps"], line
        assert arg["--out"] == f"RUNS/{task}_{algo}_seed{seed}"
        seen.add((algo, task, seed))
    assert seen == {(a, t, k) for a in ("sac", "recurrent_ppo") for t in ("close_formation", "vee5", "reconfiguration")
                    for k in range(3)}
