"""The catalogue of bad inputs (Python API and CLI) and the error each gets; docs/reliability.md's table is generated
from it (``python tests/test_bad_inputs.py --write``), and a test holds the page equal to what the inputs get now.

Every entry must be refused with one clear error: in the API a ``ValueError``, ``TypeError`` or ``RuntimeError``
(Python's own classes, no library's internals) whose message says what is allowed; on the CLI exit status 2 and one
line on stderr, never a traceback. An entry that is accepted (a silent acceptance) or gets anything else fails."""

from __future__ import annotations

import contextlib
import io
import os
import re
import shlex
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "reliability.md"
BEGIN, END = "<!-- bad-inputs:begin (generated: python tests/test_bad_inputs.py --write) -->", "<!-- bad-inputs:end -->"
COMMITTED_ZIP = "train/policies/formation_keeping_ppo_setpoints_seed0.zip"

# ---------------------------------------------------------------------------------------------- the API's inputs
# Each is a Python expression evaluated in the namespace of _api_namespace(): CFG (an EnvConfig of close_formation),
# sim() (a reset Simulation of 2 formations, 2 agents each), par() / gen() / venv() / vec() (reset envs), ID (the
# close_formation task's Gymnasium id) and the package's names.
API = [
    # Simulation.__init__
    "Simulation('close_formation')",
    "Simulation(CFG, batch_size=0)",
    "Simulation(CFG, batch_size=-1)",
    "Simulation(CFG, batch_size=2.5)",
    "Simulation(CFG, batch_size=True)",
    "Simulation(CFG, batch_size='8')",
    "Simulation(CFG, batch_size=10**9)",
    "Simulation(CFG, agents=[5])",
    "Simulation(CFG, agents=[1, 1])",
    # Simulation.reset
    "Simulation(CFG, batch_size=2).step()",
    "sim().reset(seeds=[-1, 0])",
    "sim().reset(seeds=[2**64, 0])",
    "sim().reset(seeds=[1.5, 0])",
    "sim().reset(seeds=['0', 0])",
    "sim().reset(seeds=[0])",
    "sim().reset(seeds=5)",
    "sim().reset([2], seeds=[0])",
    "sim().reset([-1], seeds=[0])",
    "sim().reset([0, 0], seeds=[0, 1])",
    "sim().reset([0.5], seeds=[0])",
    "sim().reset(seeds=[0, 1], options={'gravity': 9.8})",
    "sim().reset(seeds=[0, 1], options={'steady_wind_ned': (0, np.nan, 0)})",
    "sim().reset(seeds=[0, 1], options='windy')",
    # Simulation.step
    "sim().step(nan_at(0, 1, 2))",
    "sim().step(np.full((2, 2, 4), np.inf))",
    "sim().step(np.full((2, 2, 4), -np.inf))",
    "sim().step(np.zeros((2, 2, 3)))",
    "sim().step(np.zeros((2, 4)))",
    "sim().step('abc')",
    "sim().step(np.zeros((2, 2, 4), dtype=bool))",
    "sim().step(np.zeros((2, 2, 4), dtype=complex) + 1j)",
    "sim().step([[[None] * 4] * 2] * 2)",
    "sim().step([[[0, 0]], [[0, 0, 0, 0]]])",
    "sim().step({'uav_0': np.zeros(4)})",
    "sim().step(np.array(['0.1'] * 16).reshape(2, 2, 4))",
    # EnvConfig and its nested options
    "EnvConfig(scenario='airshow')",
    "EnvConfig(action_mode='thrust')",
    "EnvConfig(control_hz=7.0)",
    "EnvConfig(control_hz=0)",
    "EnvConfig(duration_s=-1.0)",
    "EnvConfig(duration_s=float('nan'))",
    "EnvConfig(collision_separation_b=5.0)",
    "EnvConfig(wake_update_every=0)",
    "EnvConfig(wake='yes')",
    "EnvConfig(learning='leaders')",
    "EnvConfig(learning=(0, 0))",
    "EnvConfig(turbulence_field='gusty')",
    "EnvConfig(neighbour_count=-1)",
    "EnvConfig(throttle_max=3.0)",
    "EnvConfig(reward={'slot': -1.0})",
    "EnvConfig(reward={'bogus': 1.0})",
    "EnvConfig(reward=3.0)",
    "EnvConfig(randomisation={'turbulence_sigma_mps': 20.0})",
    "EnvConfig(randomisation={'turbulence_sigma': 1.0})",
    "EnvConfig(randomisation='calm')",
    "RewardWeights(slot=float('inf'))",
    "Randomisation(steady_wind_mps=True)",
    "make_config(scenario='close_formation', gravity=9.8)",
    # Gymnasium
    "gym.make(ID, randomisation={'turbulence_sigma_mps': -1.0})",
    "gym.make(ID, randomisation={'turbulence': 1.0})",
    "gym.make(ID, reward={'benefit': 'lots'})",
    "gym.make(ID, learner=7)",
    "gym.make(ID, scenario='formation_keeping')",
    "gym.make(ID).reset(seed=-1)",
    "gen().step(np.full(4, np.nan))",
    "gen().step('up')",
    "gen().step(np.zeros(3))",
    # PettingZoo
    "formation_env.parallel_env('airshow')",
    "formation_env.parallel_env('close_formation', render_mode='video')",
    "formation_env.parallel_env('close_formation').reset(seed=-1)",
    "formation_env.parallel_env('close_formation').reset(options={'scenario': 'vee5'})",
    "formation_env.parallel_env('close_formation').step({'uav_1': np.zeros(4)})",
    "par().step({'uav_9': np.zeros(4)})",
    "par().step({})",
    "par().step('all ahead')",
    "par().step({'uav_0': np.zeros(4), 'uav_1': [0, True, 0, 0]})",
    "par().step({'uav_0': np.zeros(4), 'uav_1': np.array([0, 1j, 0, 0])})",
    "par().step({'uav_0': np.zeros(4), 'uav_1': np.array([0.0, np.nan, 0.0, 0.0])})",
    "par().step({'uav_0': np.zeros(4), 'uav_1': 'left'})",
    "par().step({'uav_0': np.zeros(4), 'uav_1': np.zeros(5)})",
    "finished_par().step({'uav_1': np.zeros(4)})",
    # vector envs
    "FormationVecEnv(0, scenario='close_formation')",
    "FormationVecEnv(65537, scenario='close_formation')",
    "FormationVecEnv(2, scenario='close_formation', seed=-1)",
    "FormationVecEnv(2, scenario='close_formation', obs_mode='dict')",
    "FormationVecEnv(2, scenario='close_formation', render_mode='human')",
    "venv().seed(-5)",
    "venv().seed(2**63 - 1)",
    "venv().step(np.full((4, 4), np.nan))",
    "venv().step(np.zeros((3, 4)))",
    "venv().step(np.zeros((4, 4), dtype=bool))",
    "venv().step(np.zeros((4, 4), dtype=complex) + 1j)",
    "venv().step(np.array([['a'] * 4] * 4))",
    "vec().reset(seed=[1, 2])",
    "vec().reset(seed=1.5)",
    # policies and training
    "load_policy('missing.zip')",
    "load_policy('corrupt.zip')",
    "load_policy('truncated.zip')",
    "load_policy('notrllib')",
    "load_policy(COMMITTED_ZIP, action_mode='thrust')",
    "train(scenario='formation_keeping', algo='ppo', steps=1000, out_dir='t1', overrides={'batch_size': 100000})",
    "train(scenario='formation_keeping', algo='ppo', steps=1000, out_dir='t2', overrides={'n_formations': 100000})",
    "train(scenario='formation_keeping', algo='ppo', steps=1000, out_dir='t3', overrides={'learning_rate': -1})",
    "train(scenario='formation_keeping', algo='ppo', steps=0, out_dir='t4')",
    "train(resume=True)",
]

