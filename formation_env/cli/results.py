"""``formation-env results``: write docs/results.md, its marl-eval JSON and the README's task table from the
committed records in train/policies/ (every number computed from the records' per-episode columns).
``--check`` writes nothing and exits 1 when a generated file differs from what the command would write."""

from __future__ import annotations

import sys


def register(sub) -> None:
    p = sub.add_parser("results", help="write docs/results.md (and its marl-eval JSON, the README's task table) from "
                                       "the committed evaluation records")
    p.add_argument("--check", action="store_true",
                   help="write nothing; exit 1 when a generated file differs from what the records give")
    p.set_defaults(func=run)


def run(args) -> int:
    import importlib.util

    from ..errors import MissingDependencyError

    if importlib.util.find_spec("rliable") is None:
        raise MissingDependencyError('formation-env results needs rliable: pip install -e ".[evaluation]"')
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
