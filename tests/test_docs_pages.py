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
