"""``formation-env data``: rebuild the package's cached data and the figure drawn from it. ``residual-table``: the
ELL residual table of pairs (formation_env/verification/residual_table.py); ``optimum TASK``: a task's cached
reference optimum (formation_env/tasks/<TASK>/optimum.py); ``task-versions``: record the fingerprint of every
registered Gymnasium id not yet in formation_env/data/task_versions.json; ``saving-map PATH``: the close-formation
saving map figure."""

from __future__ import annotations

import importlib
from pathlib import Path

from ._args import OneLineArgumentParser, bounded_int

_TASKS_DIR = Path(__file__).resolve().parents[1] / "tasks"


def optimum_units() -> dict[str, str]:
    """{task unit: its optimum module} for every task unit with an ``optimum.py`` (read off the files, so that
    building the parser imports nothing); such a module rewrites its cache with ``write_cache(path)``."""
    return {p.parent.name: f"formation_env.tasks.{p.parent.name}.optimum" for p in sorted(_TASKS_DIR.glob("*/optimum.py"))}


def register(sub) -> None:
    p = sub.add_parser("data", help="rebuild the package's cached data: the residual table, a task's optimum, the "
                                    "task versions table, the saving map figure")
    actions = p.add_subparsers(dest="action", required=True, metavar="ACTION", parser_class=OneLineArgumentParser)

    t = actions.add_parser("residual-table", help="build the ELL residual table of pairs (docs/model/ell.md, "
                                                  "\"Converged saving\"; minutes on 2 cores)")
    t.add_argument("--table", default=None, metavar="PATH",
                   help="where to write it (default the package's formation_env/data table)")
    t.add_argument("--processes", type=bounded_int(1, 64), default=2, help="worker processes, 1..64 (default 2)")
    t.add_argument("--force", action="store_true", help="replace an existing table")
    t.set_defaults(func=run_residual_table)

    o = actions.add_parser("optimum", help="rewrite a task's cached reference optimum")
    units = optimum_units()
    o.add_argument("task", choices=tuple(units), metavar="TASK", help=f"the task unit, one of {list(units)}")
    o.add_argument("--cache", default=None, metavar="PATH", help="where to write it (default the package's cache)")
    o.set_defaults(func=run_optimum)

    v = actions.add_parser("task-versions", help="record the fingerprint of every registered Gymnasium id not yet "
                                                 "in formation_env/data/task_versions.json (an entry is never "
                                                 "rewritten: a changed task needs a new version)")
    v.set_defaults(func=run_task_versions)

    m = actions.add_parser("saving-map", help="draw the close-formation saving map figure (PNG) from the cached map")
    m.add_argument("path", metavar="PATH", help="the PNG to write (e.g. docs/figures/close_formation_map.png)")
    m.set_defaults(func=run_saving_map)


def run_residual_table(args) -> int:
    from ..verification.residual_table import build
    from ..wake.residual import TABLE_PATH

    print(build(args.table or TABLE_PATH, processes=args.processes, force=args.force,
                log=lambda line: print(line, flush=True)))
    return 0


def run_optimum(args) -> int:
    module = importlib.import_module(optimum_units()[args.task])
    if not callable(getattr(module, "write_cache", None)) or not hasattr(module, "CACHE_PATH"):
        raise ValueError(f"{module.__name__} has no cache to rewrite (no write_cache and CACHE_PATH)")
    path = module.write_cache(args.cache or module.CACHE_PATH)
    print(f"wrote {path}")
    return 0


def run_task_versions(args) -> int:
    from ..tasks.versions import record_new_versions

    added = record_new_versions()
    for gid in added:
        print(f"recorded {gid}")
    if not added:
        print("every registered id is already recorded")
    return 0


def run_saving_map(args) -> int:
    from ..plotting.saving_map import plot_map

    path = Path(args.path)
    if path.is_dir():
        raise ValueError(f"saving-map PATH {args.path!r} is a directory; give the PNG file to write")
    print(f"wrote {plot_map(path)}")
    return 0
