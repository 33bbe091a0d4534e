"""A training killed with SIGKILL at several moments (mid-rollout, and inside each kind of file write: a checkpoint
zip, the checkpoint state, the learning curve, the final model) resumes with ``--resume`` every time: no file it
leaves is corrupt, and no checkpoint it had completed is lost. Small and fast: a tiny PPO run on the CLI."""

import json
import os
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import pytest
import yaml

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs SIGKILL (POSIX)")

ROOT = Path(__file__).resolve().parents[2]

# the child: the CLI, its atomic writes hooked so that the process kills itself half-way through one of them (the
# temporary file holds half its bytes, not yet renamed into place): KILL_AT = "<file name pattern>:<which write>"
HOOK = r'''
import os, signal, sys
from pathlib import Path
import formation_env.io as fio

pattern, nth = os.environ.get("KILL_AT", ":0").rsplit(":", 1)
seen = [0]
real = fio.atomic_write

def atomic_write(path, writer, *, overwrite=False):
    def write(tmp):
        writer(tmp)
        if pattern and pattern in Path(path).name:
            seen[0] += 1
            if seen[0] == int(nth):
                data = Path(tmp).read_bytes()
                Path(tmp).write_bytes(data[: len(data) // 2])
                os.kill(os.getpid(), signal.SIGKILL)
    return real(path, write, overwrite=overwrite)

fio.atomic_write = atomic_write
from formation_env.cli import main
sys.exit(main(sys.argv[1:]))
'''

STEPS = 640  # env steps: 20 rollouts of 16 decisions x 2 formations; a checkpoint every 64
CONFIG = {"formation_keeping": {"n_formations": 2, "n_steps": 16, "batch_size": 32, "n_epochs": 1, "eval_freq": 0,
                                "checkpoint_freq": 64, "policy_kwargs": {"net_arch": [8]},
                                "env_kwargs": {"duration_s": 2.0}}}


def _checkpoints(run: Path) -> dict[int, bytes]:
    out = {}
    for p in (run / "checkpoints").glob("model_*_steps.zip"):
        out[int(p.name.split("_")[1])] = p.read_bytes()
    return out


def _check_files(run: Path) -> None:
    """Every file the run holds under its own name is whole: zips test clean, JSON and YAML parse, the curve's rows
    have three fields (a temporary file of an interrupted write is hidden, ``.<name>.*``, and never read)."""
    from train.evaluation.safe_zip import read_policy_zip

    for p in run.rglob("*"):
        if not p.is_file() or p.name.startswith(".") or "logs" in p.parts:
            continue
        if p.suffix == ".zip":
            read_policy_zip(p)
            with zipfile.ZipFile(p) as z:
                assert z.testzip() is None, p
        elif p.suffix == ".json":
            json.loads(p.read_text())
        elif p.suffix == ".yaml":
            yaml.safe_load(p.read_text())
        elif p.suffix == ".csv":
            rows = p.read_text().splitlines()
            assert rows and all(len(r.split(",")) == 3 for r in rows), p


def _run(args, env, *, kill_when=None, timeout=240):
    proc = subprocess.Popen([sys.executable, "-c", HOOK, *args], cwd=ROOT, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        if kill_when is not None:
            t0 = time.monotonic()
            while proc.poll() is None and not kill_when():
                assert time.monotonic() - t0 < timeout, "the moment to kill never came"
                time.sleep(0.05)
            if proc.poll() is None:
                os.kill(proc.pid, signal.SIGKILL)
        out, err = proc.communicate(timeout=timeout)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return proc.returncode, out, err


def test_sigkill_at_six_moments_then_resume_each_time(tmp_path):
    run = tmp_path / "run"
    cfg = tmp_path / "tiny.yml"
    cfg.write_text(yaml.safe_dump(CONFIG))
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    first = ["train", "--scenario", "formation_keeping", "--algo", "ppo", "--steps", str(STEPS), "--config", str(cfg),
             "--out", str(run), "--no-progress-bar"]
    resume = ["train", "--resume", "--out", str(run), "--steps", str(STEPS), "--no-progress-bar"]
    # (how the run dies, the arguments): the first run dies inside its second checkpoint's zip write, the resumed
    # ones inside a checkpoint's state file, mid-rollout (killed from outside once a new checkpoint exists), inside
    # the curve, inside a checkpoint zip again, and inside the final model
    moments = [("model_:2", first), ("checkpoint_state:1", resume), ("outside", resume), ("curve:2", resume),
               ("model_:1", resume), ("final_model.zip:1", resume)]
    kept: dict[int, bytes] = {}
    for k, (moment, args) in enumerate(moments):
        before = set(_checkpoints(run)) if run.exists() else set()
        kill_when = None
        if moment == "outside":
            kill_when = lambda: len(_checkpoints(run)) > len(before)  # noqa: E731
            env_k = {**env, "KILL_AT": ":0"}
        else:
            env_k = {**env, "KILL_AT": moment}
        code, out, err = _run(args, env_k, kill_when=kill_when)
        assert code == -signal.SIGKILL, f"moment {k} ({moment}): exit {code}\n{out[-2000:]}\n{err[-2000:]}"
        assert "Traceback" not in err
        _check_files(run)
        now = _checkpoints(run)
        assert now, f"moment {k}: no checkpoint"
        for steps, data in kept.items():  # every completed checkpoint is still there, byte for byte
            assert now.get(steps) == data, f"moment {k} ({moment}) lost or changed checkpoint {steps}"
        kept = now
    # the last kill may leave every checkpoint written but the final model: a few more steps complete the run
    more = [a if a != str(STEPS) else str(STEPS + 128) for a in resume]
    code, out, err = _run(more, {**env, "KILL_AT": ":0"})
    assert code == 0, err[-3000:]
    assert "resuming" in out
    _check_files(run)
    assert all(_checkpoints(run).get(s) == d for s, d in kept.items())
    final = json.loads((run / "final_model.json").read_text())
    assert final["num_timesteps"] >= STEPS + 128
