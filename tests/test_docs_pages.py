"""The generated documentation pages (the task pages, the tasks' index and the option tables of
docs/environments.md) are what ``formation-env docs`` writes from the code: a changed task, option or range must
be followed by ``formation-env docs``."""

from __future__ import annotations

from pathlib import Path

from formation_env.cli.docs import SECTIONS, render_pages
from formation_env.tasks import TASKS

REPO = Path(__file__).resolve().parents[1]


def test_the_generated_pages_are_up_to_date():
    stale = [str(p.relative_to(REPO)) for p, text in render_pages(REPO).items()
             if not p.is_file() or p.read_text(encoding="utf-8") != text]
    assert not stale, f"run `formation-env docs` (pages differ: {stale})"


def test_every_task_has_a_page_in_the_template():
    for name in TASKS:
        text = (REPO / "docs" / "tasks" / f"{name}.md").read_text(encoding="utf-8")
        heads = [line[3:] for line in text.splitlines() if line.startswith("## ")]
        assert heads == [s for s in SECTIONS if s in heads] and {"Description", "Reward", "Evaluation protocol",
                                                                 "Results"} <= set(heads), (name, heads)
        assert TASKS[name].gym_id is None or f"`{TASKS[name].gym_id}`" in text


def test_a_task_page_states_each_recipe_against_ppo_from_its_record():
    """The verdict is read off the paired interval at the headline level: better, worse, or no difference shown."""
    from formation_env.cli.docs import task_page

    task = TASKS["close_formation"]

    def record(algo, lo, hi):
        return {"task": "close_formation", "candidate": f"close_formation_{algo}_setpoints",
                "levels": {"sigma_1": {"turbulence_sigma_mps": 1.0, "n_episodes": 100, "candidate_mean": 0.8,
                                       "reference_mean": 0.79, "difference": (lo + hi) / 2, "difference_ci": [lo, hi],
                                       "better": lo > 0},
                           "sigma_0": {"turbulence_sigma_mps": 0.0, "n_episodes": 100, "candidate_mean": 0.99,
                                       "reference_mean": 0.99, "difference": 0.0, "difference_ci": [-1, 1],
                                       "better": False}}}

    page = task_page(task, {}, frozenset({"close_formation"}),
                     [record("sac", 0.004, 0.02), record("recurrent_ppo", -0.01, 0.005), record("td3", -0.05, -0.02)])
    assert "* SAC against PPO" in page and "paired difference +0.012 [+0.004, +0.020]: SAC is better" in page
    assert "* recurrent PPO against PPO" in page and "[-0.010, +0.005]: no difference is shown" in page
    assert "* TD3 against PPO" in page and "PPO is better" in page
    assert "at sigma 1 m/s" in page and "at sigma 0 m/s" not in page  # the headline level only
    assert "Other algorithms against PPO" not in task_page(task, {}, frozenset({"close_formation"}), [])
