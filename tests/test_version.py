"""One version everywhere: the package, its metadata file, the citation and the changelog's latest entry."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import formation_env

REPO = Path(__file__).resolve().parents[1]


def test_one_version_everywhere():
    v = formation_env.__version__
    assert re.search(rf'^version = "{re.escape(v)}"$', (REPO / "pyproject.toml").read_text(), re.M)
    assert re.search(rf"^version: {re.escape(v)}$", (REPO / "CITATION.cff").read_text(), re.M)
    first = re.search(r"^## \[([^\]]+)\]", (REPO / "CHANGELOG.md").read_text(), re.M).group(1)
    assert first in (v, "Unreleased")
    assert f"(version {v})" in (REPO / "README.md").read_text()  # the citation line
    out = subprocess.run([sys.executable, "-m", "formation_env.cli", "--version"], capture_output=True, text=True,
                         cwd=REPO)
    assert out.returncode == 0 and out.stdout.strip() == f"formation-env {v}"
