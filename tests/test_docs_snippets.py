"""Every Python snippet of the README and docs runs as written (issue 22), each in a fresh interpreter in an empty
directory. Blocks that open with ``# API sketch`` are signatures with placeholders and are not run."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
FILES = [REPO / "README.md", *sorted((REPO / "docs").glob("**/*.md"))]


def _blocks():
    for path in FILES:
        text = path.read_text(encoding="utf-8")
        for k, m in enumerate(re.finditer(r"```python\n(.*?)```", text, re.S)):
            code = m.group(1)
            if code.lstrip().startswith("# API sketch") or code.lstrip().startswith("--8<--"):
                # an API sketch, or an include of a file (examples/*.py) that its own test runs
                continue
            yield pytest.param(code, id=f"{path.relative_to(REPO)}#{k}")


@pytest.mark.parametrize("code", list(_blocks()))
def test_snippet_runs(code, tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(REPO))
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True,
                       timeout=900)
    assert r.returncode == 0, f"stdout:\n{r.stdout[-2000:]}\nstderr:\n{r.stderr[-4000:]}"


def test_the_snippets_are_found():
    ids = [p.id for p in _blocks()]
    assert any(i.startswith("README.md") for i in ids) and any(i.startswith("docs/environments.md") for i in ids)