# ---------------------------------------------------------------------------------------------- the CLI's inputs
# Each is the command line after ``formation-env``, run in a directory holding the files of _cli_files().
CLI = [
    "",
    "fly",
    "run --scenario airshow",
    "run --scenario tracking --duration -1",
    "run --scenario tracking --duration nan",
    "run --scenario tracking --duration 1e9",
    "run --scenario tracking --duration abc",
    "run --scenario tracking --out afile.txt",
    "run --scenario tracking --out nonempty",
    "trim --speed -5",
    "trim --speed nan",
    "trim --altitude 1e7",
    "trim --fuel -1",
    "trim --gravity moon",
    "modes --speed 0",
    "verify --section nope",
    "evaluate --policy missing.zip --scenario formation_keeping",
    "evaluate --policy corrupt.zip --scenario formation_keeping",
    "evaluate --policy truncated.zip --scenario formation_keeping",
    "evaluate --policy notrllib --scenario formation_keeping",
    "evaluate --policy pid --scenario airshow",
    "evaluate --policy pid --scenario formation_keeping --episodes 0",
    "evaluate --policy pid --scenario formation_keeping --episodes -3",
    "evaluate --policy pid --scenario formation_keeping --turbulence -1",
    "evaluate --policy pid --scenario formation_keeping --turbulence nan",
    "evaluate --policy pid --scenario formation_keeping --seeds -1",
    "evaluate --policy pid --scenario formation_keeping --seeds 1 2 --episodes 3",
    "evaluate --policy pid --scenario formation_keeping --duration 0",
    "evaluate --policy pid --scenario formation_keeping --throttle-max 5",
    "evaluate --policy pid --scenario formation_keeping --action-mode thrust",
    "evaluate --policy pid --scenario formation_keeping --bootstrap-resamples -1",
    "evaluate --policy pid --scenario formation_keeping --out nonempty",
    "replay --scenario formation_keeping --policy missing.zip",
    "replay --scenario airshow",
    "replay --scenario formation_keeping --seed -1",
    "replay --scenario formation_keeping --stride 0",
    "replay --scenario formation_keeping --turbulence -2",
    "replay --scenario formation_keeping --policy corrupt.zip",
    "train --scenario formation_keeping --algo dqn",
    "train --scenario formation_keeping --algo ppo --steps -5",
    "train --scenario formation_keeping --algo ppo --steps 0",
    "train --scenario formation_keeping --algo ppo --steps abc",
    "train --scenario formation_keeping --algo ppo --seed -1",
    "train --scenario airshow --algo ppo --out t5",
    "train --scenario formation_keeping --algo ppo --config batch.yml --out t6",
    "train --scenario formation_keeping --algo ppo --config formations.yml --out t7",
    "train --scenario formation_keeping --algo ppo --config missing.yml --out t8",
    "train --scenario formation_keeping --algo ppo --config broken.yml --out t9",
    "train --scenario formation_keeping --algo ppo --config nested.yml --out t10",
    "train --scenario formation_keeping --algo ppo --config rate.yml --out t11",
    "train --resume",
    "train --resume --out emptydir",
    "train --scenario formation_keeping --algo ppo --out nonempty",
    "train --backend rllib --scenario formation_keeping --num-cpus 0",
    "train --backend rllib --scenario formation_keeping --iterations 0",
]


