"""The committed wake-surfing records (``train/policies/<group>_levels.json`` and the task's
``wake_surfing_ppo_setpoints_evaluation.json``), made as issue 23 part 7 made them: every controller flown once per
setting (task and randomised-leader variant at sigma 0.25, 0 and 1) on the default held-out seeds, its episodes saved
as ``EPISODES_DIR/<scenario>_sigma_<s>/<name>.json``, then each policy group's report
(:func:`train.evaluation.wake_surfing_eval.surfing_report`, what ``python -m train.evaluation.wake_surfing_eval``
runs after flying) from the same episodes, so that the baselines and ceilings are flown once for every group.

    python -m train.publish.wake_surfing_records EPISODES_DIR ZIP [ZIP ...] [--out-dir train/policies] [--overwrite]

Zips are named ``<group>_seed<k>.zip``; flights already saved in EPISODES_DIR are not flown again.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

__all__ = ["SETTINGS", "CEILINGS", "EPISODE_COLUMNS", "fly_setting", "group_levels", "main"]

#: (scenario, turbulence sigma m/s): the task's level first
SETTINGS = (("wake_surfing", 0.25), ("wake_surfing", 0.0), ("wake_surfing", 1.0),
            ("wake_surfing_random_leader", 0.25), ("wake_surfing_random_leader", 0.0),
            ("wake_surfing_random_leader", 1.0))
#: the oracle station-keeper ceilings' margins below the optimum, spans
CEILINGS = (0.0, 0.05)
#: the per-episode columns a levels record keeps
EPISODE_COLUMNS = ("saving", "saving_ratio", "reference_saving", "box_outside_frac", "min_separation_m", "collision")
#: the level kept in full (every episode) in the task group's evaluation record
FULL = ("wake_surfing_ppo_setpoints", "wake_surfing_sigma_0.25")


def _setting_dir(episodes_dir: Path, scenario: str, sigma: float) -> Path:
    return Path(episodes_dir) / f"{scenario}_sigma_{sigma:g}"


def fly_setting(episodes_dir, scenario: str, sigma: float, zips, *, episodes: int = 100, log=print) -> list[str]:
    """Fly the baselines, the ceilings and every policy in ``zips`` on ``episodes`` held-out episodes of one setting,
    each saved once (an existing file is kept); the names flown."""
    from formation_env.io import atomic_write_text

    from ..config import TEST_SEED_BASE
    from ..evaluation.episodes import eval_env_config
    from ..evaluation.wake_surfing_rollout import (es_surfer, fly, oracle_keeper, pid_formation_surfer, pid_surfer,
                                                   sb3_surfer)

    out = _setting_dir(episodes_dir, scenario, sigma)
    out.mkdir(parents=True, exist_ok=True)
    cfg = eval_env_config(scenario, "setpoints", turbulence_sigma_mps=sigma)
    seeds = [TEST_SEED_BASE + i for i in range(episodes)]
    surfers = [pid_surfer(), pid_formation_surfer(), es_surfer(), *(oracle_keeper(m) for m in CEILINGS),
               *(sb3_surfer(str(z)) for z in zips)]
    for s in surfers:
        f = out / f"{s.name}.json"
        if not f.exists():
            eps = fly(s, seeds, config=cfg)
            atomic_write_text(f, json.dumps(eps, default=float))
            log(f"{scenario} sigma {sigma:g} {s.name}: ratio {sum(e['saving_ratio'] for e in eps) / len(eps):.3f}")
    return [s.name for s in surfers]


def _group_report(episodes_dir, scenario: str, sigma: float, group: str) -> tuple[dict, list[str]]:
    from ..evaluation.episodes import eval_env_config
    from ..evaluation.wake_surfing_eval import BASELINE_NAMES, _rounded, surfing_report

    d = _setting_dir(episodes_dir, scenario, sigma)
    names = sorted(p.stem for p in d.glob(f"{group}_seed*.json"))
    if not names:
        raise ValueError(f"no episodes of policy group {group!r} in {d}")
    ceilings = [f"oracle_keeper_margin{m:g}" for m in CEILINGS]
    eps = {n: json.loads((d / f"{n}.json").read_text()) for n in [*BASELINE_NAMES, *names, *ceilings]}
    cfg = eval_env_config(scenario, "setpoints", turbulence_sigma_mps=sigma)
    r = surfing_report(eps, names, scenario=scenario, seeds=[e["seed"] for e in eps["pid"]],
                       randomisation=cfg.randomisation, policy_specs={n: f"train/policies/{n}.zip" for n in names})
    return _rounded(json.loads(json.dumps(r, default=float))), names


def group_levels(episodes_dir, group: str, settings=SETTINGS) -> tuple[dict, dict | None]:
    """``(levels, full)``: the group's levels (``<scenario>_sigma_<s>`` -> summaries of every controller, paired
    comparisons, rliable aggregates and per-episode columns: every controller's for the task group, the policies'
    only for another group) and, for the task group, the full report of its task level (None otherwise)."""
    from formation_env.scenarios import get_scenario

    levels, full = {}, None
    for scenario, sigma in settings:
        r, names = _group_report(episodes_dir, scenario, sigma, group)
        key = f"{scenario}_sigma_{sigma:g}"
        is_full = (group, key) == FULL
        if is_full:
            full = r
        keep = list(r["controllers"]) if group == FULL[0] else names
        levels[key] = {
            "scenario": scenario, "wake_fidelity": get_scenario(scenario).wake_fidelity, "turbulence_sigma_mps": sigma,
            "seeds": [r["seeds"][0], r["seeds"][-1]],
            "summaries": {n: c["summary"] for n, c in r["controllers"].items()},
            "comparisons": r["comparisons"], "seed_spread": r.get("seed_spread"), "aggregates": r.get("aggregates"),
            "episodes": (f"in train/policies/{group}_evaluation.json (every episode in full)" if is_full else
                         {n: {k: [e[k] for e in r["controllers"][n]["episodes"]] for k in EPISODE_COLUMNS}
                          for n in keep}),
            "episode_seeds": [r["seeds"][0], r["seeds"][-1]]}
    return levels, full


def _command(group: str) -> str:
    return (f"python -m train.evaluation.wake_surfing_eval train/policies/{group}_seed{{0,1,2}}.zip --oracle-margins "
            "--oracle-keeper-margins 0 0.05 [--turbulence 0|1] [--scenario wake_surfing_random_leader] --out DIR")


def _write_compact(path: Path, data, overwrite: bool) -> None:
    from formation_env.io import atomic_write_text

    atomic_write_text(path, json.dumps(data, separators=(",", ":")) + "\n", overwrite=overwrite)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m train.publish.wake_surfing_records", description=__doc__.split("\n\n")[0])
    p.add_argument("episodes_dir")
    p.add_argument("zips", nargs="+")
    p.add_argument("--episodes", type=int, default=100)
    p.add_argument("--out-dir", default="train/policies")
    p.add_argument("--overwrite", action="store_true")
    a = p.parse_args(argv)
    if a.episodes < 1:
        print(f"error: --episodes must be >= 1, got {a.episodes}", file=sys.stderr)
        return 2
    missing = [z for z in a.zips if not Path(z).is_file()]
    if missing:
        print(f"error: policy file {missing[0]!r} does not exist", file=sys.stderr)
        return 2
    groups = sorted({Path(z).stem.rsplit("_seed", 1)[0] for z in a.zips})
    try:
        for scenario, sigma in SETTINGS:
            fly_setting(a.episodes_dir, scenario, sigma, a.zips, episodes=a.episodes)
        out = Path(a.out_dir)
        for group in groups:
            levels, full = group_levels(a.episodes_dir, group)
            if full is not None:
                full["command"] = _command(group).replace(
                    " [--turbulence 0|1] [--scenario wake_surfing_random_leader]", "")
                _write_compact(out / f"{group}_evaluation.json", full, a.overwrite)
            _write_compact(out / f"{group}_levels.json", {
                "command": _command(group), "levels": levels,
                "about": f"Held-out wake-surfing evaluation of {group} at three turbulence levels (0.25: the task's; 0; "
                         "1) on the task and its randomised-leader variant: per setting every controller's summary, "
                         "the paired comparisons (saving ratio, 95 % bootstrap), the rliable aggregates and per-episode "
                         "columns. Each controller flew train.evaluation.wake_surfing_rollout.fly once per setting on "
                         "the default held-out seeds (train.publish.wake_surfing_records); the statistics are "
                         "train.evaluation.wake_surfing_eval.surfing_report's. The converged wake; the extremum "
                         "seeker with the station keeper flying its set-point."}, a.overwrite)
            print(f"wrote {group}_levels.json")
    except (ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
