"""Package layering (issue 14): ``formation_env`` imports neither ``agents`` nor ``train`` (only the
console commands of ``formation_env.cli`` import ``train``, lazily); ``agents`` does not import
``train``; no import cycle between the top-level packages, between formation_env's subpackages, nor between
formation_env's modules; files stay small.

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


def _targets(found, modules) -> dict[str, int]:
    """The modules of ``modules`` that the imports ``found`` (:func:`_scan`'s) name, each with its first line:
    ``from p import x`` names ``p.x`` where that is a module, else ``p`` (``x`` an attribute of ``p``'s
    ``__init__``); the parent packages Python initialises on the way are not edges."""
    by_line: dict[int, list[str]] = {}
    for name, line, _ in found:
        by_line.setdefault(line, []).append(name)
    out: dict[str, int] = {}
    for line, names in sorted(by_line.items()):
        for n in names:
            children = [c for c in names if c.rpartition(".")[0] == n]
            if children and all(c in modules for c in children):
                continue  # ``from p import a, b`` of submodules: p is only the path to them
            if n in modules:
                out.setdefault(n, line)
    return out


def _module_edges(package: str) -> dict[str, dict[str, list[str]]]:
    """Edges module -> module inside ``package`` from every import (module level, in a function, under
    ``TYPE_CHECKING``): a deferred import still makes the two modules one unit to read, test and change."""
    files = {_module_name(p): p for p in _py_files(package)}
    edges: dict[str, dict[str, list[str]]] = {}
    for mod, path in files.items():
        for dst, line in _targets(_imports(path), files).items():
            if dst != mod:
                edges.setdefault(mod, {}).setdefault(dst, []).append(_where(path, line))
    return edges


def test_module_cycle_finder_sees_deferred_type_checking_and_package_imports():
    modules = {"p", "p.a", "p.b", "p.c", "p.d"}
    sources = {
        "p": "from .c import Y\nfrom .d import Z\n",
        "p.a": "from . import b\n",  # the submodule b, not the package
        "p.b": "def f():\n    from .a import X\n",  # deferred: still a cycle a <-> b
        "p.c": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from . import a\n",
        "p.d": "def g():\n    from . import CONST\n",  # an attribute of p's __init__: p <-> d
    }
    edges = {m: {t: ["x"] for t in _targets(_scan(src, m, m == "p"), modules) if t != m}
             for m, src in sources.items()}
    assert edges["p.c"] == {"p.a": ["x"]} and edges["p.a"] == {"p.b": ["x"]}
    assert _cycles(edges) == [["p", "p.d"], ["p.a", "p.b"]]


def test_no_cycle_between_formation_env_modules():
    """No two modules of formation_env import each other, directly or around a loop, at any level (a function's
    import and a ``TYPE_CHECKING`` import count)."""
    edges = _module_edges("formation_env")
    cycles = _cycles(edges)
    assert not cycles, "import cycles between formation_env modules (edge: importing file:line):\n" + \
        _describe(cycles, edges)


# ---------------------------------------------------------------- (d) file size

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
