"""``formation-env results``: write docs/results.md, its marl-eval JSON and the README's task table from the
committed records in train/policies/ (every number computed from the records' per-episode columns).
``--check`` writes nothing and exits 1 when a generated file differs from what the command would write.
``--absolute TASK`` flies the best training seed of each of the task's learned methods on 1,000 further held-out
episodes (the absolute metric, train/publish/absolute.py) and writes its record; the page then shows it."""

from __future__ import annotations

import sys


def register(sub) -> None:
    p = sub.add_parser("results", help="write docs/results.md (and its marl-eval JSON, the README's task table) from "
                                       "the committed evaluation records")
    p.add_argument("--check", action="store_true",
                   help="write nothing; exit 1 when a generated file differs from what the records give")
    p.add_argument("--absolute", metavar="TASK",
                   help="fly the best seed of each learned method of TASK (a task whose evaluation protocol "
                        "carries the absolute metric) on 1,000 further held-out episodes and write "
                        "train/policies/TASK_absolute.json (minutes to an hour on 2 cores)")
    p.add_argument("--overwrite", action="store_true", help="with --absolute: replace a method already recorded")
    p.set_defaults(func=run)


def run(args) -> int:
    import importlib.util

    from ..errors import MissingDependencyError

    if importlib.util.find_spec("rliable") is None:
        raise MissingDependencyError('formation-env results needs rliable: pip install -e ".[evaluation]"')
    if args.absolute is not None:
        from train.publish.absolute import ABSOLUTE_TASKS, write_absolute

        if args.absolute not in ABSOLUTE_TASKS:
            raise ValueError(f"--absolute must be one of {list(ABSOLUTE_TASKS)}, got {args.absolute!r}")
        print(f"wrote {write_absolute(args.absolute, overwrite=args.overwrite)}")
    elif args.overwrite:
        raise ValueError("--overwrite goes with --absolute TASK")
    from train.publish.results_page import write_results

    changed = write_results(check=args.check)
    for path in changed:
        print(f"{'differs' if args.check else 'wrote'} {path}")
    if args.check and changed:
        print("formation-env results: the generated files differ from the records; run `formation-env results`",
              file=sys.stderr)
        return 1
    if not changed:
        print("the generated files match the records")
    return 0