def _cli_files(where: Path) -> None:
    """The files the CLI's inputs name, in the directory they run in."""
    raw = (ROOT / COMMITTED_ZIP).read_bytes()
    (where / "corrupt.zip").write_text("not a zip")
    (where / "truncated.zip").write_bytes(raw[: len(raw) // 2])
    (where / "notrllib").mkdir()
    (where / "nonempty").mkdir()
    (where / "nonempty" / "keep.txt").write_text("mine")
    (where / "emptydir").mkdir()
    (where / "afile.txt").write_text("a file")
    section = "formation_keeping:\n  "
    (where / "batch.yml").write_text(section + "batch_size: 100000\n")
    (where / "formations.yml").write_text(section + "n_formations: 100000\n")
    (where / "broken.yml").write_text(section + "batch_size: [1, 2\n")
    (where / "nested.yml").write_text(section + "env_kwargs:\n    randomisation:\n      turbulence: 1.0\n")
    (where / "rate.yml").write_text(section + "learning_rate: -1\n")


def _api_namespace() -> dict:
    import gymnasium as gym

    import formation_env
    from formation_env.envs import FormationVecEnv, FormationVectorEnv
    from formation_env.sim import EnvConfig, Simulation
    from formation_env.sim.config import Randomisation, RewardWeights
    from formation_env.tasks import get_task, make_config
    from train.evaluation.policy_loader import load_policy
    from train.sb3.train import train as _train

    cfg = make_config(scenario="close_formation", duration_s=5.0)

    def sim():
        s = Simulation(cfg, batch_size=2)
        s.reset(seeds=[0, 1])
        return s

    def nan_at(*where):
        a = np.zeros((2, 2, 4))
        a[where] = np.nan
        return a

    def par():
        p = formation_env.parallel_env("close_formation")
        p.reset(seed=0)
        return p

    def finished_par():
        p = formation_env.parallel_env("close_formation", duration_s=0.1)
        p.reset(seed=0)
        p.step({a: np.zeros(4) for a in p.agents})
        return p

    def gen():
        e = gym.make(get_task("close_formation").gym_id)
        e.reset(seed=0)
        return e

    def venv():
        v = FormationVecEnv(2, scenario="close_formation")
        v.reset()
        return v

    def vec():
        return FormationVectorEnv(2, scenario="close_formation")

    def train(**kw):
        return _train(progress_bar=False, log=lambda m: None, **kw)

    return {"np": np, "gym": gym, "formation_env": formation_env, "Simulation": Simulation, "EnvConfig": EnvConfig,
            "RewardWeights": RewardWeights, "Randomisation": Randomisation, "make_config": make_config,
            "FormationVecEnv": FormationVecEnv, "FormationVectorEnv": FormationVectorEnv, "CFG": cfg, "sim": sim,
            "nan_at": nan_at, "par": par, "finished_par": finished_par, "gen": gen, "venv": venv, "vec": vec,
            "ID": get_task("close_formation").gym_id, "load_policy": load_policy, "train": train,
            "COMMITTED_ZIP": str(ROOT / COMMITTED_ZIP)}


def _normal(text: str, where: Path) -> str:
    """A message as the page shows it: one line, the run's directory and machine-specific figures left out."""
    text = " ".join(str(text).split())
    text = text.replace(str(where) + os.sep, "").replace(str(where), ".").replace(str(ROOT) + os.sep, "")
    text = re.sub(r"0x[0-9a-f]+", "0x…", text)
    text = re.sub(r"at most [\d,]+ formations fit in (\d+)% of this machine's [\d.]+ \w+ memory",
                  r"at most N formations fit in \1% of this machine's memory", text)
    return text


ALLOWED = (ValueError, TypeError, RuntimeError)


def try_api(expr: str, ns: dict, where: Path) -> tuple[str, str]:
    """(outcome, message): outcome "ValueError" / "TypeError" / "RuntimeError", or "ACCEPTED" / "OTHER:<type>"."""
    import warnings

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            eval(expr, ns)  # noqa: S307 - the catalogue's own expressions
    except ALLOWED as exc:
        kind = type(exc).__name__
        if type(exc) not in ALLOWED:  # a library's subclass (numpy's AxisError, ...) is not a clear error
            kind = f"OTHER:{type(exc).__module__}.{kind}"
        return kind, _normal(exc, where)
    except Exception as exc:  # noqa: BLE001 - recorded as what it is
        return f"OTHER:{type(exc).__module__}.{type(exc).__name__}", _normal(exc, where)
    return "ACCEPTED", ""


def try_cli(line: str, where: Path) -> tuple[str, str]:
    """(outcome, message): "exit 2" and the stderr line, or what happened instead ("exit <n>", "TRACEBACK")."""
    import warnings

    from formation_env.cli import main

    err, out = io.StringIO(), io.StringIO()
    code = None
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            code = main(shlex.split(line))
        except SystemExit as exc:
            code = exc.code
        except BaseException as exc:  # noqa: BLE001 - an escaped exception is a traceback to a user
            return "TRACEBACK", _normal(f"{type(exc).__name__}: {exc}", where)
    text = err.getvalue().strip()
    if "Traceback" in text:
        return "TRACEBACK", _normal(text.splitlines()[-1], where)
    lines = [ln for ln in text.splitlines() if ln.strip()]
    msg = _normal(lines[-1] if lines else "", where)
    if code == 2 and len(lines) == 1:
        return "exit 2", msg
    return f"exit {code} ({len(lines)} lines)", msg


def run_all(where: Path) -> list[tuple[str, str, str, str]]:
    """Every entry tried, in ``where`` (its working directory meanwhile): (surface, input, outcome, message)."""
    _cli_files(where)
    before = Path.cwd()
    os.chdir(where)
    try:
        ns = _api_namespace()
        rows = [("API", expr, *try_api(expr, ns, where)) for expr in API]
        rows += [("CLI", f"formation-env {line}".strip(), *try_cli(line, where)) for line in CLI]
    finally:
        os.chdir(before)
    return rows


def table(rows) -> str:
    def cell(text: str, n: int = 170) -> str:
        text = text if len(text) <= n else text[: n - 1] + "…"
        return text.replace("|", "\\|")

    out = ["| # | where | input | error |", "|---|---|---|---|"]
    for k, (surface, given, outcome, msg) in enumerate(rows, 1):
        err = f"{outcome}: {msg}" if surface == "API" else f"exit 2: `{cell(msg, 160)}`" if outcome == "exit 2" else \
            f"{outcome}: {msg}"
        out.append(f"| {k} | {surface} | `{cell(given, 110)}` | {cell(err) if surface == 'API' else err} |")
    return "\n".join(out) + "\n"


def page_block() -> str:
    text = PAGE.read_text()
    return text[text.index(BEGIN) + len(BEGIN):text.index(END)].strip("\n") + "\n"


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    return run_all(tmp_path_factory.mktemp("bad-inputs"))


def test_at_least_100_bad_inputs_each_refused_with_one_clear_error(rows):
    assert len(rows) >= 100 and len({r[1] for r in rows}) == len(rows)
    bad = [(given, outcome, msg) for _, given, outcome, msg in rows
           if outcome not in ("ValueError", "TypeError", "RuntimeError", "exit 2") or len(msg) < 15]
    assert not bad, "accepted, a traceback or an unclear error:\n" + "\n".join(map(str, bad))


def test_the_reliability_page_lists_what_each_input_gets_now(rows):
    assert page_block() == table(rows), "docs/reliability.md is out of date: python tests/test_bad_inputs.py --write"


def write_page(rows) -> None:
    from formation_env.io import atomic_write_text

    text = PAGE.read_text()
    new = text[:text.index(BEGIN) + len(BEGIN)] + "\n" + table(rows) + text[text.index(END):]
    atomic_write_text(PAGE, new, overwrite=True)  # the page's own generated block, rewritten in place


if __name__ == "__main__":
    import tempfile

    sys.path.insert(0, str(ROOT))
    with tempfile.TemporaryDirectory() as tmp:
        found = run_all(Path(tmp))
    if "--write" in sys.argv[1:]:
        write_page(found)
    print(table(found))
