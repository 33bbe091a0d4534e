"""Re-flying the first episodes of a committed held-out record (train/policies/*_levels.json) with the committed zip:
the one way the record tests fly a record's episodes again."""

from __future__ import annotations

from pathlib import Path

from train.evaluation.episodes import eval_env_config, run_episodes
from train.evaluation.policy_loader import load_policy

POLICIES = Path(__file__).resolve().parents[2] / "train" / "policies"


def refly(level_rec: dict, task: str, name: str, n: int = 2) -> tuple[list[dict], dict]:
    """The first ``n`` episodes of one level of a record (``by_level[...]``) flown again on ``task`` by the committed
    ``train/policies/<name>.zip`` (through the guard its sidecar names), at the level's turbulence and with the wake
    fidelity the record was made with (records before issue 23 part 7 name none: the nseg-10 lattice). Returns the
    episodes and the policy's recorded columns."""
    cols = level_rec["episodes"][name]
    pol = load_policy(str(POLICIES / f"{name}.zip"))
    cfg = eval_env_config(task, pol.action_mode, turbulence_sigma_mps=level_rec["turbulence_sigma_mps"],
                          wake_fidelity=level_rec.get("wake_fidelity", "lattice"))
    return run_episodes(pol, cfg, cols["seed"][:n]), cols
