"""Package layering (issue 14): ``formation_env`` imports neither ``agents`` nor ``train`` (only the
console commands of ``formation_env.cli`` import ``train``, lazily); ``agents`` does not import
``train``; no import cycle between the top-level packages, between formation_env's subpackages, nor between
any two modules of formation_env, agents and train; no private name (``_x``) imported across a package boundary
(formation_env, agents, train and their subpackages); files stay small.

The static checks read the sources with :mod:`ast` and count every import: module level, inside
functions, ``importlib.import_module("...")`` / ``__import__("...")`` with a literal name."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
import textwrap
from functools import lru_cache
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
TOP_PACKAGES = ("formation_env", "agents", "train")
MAX_LINES = 500


# ---------------------------------------------------------------- AST helpers

def _module_name(path: Path) -> str:
    parts = list(path.relative_to(REPO).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _py_files(package: str) -> list[Path]:
    return sorted(p for p in (REPO / package).rglob("*.py") if "__pycache__" not in p.parts)


def _scan(source: str, module: str, is_package: bool, filename: str = "<src>") -> list[tuple[str, int, bool]]:
    """(absolute imported name, line, at import time) for every import in ``source``: ``from a import
    b`` gives both ``a`` and ``a.b`` (b may be a submodule); relative imports are resolved against
    ``module``; "at import time" is False inside a function body."""
    package = module.split(".") if is_package else module.split(".")[:-1]
    found: list[tuple[str, int, bool]] = []

    def visit(node, top: bool) -> None:
        if isinstance(node, ast.Import):
            found.extend((a.name, node.lineno, top) for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[:len(package) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module
            found.append((name, node.lineno, top))
            found.extend((f"{name}.{a.name}", node.lineno, top) for a in node.names if a.name != "*")
        elif (isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant)
              and isinstance(node.args[0].value, str)):
            func = node.func
            fname = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
            if fname in ("import_module", "__import__"):
                found.append((node.args[0].value, node.lineno, top))
        inner = top and not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
        for child in ast.iter_child_nodes(node):
            visit(child, inner)

    visit(ast.parse(source, filename), True)
    return found


@lru_cache(maxsize=None)
def _imports(path: Path) -> tuple[tuple[str, int, bool], ...]:
    return tuple(_scan(path.read_text(encoding="utf-8"), _module_name(path), path.name == "__init__.py", str(path)))


def _top(name: str) -> str:
    return name.split(".")[0]


def _where(path: Path, line: int) -> str:
    return f"{path.relative_to(REPO).as_posix()}:{line}"


def _cycles(edges: dict[str, dict[str, list[str]]]) -> list[list[str]]:
    """Strongly connected components with more than one node (Tarjan), each sorted."""
    index, low, stack, on_stack, out = {}, {}, [], set(), []
    nodes = sorted(set(edges) | {d for e in edges.values() for d in e})

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges.get(v, {})):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in nodes:
        if v not in index:
            visit(v)
    return sorted(out)


def _describe(cycles, edges) -> str:
    lines = []
    for comp in cycles:
        lines.append(" <-> ".join(comp))
        for a in comp:
            for b in comp:
                if b in edges.get(a, {}):
                    lines.append(f"    {a} -> {b}: {', '.join(edges[a][b])}")
    return "\n".join(lines)


# ---------------------------------------------------------------- (a) shadowing user files

SMOKE = textwrap.dedent("""
    import sys, os
    assert sys.path[0] in ("", os.getcwd()), sys.path[:2]
    import numpy as np
    import gymnasium as gym
    import formation_env
    from formation_env.envs import GYM_IDS

    def steps(env_step, sample, n=3):
        for _ in range(n):
            env_step(sample())

    # PettingZoo parallel env
    env = formation_env.parallel_env("formation_keeping")
    obs, infos = env.reset(seed=0)
    assert set(obs) == set(env.agents)
    for _ in range(3):
        env.step({a: np.zeros(env.action_space(a).shape, np.float32) for a in env.agents})
    env.close()

    # PettingZoo AEC env
    aec = formation_env.env("formation_keeping")
    aec.reset(seed=0)
    for _ in range(3 * len(aec.possible_agents)):
        agent = aec.agent_selection
        done = aec.terminations[agent] or aec.truncations[agent]
        aec.step(None if done else aec.action_space(agent).sample())
    aec.close()

    # every Gymnasium id the package registers
    ids = sorted(i for i in gym.registry if i.startswith("formation_env/"))
    assert ids and set(ids) == set(GYM_IDS), (ids, sorted(GYM_IDS))
    for env_id in ids:
        genv = gym.make(env_id)
        genv.reset(seed=0)
        genv.action_space.seed(0)
        for _ in range(3):
            genv.step(genv.action_space.sample())
        genv.close()

    # vector envs (SB3 VecEnv and Gymnasium VectorEnv), a small batch
    from formation_env.envs.vector import FormationVecEnv, FormationVectorEnv
    venv = FormationVecEnv(2, scenario="formation_keeping", seed=0)
    venv.reset()
    for _ in range(3):
        venv.step(np.zeros((venv.num_envs,) + venv.action_space.shape, np.float32))
    venv.close()
    vec = FormationVectorEnv(2, scenario="formation_keeping", seed=0)
    vec.reset(seed=0)
    for _ in range(3):
        vec.step(vec.action_space.sample())
    vec.close()

    for name in ("agents", "train"):  # the user's files, never the project's packages
        mod = sys.modules.get(name)
        assert mod is None or os.path.dirname(os.path.abspath(mod.__file__)) == os.getcwd(), mod
    print("LAYERING-OK", len(ids))
