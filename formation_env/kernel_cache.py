"""Keep numba's on-disk kernel cache consistent with the sources of the whole package.

numba caches each ``cache=True`` function keyed on its *own* source file only (numba 0.68: a hash of that file's
bytes; earlier: its modification time). A compiled function that calls, or inlines, a kernel from another file --
``decide_packed`` (sim/step.py) inlines the stages of sim/stages.py and calls the ELL of wake/*.py -- is *not*
recompiled when only that other file changes: the cached caller silently runs the old physics (measured: an edit
of sim/stages.py left the cached decision step running the previous code). So the package keeps one fingerprint of
the sources its kernels can depend on (the modules that import numba and everything of the package they import,
:func:`_sources`) beside the cache and, when it differs from the sources being imported, deletes the package's
cached kernels before any is loaded (``formation-env warmup`` recompiles them with progress). Editing a module
outside that set (a task, an env adapter, the Python driver of the Simulation, the CLI) recompiles nothing.

Cache roots: the in-tree ``__pycache__`` directories (numba's default when the package is writable) or, with
``NUMBA_CACHE_DIR`` set, that directory (numba's ``<dir name>_<sha1 of its path>`` subdirectories). Only this
package's cache files (``*.nbi``, ``*.nbc``) are touched. A read-only install, where nothing can be written, is
left as it is (its sources do not change).
"""

from __future__ import annotations

import hashlib
import os
import re
from pathlib import Path

__all__ = ["PACKAGE_DIR", "source_fingerprint", "cache_dirs", "check_kernel_cache"]

PACKAGE_DIR = Path(__file__).resolve().parent
_STAMP_NAME = "formation_env_kernel_sources.sha256"
_CACHE_SUFFIXES = (".nbi", ".nbc")

_FROM = re.compile(r"^[ \t]*from[ \t]+(\.*)([\w.]*)[ \t]+import[ \t]+(\([^)]*\)|[^\n#;]*)", re.M)
_IMPORT = re.compile(r"^[ \t]*import[ \t]+([\w., \t]+)", re.M)


def _module_file(path: Path) -> Path | None:
    if path.with_suffix(".py").is_file():
        return path.with_suffix(".py")
    if (path / "__init__.py").is_file():
        return path / "__init__.py"
    return None


def _imports(path: Path, text: str, package_dir: Path) -> tuple[list[Path], bool]:
    """(the package's files ``path`` imports, whether it imports numba), read off its import statements (any
    indentation, so imports inside functions count; an import quoted in a docstring counts too, which only widens
    the set)."""
    found, numba = [], False
    root = package_dir.parent
    for m in _IMPORT.finditer(text):
        for name in m.group(1).replace(" as ", ",").split(","):
            name = name.strip()
            numba |= name.split(".")[0] == "numba"
            if name.startswith(package_dir.name + "."):
                f = _module_file(root.joinpath(*name.split(".")))
                found += [f] if f else []
    for m in _FROM.finditer(text):
        dots, module, names = m.groups()
        if not dots:
            numba |= module.split(".")[0] == "numba"
            if module.split(".")[0] != package_dir.name:
                continue
            target = root.joinpath(*module.split("."))
        else:
            target = path.parent
            for _ in range(len(dots) - 1):
                target = target.parent
            target = target.joinpath(*module.split(".")) if module else target
        for name in names.strip("()").replace("\n", ",").split(","):
            name = name.split(" as ")[0].strip()
            if not name or name == "*":
                name = ""
            sub = _module_file(target / name) if name else None
            f = sub or _module_file(target)  # a submodule, else a name from the module (or package) itself
            found += [f] if f else []
    return found, numba


def _sources(package_dir: Path) -> list[Path]:
    """The package's sources a compiled kernel can depend on: every module that imports numba and, transitively,
    every module of the package they import (a name taken from a package resolves to its submodule when there is
    one, else to the package's ``__init__``). A kernel can reference only functions and globals of the modules its
    own module imports, so a module outside this set (the Python driver ``sim/simulation.py``, the env adapters,
    the tasks, the CLI) can change without any cached kernel going stale."""
    files = sorted(p for p in package_dir.rglob("*.py") if "__pycache__" not in p.parts)
    texts = {p: p.read_text(encoding="utf-8") for p in files}
    edges, stack = {}, []
    for p in files:
        edges[p], uses_numba = _imports(p, texts[p], package_dir)
        if uses_numba:
            stack.append(p)
    seen: set[Path] = set()
    while stack:
        p = stack.pop()
        if p in seen:
            continue
        seen.add(p)
        stack.extend(f for f in edges.get(p, ()) if f in texts)
    return sorted(seen)


def source_fingerprint(package_dir: Path = PACKAGE_DIR) -> str:
    """sha256 over the package's kernel-relevant sources (relative path and bytes, in sorted order)."""
    h = hashlib.sha256()
    for p in _sources(package_dir):
        h.update(p.relative_to(package_dir).as_posix().encode())
        h.update(b"\0")
        h.update(p.read_bytes())
        h.update(b"\0")
    return h.hexdigest()


def cache_dirs(package_dir: Path = PACKAGE_DIR, numba_cache_dir: str | None = None) -> tuple[Path, list[Path]]:
    """(the directory the fingerprint lives in, the directories numba keeps this package's kernels in)."""
    dirs = sorted({p.parent for p in _sources(package_dir)})
    if numba_cache_dir:
        root = Path(numba_cache_dir)
        # numba's _UserProvidedCacheLocator: <cache dir>/<parent dir name>_<sha1 of the absolute source dir>
        return root, [root / f"{d.name}_{hashlib.sha1(str(d.resolve()).encode()).hexdigest()}" for d in dirs]
    return package_dir / "__pycache__", [d / "__pycache__" for d in dirs]


def check_kernel_cache(package_dir: Path = PACKAGE_DIR, numba_cache_dir: str | None = None) -> int:
    """Delete this package's cached kernels when its sources differ from the ones they were compiled from (the
    fingerprint beside the cache; no fingerprint: unknown provenance, so deleted too), then record the current
    fingerprint. Returns the number of cache files deleted (0 when the fingerprint matched or nothing can be
    written). ``numba_cache_dir`` None: numba's own setting (``NUMBA_CACHE_DIR``)."""
    if numba_cache_dir is None:
        numba_cache_dir = os.environ.get("NUMBA_CACHE_DIR") or None
    stamp_dir, dirs = cache_dirs(package_dir, numba_cache_dir)
    stamp = stamp_dir / _STAMP_NAME
    current = source_fingerprint(package_dir)
    try:
        if stamp.read_text().strip() == current:
            return 0
    except OSError:
        pass
    removed = 0
    for d in dirs:
        if not d.is_dir():
            continue
        for f in d.iterdir():
            if f.suffix in _CACHE_SUFFIXES:
                try:
                    f.unlink()
                    removed += 1
                except OSError:  # another process removed it, or not ours to remove
                    pass
    try:
        stamp_dir.mkdir(parents=True, exist_ok=True)
        tmp = stamp.with_name(f"{stamp.name}.{os.getpid()}.tmp")
        tmp.write_text(current + "\n")
        os.replace(tmp, stamp)  # atomic: a concurrent import reads the old or the new fingerprint, never half
    except OSError:  # read-only install
        return removed
    return removed
