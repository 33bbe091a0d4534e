"""formation_env.kernel_cache: a numba cache compiled from other sources of the package is deleted before it
loads (numba keys a cached function on its own file only, so a caller compiled against an older callee in
another file would silently run the old code)."""

from __future__ import annotations

import hashlib

from formation_env import kernel_cache as kc


def _package(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sim" / "__pycache__").mkdir(parents=True)
    (pkg / "cli").mkdir()
    (pkg / "sim" / "__init__.py").write_text("")
    (pkg / "sim" / "step.py").write_text("from numba import njit\nfrom .stages import callee\n\n\n"
                                         "@njit(cache=True)\ndef decide(): return callee()\n")
    (pkg / "sim" / "stages.py").write_text("def callee(): return 1\n")
    (pkg / "cli" / "main.py").write_text("HELP = 'a'\n")
    (pkg / "__init__.py").write_text("")
    cached = [pkg / "sim" / "__pycache__" / n for n in ("step.decide-1.py311.nbi", "step.decide-1.py311.1.nbc")]
    for c in cached:
        c.write_bytes(b"compiled")
    keep = pkg / "sim" / "__pycache__" / "step.cpython-311.pyc"
    keep.write_bytes(b"bytecode")
    return pkg, cached, keep


def test_an_edit_in_a_callee_file_deletes_the_cached_callers(tmp_path):
    pkg, cached, keep = _package(tmp_path)
    assert kc.check_kernel_cache(pkg, numba_cache_dir="") == 2  # no fingerprint yet: provenance unknown
    assert not any(c.exists() for c in cached) and keep.exists()  # only numba's files
    for c in cached:  # recompiled against these sources
        c.write_bytes(b"compiled")
    assert kc.check_kernel_cache(pkg, numba_cache_dir="") == 0  # unchanged sources: the cache stays
    assert all(c.exists() for c in cached)
    (pkg / "sim" / "stages.py").write_text("def callee(): return 2\n")  # the callee's file only
    assert kc.check_kernel_cache(pkg, numba_cache_dir="") == 2
    assert not any(c.exists() for c in cached)


def test_modules_no_kernel_imports_do_not_invalidate(tmp_path):
    pkg, cached, _ = _package(tmp_path)
    kc.check_kernel_cache(pkg, numba_cache_dir="")
    for c in cached:
        c.write_bytes(b"compiled")
    (pkg / "cli" / "main.py").write_text("from ..sim.step import decide\nHELP = 'b'\n")  # a client of the kernels
    assert kc.check_kernel_cache(pkg, numba_cache_dir="") == 0 and all(c.exists() for c in cached)


def test_the_kernel_sources_of_the_real_package():
    names = {f.relative_to(kc.PACKAGE_DIR).as_posix() for f in kc._sources(kc.PACKAGE_DIR)}
    # the compiled layers and what they import, followed through files and packages
    assert {"sim/step.py", "sim/stages.py", "sim/observe.py", "wake/kernels.py", "wake/aic.py", "aircraft/eom.py",
            "atmosphere/spectral_field_kernels.py", "constants.py", "frames.py", "control/law.py"} <= names
    # the Python driver, the adapters, the tasks and the front ends are clients: editing them recompiles nothing
    for name in ("sim/simulation.py", "sim/config.py", "tasks/base.py", "envs/parallel.py", "cli/__init__.py",
                 "scenarios/definitions.py"):
        assert name not in names, name
    # every module that imports numba is in it
    for f in kc.PACKAGE_DIR.rglob("*.py"):
        if "__pycache__" not in f.parts and kc._imports(f, f.read_text(encoding="utf-8"), kc.PACKAGE_DIR)[1]:
            assert f.relative_to(kc.PACKAGE_DIR).as_posix() in names, f


def test_a_user_cache_dir_is_checked_where_numba_puts_it(tmp_path):
    pkg, _, _ = _package(tmp_path)
    root = tmp_path / "numba_cache"
    sub = root / f"sim_{hashlib.sha1(str((pkg / 'sim').resolve()).encode()).hexdigest()}"  # numba's layout
    sub.mkdir(parents=True)
    (sub / "step.decide-1.py311.nbi").write_bytes(b"compiled")
    assert kc.check_kernel_cache(pkg, numba_cache_dir=str(root)) == 1
    assert (root / "formation_env_kernel_sources.sha256").read_text().strip() == kc.source_fingerprint(pkg)
    assert kc.check_kernel_cache(pkg, numba_cache_dir=str(root)) == 0