""")


def test_envs_work_beside_user_files_named_agents_and_train(tmp_path):
    for name in ("agents", "train"):
        (tmp_path / f"{name}.py").write_text('raise ImportError("user file shadowing")\n')
    env = dict(os.environ)
    # the project after the user's directory (the -c script puts the cwd first on sys.path)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(REPO), env.get("PYTHONPATH", "")) if p)
    env.setdefault("MPLBACKEND", "Agg")
    r = subprocess.run([sys.executable, "-c", SMOKE], cwd=tmp_path, env=env, capture_output=True, text=True,
                       timeout=900)
    assert r.returncode == 0, f"stdout:\n{r.stdout[-3000:]}\nstderr:\n{r.stderr[-6000:]}"
    assert "LAYERING-OK" in r.stdout


# ---------------------------------------------------------------- (b) what formation_env imports

def test_formation_env_never_imports_agents():
    bad = [f"{_where(p, line)} imports {name}" for p in _py_files("formation_env")
           for name, line, _ in _imports(p) if _top(name) == "agents"]
    assert not bad, "formation_env must not import agents (the control law is formation_env.control):\n" + \
        "\n".join(bad)


def test_only_the_cli_imports_train_and_only_lazily():
    bad = []
    for p in _py_files("formation_env"):
        in_cli = p.relative_to(REPO / "formation_env").parts[0] == "cli"
        for name, line, top in _imports(p):
            if _top(name) != "train":
                continue
            if not in_cli:
                bad.append(f"{_where(p, line)} imports {name} (only formation_env/cli may import train)")
            elif top:
                bad.append(f"{_where(p, line)} imports {name} at module level (import it inside the command)")
    assert not bad, "\n".join(bad)


def test_the_ast_scan_sees_every_import_form():
    """The scanner itself: plain, from-, relative, nested, try-guarded and importlib forms."""
    src = ("import agents.fcs\n"
           "from .. import io\n"
           "def f():\n    from agents import run\n    import importlib\n"
           "    importlib.import_module('train.train')\n"
           "try:\n    from train import evaluate\nexcept ImportError:\n    pass\n"
           "class C:\n    from ..control import policy\n")
    found = {(n, top) for n, _, top in _scan(src, "formation_env.report.builder", False)}
    assert {("agents.fcs", True), ("agents", False), ("agents.run", False), ("train.train", False),
            ("train", True), ("train.evaluate", True), ("formation_env.io", True),
            ("formation_env.control.policy", True)} <= found
    assert _unit("formation_env.control.policy") == "formation_env.control"
    assert _unit("formation_env.io") == "formation_env.io" and _unit("formation_env") is None


# ---------------------------------------------------------------- (c) no import cycles

def _top_level_edges() -> dict[str, dict[str, list[str]]]:
    edges: dict[str, dict[str, list[str]]] = {}
    for pkg in TOP_PACKAGES:
        for p in _py_files(pkg):
            cli = pkg == "formation_env" and p.relative_to(REPO / pkg).parts[0] == "cli"
            for name, line, _ in _imports(p):
                dst = _top(name)
                if dst == pkg or dst not in TOP_PACKAGES:
                    continue
                if cli and dst == "train":  # the console entry point runs the training code (lazily)
                    continue
                lst = edges.setdefault(pkg, {}).setdefault(dst, [])
                if _where(p, line) not in lst:
                    lst.append(_where(p, line))
    return edges


def test_top_level_packages_are_layered():
    edges = _top_level_edges()
    for src, dst in (("formation_env", "agents"), ("formation_env", "train"), ("agents", "train")):
        assert dst not in edges.get(src, {}), f"{src} imports {dst} at {', '.join(edges[src][dst])}"
    cycles = _cycles(edges)
    assert not cycles, "import cycle between top-level packages:\n" + _describe(cycles, edges)


def _unit(module: str) -> str | None:
    """formation_env.<sub>[...] -> formation_env.<sub> (a subpackage or a top-level module);
    None for the package root (its __init__ is the public facade) and for non-modules."""
    parts = module.split(".")
    if parts[0] != "formation_env" or len(parts) < 2:
        return None
    sub = REPO / "formation_env" / parts[1]
    if sub.is_dir() or sub.with_suffix(".py").is_file():
        return ".".join(parts[:2])
    return None


def _subpackage_edges() -> dict[str, dict[str, list[str]]]:
    edges: dict[str, dict[str, list[str]]] = {}
    for p in _py_files("formation_env"):
        src = _unit(_module_name(p))
        if src is None:
            continue
        for name, line, _ in _imports(p):
            dst = _unit(name)
            if dst is not None and dst != src:
                where = _where(p, line)
                lst = edges.setdefault(src, {}).setdefault(dst, [])
                if where not in lst:
                    lst.append(where)
    return edges


def test_report_does_not_import_the_cli():
    edges = _subpackage_edges()
    assert "formation_env.cli" not in edges.get("formation_env.report", {}), \
        edges["formation_env.report"]["formation_env.cli"]
    callers = sorted(s for s, d in edges.items() if "formation_env.cli" in d)
    assert not callers, f"only the console entry point may import formation_env.cli: {callers}"


def test_cycle_finder_finds_cycles():
    edges = {"a": {"b": ["x"]}, "b": {"c": ["y"]}, "c": {"a": ["z"]}, "d": {"a": ["w"]}}
    assert _cycles(edges) == [["a", "b", "c"]]
    assert _cycles({"a": {"b": ["x"]}}) == []


def test_no_cycle_between_formation_env_subpackages():
    """Edges formation_env.<sub> -> formation_env.<sub2> from every import (module or function level)."""
    edges = _subpackage_edges()
    cycles = _cycles(edges)
    assert not cycles, ("import cycles between formation_env subpackages (edge: importing file:line); "
                        "to be decided (see issue 14):\n" + _describe(cycles, edges))


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for pkg in TOP_PACKAGES for p in _py_files(pkg)}


def _module_edges() -> dict[str, dict[str, list[str]]]:
    """Edges module -> module between the modules of formation_env, agents and train, from every import (module or
    function level); ``from a import b`` is an edge to ``a.b`` where that is a module, else to ``a``. A module's
    import of its own package (``__init__``) is left out: the package runs it first anyway."""
    modules = _modules()
    edges: dict[str, dict[str, list[str]]] = {}
    for src, p in modules.items():
        for name, line, _ in _imports(p):
            dst = name
            while dst and dst not in modules:
                dst = dst.rpartition(".")[0]
            if not dst or dst == src or src.startswith(dst + "."):
                continue
            lst = edges.setdefault(src, {}).setdefault(dst, [])
            if _where(p, line) not in lst:
                lst.append(_where(p, line))
    return edges


# Module cycles known and tolerated exactly as they stand (each entry a sorted cycle; delete an entry with its fix).
# Any other cycle, or one of these grown, fails.
KNOWN_MODULE_CYCLES: tuple[list[str], ...] = ()


def test_no_cycle_between_modules():
    """Module-level cycles across formation_env, agents and train (the subpackage test above cannot see a cycle
    inside one subpackage, nor any in agents and train)."""
    edges = _module_edges()
    cycles = [c for c in _cycles(edges) if c not in KNOWN_MODULE_CYCLES]
    assert not cycles, "import cycles between modules (edge: importing file:line):\n" + _describe(cycles, edges)


def test_module_cycle_finder_sees_the_package_graph():
    edges = _module_edges()
    assert "train.sb3.config" in edges["train.evaluation.policy_loader"]
    assert "agents.registry" in edges["train.sb3.residual"]
    assert all(not dst.startswith("agents.") or src.startswith(("agents.", "train."))
               for src, d in edges.items() for dst in d)


# ---------------------------------------------------------------- (d) private names stay inside their package

def _package(module: str) -> str:
    """The package that owns ``module``'s private names: its top-level package and, inside a subpackage of it,
    that subpackage (``formation_env.sim``, ``train.sb3``); a top-level module belongs to the top-level package."""
    parts = module.split(".")
    if len(parts) >= 2 and (REPO / parts[0] / parts[1]).is_dir():
        return ".".join(parts[:2])
    return parts[0]


def _private_part(name: str) -> tuple[str, str] | None:
    """(owner, name) of the first private component of a dotted name (``a.b._c.d`` -> ``("a.b", "_c")``), dunders
    excepted; None when it has none."""
    parts = name.split(".")
    for i, part in enumerate(parts[1:], start=1):
        if part.startswith("_") and not (part.startswith("__") and part.endswith("__")):
            return ".".join(parts[:i]), part
    return None


def _private_imports() -> list[str]:
    found = []
    for src, p in _modules().items():
        for name, line, _ in _imports(p):
            if _top(name) not in TOP_PACKAGES:
                continue
            private = _private_part(name)
            if private is not None and _package(private[0]) != _package(src):
                found.append(f"{_where(p, line)} imports {name} (private to {_package(private[0])})")
    return sorted(set(found))


# (importing file, private name) known and tolerated: both wake_surfing files move into the wake_surfing task
# (issue 63, item 3), which removes the crossing; delete the entry with that move.
KNOWN_PRIVATE_IMPORTS = (
    ("train/publish/wake_surfing_records.py", "train.evaluation.wake_surfing_eval._rounded"),
)


def test_no_private_name_imported_across_packages():
    bad = [b for b in _private_imports()
           if not any(b.startswith(f"{f}:") and f" imports {n} " in b for f, n in KNOWN_PRIVATE_IMPORTS)]
    assert not bad, "private names imported from another package (make them public or move the code):\n" + \
        "\n".join(bad)


def test_private_name_helpers():
    assert _private_part("formation_env.cli._args.MAX_DURATION_S") == ("formation_env.cli", "_args")
    assert _private_part("formation_env.cli.bench.__all__") is None
    assert _private_part("train.evaluation.policy_loader.load_policy") is None
    assert _package("formation_env.cli._args") == "formation_env.cli" and _package("formation_env.io") == "formation_env"
    assert _package("train.sb3.residual") == "train.sb3" and _package("agents.registry") == "agents"


# ---------------------------------------------------------------- (e) file size

def test_no_source_file_over_500_lines():
    long = []
    for pkg in TOP_PACKAGES:
        for p in _py_files(pkg):
            n = len(p.read_text(encoding="utf-8").splitlines())
            if n > MAX_LINES:
                long.append(f"{p.relative_to(REPO).as_posix()}: {n} lines")
    assert not long, f"files over {MAX_LINES} lines:\n" + "\n".join(long)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(pytest.main([__file__, "-q"]))
