"""The scripts in examples/ run as a researcher runs them: ``python examples/<file>.py --smoke`` in a subprocess,
from a working directory of their own (PYTHONPATH the repository, as a checkout without installing it).

That working directory holds a user's own ``train.py`` and ``agents/`` package, each raising ImportError when
imported: an example must never pick up modules from the directory it is run in (the project's ``train`` and
``agents`` are top-level packages of the same names).

Each test checks the exit status and what the example is there to show (the paired difference an evaluation
prints, the model a training saves). The recipes written out in the training examples are checked against
train/hyperparams/ppo.yml and mappo.yml, and each training example's smoke model against the final model of
``formation-env train`` at the same sizes (bit for bit), so the examples cannot drift from the committed recipe.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "examples"
_SHADOW = "raise ImportError('a user module in the working directory was imported: {}')\n"


@pytest.fixture
def workdir(tmp_path):
    """A working directory with a user's own ``train.py`` and ``agents/`` that must never be imported."""
    (tmp_path / "train.py").write_text(_SHADOW.format("train.py"))
    (tmp_path / "agents").mkdir()
    (tmp_path / "agents" / "__init__.py").write_text(_SHADOW.format("agents/"))
    return tmp_path


def run_example(name: str, cwd: Path, *args: str, timeout: float = 300, env: dict | None = None) -> str:
    """``python examples/<name> --smoke ARGS`` run from ``cwd``; its output. Importing the working directory's
    ``train.py`` or ``agents/`` is an AssertionError, any other failure ``pytest.fail``."""
    env = {**os.environ, "PYTHONPATH": str(REPO), **(env or {})}
    env.pop("RAY_ADDRESS", None)
    r = subprocess.run([sys.executable, str(EXAMPLES / name), "--smoke", *args], cwd=cwd, env=env,
                       capture_output=True, text=True, timeout=timeout)
    return _checked(r, name)


def _checked(r: subprocess.CompletedProcess, name: str) -> str:
    out = r.stdout + r.stderr
    assert "a user module in the working directory was imported" not in out, f"{name}:\n{out[-3000:]}"
    if r.returncode != 0:
        pytest.fail(f"{name} exited {r.returncode}:\n{out[-6000:]}")
    return out


def test_an_example_copied_next_to_the_users_train_py_imports_the_project(workdir):
    """A researcher copies an example into their own project, which has a train.py: ``--help`` runs the imports.
    The script's own directory is first on sys.path; ``import formation_env.own_packages`` binds ``train`` to the
    project's package before the example imports it."""
    shutil.copy(EXAMPLES / "train_ppo_close_formation.py", workdir)
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    r = subprocess.run([sys.executable, "train_ppo_close_formation.py", "--help"], cwd=workdir, env=env,
                       capture_output=True, text=True, timeout=120)
    assert "--smoke" in _checked(r, "a copied train_ppo_close_formation.py")


