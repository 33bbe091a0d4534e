"""docs/results.md, its marl-eval JSON and the README's task table are exactly what `formation-env results` writes
from the committed records (no hand-typed result anywhere)."""

from __future__ import annotations

import json

import pytest

pytest.importorskip("rliable")

from train.publish import results_page as rp  # noqa: E402


def test_the_generated_files_equal_what_the_records_give():
    changed = rp.write_results(check=True)
    assert not changed, f"{[str(p) for p in changed]} differ from the records: run `formation-env results`"


def test_every_task_with_records_is_on_the_page_with_its_version():
    from formation_env.tasks import get_task

    page = rp.PAGE.read_text(encoding="utf-8")
    for src in rp.RECORDS:
        task = get_task(src.task)
        assert f"## {task.name}" in page and f"`{task.gym_id}`" in page
        assert src.file in page


def test_a_changed_record_changes_the_page(tmp_path, monkeypatch):
    src = next(s for s in rp.RECORDS if s.task == "close_formation")
    data = json.loads((rp.POLICIES / src.file).read_text())
    node = data
    for key in src.path:
        node = node[key]
    name = next(n for n in node if n not in rp.CLASSICAL)
    col = rp._metric_key(rp._columns(node[name]), "harvest_ratio")
    node[name][col] = [v * 0.5 for v in node[name][col]]
    (tmp_path / src.file).write_text(json.dumps(data))
    changed = rp.collect((src,), policies=tmp_path)
    original = rp.collect((src,))
    page_changed, _ = rp.results_markdown(changed)
    page_original, _ = rp.results_markdown(original)
    assert page_changed != page_original


def test_the_absolute_metric_flies_each_methods_best_seed():
    """The seed each absolute record flew is the one the committed 100-episode record chooses (its headline
    estimator), on seeds disjoint from those episodes: a record left behind by a changed record fails here."""
    from formation_env.tasks import get_task
    from train.publish import absolute as ab

    data = rp.collect()
    recorded = [t for t in ab.ABSOLUTE_TASKS if ab.absolute_path(t).is_file()]
    assert recorded, "no absolute record committed"
    for name in recorded:
        task = get_task(name)
        rec = json.loads(ab.absolute_path(name).read_text())["records"]
        chosen = ab.best_seeds(name, data)
        assert set(rec) <= set(chosen)
        for group, r in rec.items():
            assert r["policy"] == chosen[group]["policy"]
            assert r["n_episodes"] == ab.ABSOLUTE_EPISODES == len(r["episodes"]["seed"])
            assert r["seeds"][0] == task.evaluation.seed_base + ab.ABSOLUTE_SEED_OFFSET
            assert r["task_version"] == task.version
        # the choice: the best estimate among the method's seeds
        level = data[name][task.evaluation.headline_level]
        for group, c in chosen.items():
            values = []
            for run, cols in level["runs"][group].items():
                x = cols[rp._metric_key(cols, task.evaluation.metric)]
                values.append(ab._point(x, c["estimator"]))
            best = max(values) if task.evaluation.higher_is_better else min(values)
            assert c["value"] == pytest.approx(best, abs=1e-6)


def test_the_catalogue_is_the_tasks_own_records():
    """Each task declares its committed records (EvaluationProtocol.records): the catalogue holds exactly them, one
    source per level, and a record that is not a RecordFile is refused with the value named."""
    from formation_env.tasks import TASKS, EvaluationProtocol, RecordFile

    declared = [(t.name, s, r.file) for t in TASKS.values() for r in t.evaluation.records for s in r.levels]
    assert [(s.task, s.sigma, s.file) for s in rp.RECORDS] == declared
    assert RecordFile("x.json", ("by_level", "sigma_{sigma}", "episodes")).keys_at(1.5) == ("by_level", "sigma_1.5",
                                                                                            "episodes")
    with pytest.raises(ValueError, match="RecordFile objects, got 'x.json'"):
        EvaluationProtocol(records=("x.json",))


def test_the_committed_ppo_evaluations_are_the_tasks_declarations():
    # publish recompute and publish committed read the tasks' declarations (EvaluationProtocol.ppo_record_score):
    # each declared record exists, its score is one the aggregates know, and no other such record is left out
    import dataclasses

    from formation_env.tasks import TASKS, EvaluationProtocol
    from train.evaluation.aggregates import SCORES
    from train.publish import publish, recompute, report_committed

    assert set(recompute.TASKS) == {n for n, t in TASKS.items() if t.evaluation.ppo_record_score}
    on_disk = {p.name[: -len("_ppo_setpoints_evaluation.json")]
               for p in publish.POLICIES.glob("*_ppo_setpoints_evaluation.json")}
    assert set(recompute.TASKS) == on_disk
    assert all(recompute.HEADLINE[t] in SCORES for t in recompute.TASKS)
    assert set(report_committed.TASKS) == {t for t in recompute.TASKS if TASKS[t].evaluator is None}
    with pytest.raises(ValueError, match="ppo_record_score must be a score name or None, got 3"):
        dataclasses.replace(EvaluationProtocol(), ppo_record_score=3)
