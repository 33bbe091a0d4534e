"""A user's own ``train.py`` and ``agents/`` in the working directory never stand in for the project's ``train`` and
``agents`` packages (formation_env.own_packages).

``python -m formation_env.cli`` puts the working directory first on ``sys.path``; the ``formation-env`` console
script does not, and is run too. Both train and evaluate from a directory whose ``train.py`` and ``agents/`` raise
ImportError when imported. The examples are run the same way in tests/examples/test_examples.py (a copied example,
and Ray's env runners)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from formation_env import own_packages

REPO = Path(__file__).resolve().parents[2]
_SHADOW = "raise ImportError('a user module in the working directory was imported: {}')\n"
_TINY = "n_formations: 1\nn_steps: 64\nbatch_size: 64\nn_epochs: 1\neval_freq: 0\ncheckpoint_freq: 0\n"


@pytest.fixture
def workdir(tmp_path):
    (tmp_path / "train.py").write_text(_SHADOW.format("train.py"))
    (tmp_path / "agents").mkdir()
    (tmp_path / "agents" / "__init__.py").write_text(_SHADOW.format("agents/"))
    (tmp_path / "tiny.yml").write_text(_TINY)
    return tmp_path


def _launcher(kind: str) -> list[str]:
    if kind == "module":
        return [sys.executable, "-m", "formation_env.cli"]
    exe = Path(sys.executable).with_name("formation-env")
    if not exe.is_file():
        pytest.skip("no formation-env console script beside this interpreter")
    return [str(exe)]


def _run(cmd: list[str], cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(REPO), "MPLBACKEND": "Agg"}
    return subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


COMMANDS = {
    "train": ["train", "--scenario", "formation_keeping", "--algo", "ppo", "--steps", "64", "--config", "tiny.yml",
              "--out", "run", "--no-progress-bar"],
    "evaluate": ["evaluate", "--policy", "pid", "--policy", "station_keeper", "--scenario", "close_formation",
                 "--episodes", "1", "--duration", "1", "--out", "eval"],
}


@pytest.mark.parametrize(("launcher", "command"), [("module", "train"), ("module", "evaluate"),
                                                   ("console", "evaluate")])
def test_commands_ignore_the_users_train_py_and_agents(workdir, launcher, command):
    r = _run([*_launcher(launcher), *COMMANDS[command]], workdir)
    out = r.stdout + r.stderr
    assert "a user module in the working directory was imported" not in out, out[-3000:]
    assert r.returncode == 0, out[-3000:]
    assert (workdir / ("run/final_model.zip" if command == "train" else "eval/results.json")).is_file()


def test_a_foreign_train_already_imported_is_one_line_exit_2(tmp_path):
    """A process that imported a user's ``train`` first cannot have the project's: the command says so, naming
    both places, instead of failing deep inside an import."""
    (tmp_path / "train.py").write_text("VALUE = 1\n")
    code = "import sys, train; from formation_env.cli import main; sys.exit(main(['evaluate', '--help']))"
    r = _run([sys.executable, "-c", code], tmp_path, timeout=120)
    assert r.returncode == 2, r.stdout + r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert lines[0].startswith("formation-env: error:") and str(tmp_path / "train.py") in lines[0], lines[0]
    assert str(REPO / "train") in lines[0], lines[0]


def test_bind_is_idempotent_and_keeps_the_projects_packages():
    import agents
    import train

    own_packages.bind()
    assert Path(train.__file__).parent == own_packages.package_dir("train") == REPO / "train"
    assert Path(agents.__file__).parent == own_packages.package_dir("agents") == REPO / "agents"