def _module(name: str):
    spec = importlib.util.spec_from_file_location(f"example_{name}", EXAMPLES / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_every_example_has_a_docstring_and_a_smoke_flag():
    files = sorted(EXAMPLES.glob("*.py"))
    assert {f.name for f in files} >= {"quickstart_pettingzoo.py", "train_ppo_close_formation.py",
                                       "evaluate_committed.py", "mappo_vee5.py", "rllib_vee5.py",
                                       "torchrl_close_formation.py"}
    for f in files:
        text = f.read_text()
        assert text.startswith('"""'), f"{f.name}: no module docstring"
        assert f"python examples/{f.name} --smoke" in text and "--smoke" in text, f"{f.name}: docstring says how to run"


def test_quickstart_pettingzoo(workdir):
    out = run_example("quickstart_pettingzoo.py", workdir)
    assert "agents: ['uav_1']" in out
    for group in ("slot_position_error", "induced_wind", "neighbours"):
        assert re.search(rf"^\s+{group}\s+\d+", out, re.M), f"observation group {group} not printed"
    assert "induced wind (N, E, D)" in out and "induced-drag saving" in out
    rows = dict(re.findall(r"^(pid|random)\s+20\s+\S+\s+\S+ m\s+(\S+)$", out, re.M))
    assert set(rows) == {"pid", "random"}, out[-2000:]
    assert 0.0 < float(rows["pid"]) < 1.0  # the follower starts near the optimum: it harvests part of it


def _recipe_matches(mod, algo_section: dict) -> None:
    kw = dict(mod.PPO_KWARGS)
    assert mod.REWARD_SCALE == algo_section["reward_scale"]
    assert mod.N_FORMATIONS == algo_section["n_formations"]
    assert mod.TOTAL_STEPS == algo_section["n_timesteps"]
    for key in ("n_steps", "batch_size", "n_epochs", "gamma", "gae_lambda", "clip_range", "ent_coef", "vf_coef",
                "max_grad_norm"):
        assert kw[key] == algo_section[key], key
    lr = algo_section["learning_rate"]
    if isinstance(lr, str):  # "lin_<initial>": decayed linearly to 0
        assert kw["learning_rate"](1.0) == pytest.approx(float(lr[4:])) and kw["learning_rate"](0.0) == 0.0
    else:
        assert kw["learning_rate"] == lr
    net = kw.get("policy_kwargs") or mod.NET
    pk = algo_section["policy_kwargs"]
    assert net["net_arch"] == pk["net_arch"] and net["log_std_init"] == pk["log_std_init"]
    assert net["activation_fn"].__name__.lower() == pk["activation_fn"]


def test_training_examples_write_out_the_committed_recipes():
    from train.sb3.config import load_hyperparams

    from formation_env.tasks import get_task
    from train.sb3.config import TrainConfig, make_env_config

    ppo = load_hyperparams("ppo", "close_formation")
    _recipe_matches(_module("train_ppo_close_formation"), ppo)
    assert ppo["action_guard"] is True  # the example's GuardedVecEnv
    mappo = load_hyperparams("ppo", "vee5", REPO / "train" / "hyperparams" / "mappo.yml")
    assert mappo["policy"] == "CentralCriticPolicy"
    _recipe_matches(_module("mappo_vee5"), mappo)
    assert mappo.get("action_guard") is False  # the example flies without the guard
    for scenario, params in (("close_formation", ppo), ("vee5", mappo)):  # the examples' env: the CLI's
        cfg = TrainConfig.from_hyperparams(params, scenario=scenario, algo="ppo", action_mode="setpoints", seed=0)
        assert make_env_config(cfg) == get_task(scenario).default_config()


def _paired_line(out: str, metric: str, baseline: str) -> float:
    m = re.search(rf"^{metric}, \S+ minus {baseline}: ([+-]\d\.\d+) \[([+-]\d\.\d+), ([+-]\d\.\d+)\]", out, re.M)
    assert m, f"no paired difference against {baseline} printed:\n{out[-3000:]}"
    d, lo, hi = map(float, m.groups())
    assert lo <= d <= hi
    return d


def _same_as_the_cli_run(model_zip: Path, tmp: Path, scenario: str, smoke: dict, config_file=None) -> None:
    """The example's model is bit for bit the final model of ``formation-env train`` with the same sizes."""
    import torch
    from stable_baselines3 import PPO

    from train.sb3.train import train

    train(scenario=scenario, algo="ppo", seed=0, steps=2048, out_dir=tmp, config_file=config_file,
          overrides={**smoke, "eval_freq": 0, "checkpoint_freq": 0}, log=lambda m: None, progress_bar=False)
    cli = PPO.load(tmp / "final_model.zip", device="cpu").policy.state_dict()
    example = PPO.load(model_zip, device="cpu").policy.state_dict()
    assert cli.keys() == example.keys()
    assert all(torch.equal(cli[k], example[k]) for k in cli), "the example trains another policy than the CLI"


def test_train_ppo_close_formation(workdir, tmp_path_factory):
    out = run_example("train_ppo_close_formation.py", workdir, "--out", "run")
    model = workdir / "run" / "model.zip"
    assert model.is_file() and (workdir / "run" / "model.json").is_file()
    assert re.search(r"trained 2,048 steps", out)
    assert "UserWarning" not in out  # the sidecar records the task's version
    for baseline in ("pid", "station_keeper"):
        _paired_line(out, "harvest_ratio", baseline)
    _same_as_the_cli_run(model, tmp_path_factory.mktemp("cli"), "close_formation",
                         {"n_formations": 4, "batch_size": 128})


def test_evaluate_committed(workdir):
    out = run_example("evaluate_committed.py", workdir)
    assert "formation_env/CloseFormation-v" in out
    for baseline in ("pid", "station_keeper"):
        _paired_line(out, "harvest_ratio", baseline)
    # the committed policy harvests more than the thesis PID even in 4 short episodes
    assert _paired_line(out, "harvest_ratio", "pid") > 0


def test_mappo_vee5(workdir, tmp_path_factory):
    out = run_example("mappo_vee5.py", workdir, "--out", "run")
    assert (workdir / "run" / "model.zip").is_file()
    assert re.search(r"2 vees x 4 followers, actor input (\d+), critic input (\d+)", out)
    a, c = map(int, re.search(r"actor input (\d+), critic input (\d+)", out).groups())
    assert c == 4 * a  # the agent-specific global state: its own observation and the three others'
    assert re.search(r"^model: formation saving \d\.\d{3}, collisions \d+/2$", out, re.M)
    _same_as_the_cli_run(workdir / "run" / "model.zip", tmp_path_factory.mktemp("cli"), "vee5",
                         {"n_formations": 2, "batch_size": 128}, REPO / "train" / "hyperparams" / "mappo.yml")


def test_torchrl_close_formation(workdir):
    pytest.importorskip("torchrl")
    out = run_example("torchrl_close_formation.py", workdir)
    assert "PettingZooWrapper groups: {'uav': ['uav_1']}" in out
    assert len(re.findall(r"^\s+(random|pid)\s*: 10 decisions", out, re.M)) == 4
    assert "GymEnv('formation_env/CloseFormation-v" in out


RAY_EXIT_DEADLINE_S = 90.0


def _ray_processes(tmpdir: str) -> list[int]:
    """Processes started with RAY_TMPDIR = ``tmpdir`` (every Ray process of the example's instance)."""
    pids = []
    for p in Path("/proc").iterdir():
        if not p.name.isdigit():
            continue
        try:
            if f"RAY_TMPDIR={tmpdir}".encode() in (p / "environ").read_bytes().split(b"\0") \
                    or tmpdir.encode() in (p / "cmdline").read_bytes():
                pids.append(int(p.name))
        except OSError:
            continue
    return pids


def _run_rllib(workdir, *args) -> str:
    pytest.importorskip("ray.rllib", reason="needs the 'distributed' extra (ray[rllib])")
    ray_tmp = tempfile.mkdtemp(prefix="fe-ex-ray-", dir="/tmp")  # short: Ray's socket paths must stay short
    try:
        out = run_example("rllib_vee5.py", workdir, "--out", "run", *args, env={"RAY_TMPDIR": ray_tmp}, timeout=400)
    finally:
        # Ray's own processes (raylet, GCS, workers) exit after the driver's ray.shutdown() returns, on their own
        # schedule: on a busy machine several seconds later. A process still there after the deadline is left behind.
        deadline = time.monotonic() + RAY_EXIT_DEADLINE_S
        left = _ray_processes(ray_tmp)
        while left and time.monotonic() < deadline:
            time.sleep(0.5)
            left = _ray_processes(ray_tmp)
        for pid in left:  # not to leak them into the rest of the suite
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
        shutil.rmtree(ray_tmp, ignore_errors=True)
    assert not left, f"Ray processes left behind {RAY_EXIT_DEADLINE_S:g} s after the example ended: {left}"
    return out


def test_rllib_vee5(workdir):
    out = _run_rllib(workdir)
    assert re.search(r"RLlib: 1 iterations, [\d,]+ env steps", out)
    assert (workdir / "run" / "summary.json").is_file()
    assert re.search(r"formation saving \d\.\d{3}, collisions \d+/2$", out, re.M)


def test_rllib_vee5_env_runners_ignore_the_users_train_py(workdir):
    """Ray puts the driver's working directory first on its workers' sys.path; an env runner unpickling the env
    (train.rllib.env.FormationMultiAgentEnv) still imports the project's train package (the workers' setup hook,
    train.rllib.cluster.WORKER_RUNTIME_ENV)."""
    out = _run_rllib(workdir, "--env-runners", "1")
    assert re.search(r"RLlib: 1 iterations, [\d,]+ env steps", out)


def code_lines(path: Path) -> int:
    """Lines of code: not blank, not a comment, not inside a docstring (module, class or function)."""
    import ast
    import io
    import tokenize

    text = path.read_text()
    doc_lines = set()
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(getattr(first, "value", None), ast.Constant) \
                    and isinstance(first.value.value, str):
                doc_lines.update(range(first.lineno, first.end_lineno + 1))
    code = set()
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        if tok.type not in (tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT,
                            tokenize.ENDMARKER):
            code.update(range(tok.start[0], tok.end[0] + 1))
    return len(code - doc_lines)


def test_custom_task_is_one_short_file_without_compiled_code():
    """examples/custom_task.py: <= 120 lines of code (blank, comment and docstring lines not counted), no numba,
    and its terms are Python: the package's kernel sources are not among the files it touches."""
    path = EXAMPLES / "custom_task.py"
    assert code_lines(path) <= 120
    assert "numba" not in path.read_text()


def test_custom_task(workdir):
    """The task of one's own: registered with its Gymnasium id, its Python reward term in the info and its
    observation group at the end of the observation, PPO trained for 2,048 steps on it, and the evaluation's
    episodes carrying its metric for the policy and the thesis PID."""
    out = run_example("custom_task.py", workdir, "--out", "run", timeout=600)
    assert re.search(r"^custom/FuelSlot-v0: observation \d+ \(the last: the fuel-flow saving [+-]\d\.\d{3}\), reward "
                     r"[+-]\d+\.\d{3} of which fuel_flow_saving [+-]\d\.\d{3}$", out, re.M), out[-3000:]
    assert "trained 2,048 steps" in out and (workdir / "run" / "model.zip").is_file()
    rows = dict(re.findall(r"^(model|pid): fuel-flow saving ([+-]\d\.\d{3}) \(mean of 4 episodes\)", out, re.M))
    assert set(rows) == {"model", "pid"}, out[-3000:]
    assert all(-1.0 <= float(v) <= 1.0 for v in rows.values())
