"""The documentation site builds with warnings as errors (``mkdocs build --strict``): a broken link or anchor, a page
missing from the nav, an include (``--8<--``) whose file does not exist or an API reference that does not resolve
fails the test."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

pytest.importorskip("mkdocs")
pytest.importorskip("mkdocstrings")
pytest.importorskip("pymdownx")


def test_the_site_builds_strict(tmp_path):
    r = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file", str(REPO / "mkdocs.yml"),
                        "--site-dir", str(tmp_path / "site")], cwd=REPO, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, f"mkdocs build --strict failed:\n{r.stdout[-3000:]}\n{r.stderr[-6000:]}"
    assert (tmp_path / "site" / "tasks" / "close_formation" / "index.html").is_file()
    assert (tmp_path / "site" / "api" / "index.html").is_file()
