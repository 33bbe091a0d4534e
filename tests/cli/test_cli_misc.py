"""The top-level CLI behaviours that are not bad input: ``--version``, a closed stdout pipe, the exit
status of ``report`` (0 once written, ``--strict`` 1 on a mismatch) and ``verify`` (1 on a mismatch),
``bench``'s progress on stderr, and ``--allow-scenario-mismatch``."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import formation_env
from formation_env.cli import main

ROOT = Path(__file__).resolve().parents[2]


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"formation-env {formation_env.__version__}"


def test_version_console_script():
    exe = Path(sys.executable).with_name("formation-env")
    cmd = [str(exe)] if exe.is_file() else [sys.executable, "-m", "formation_env.cli"]
    r = subprocess.run([*cmd, "--version"], capture_output=True, text=True, check=False)
    assert r.returncode == 0 and r.stdout.strip() == f"formation-env {formation_env.__version__}", r.stderr


# ``formation-env verify --json`` with a 1 MB section, so the pipe closes while it writes.
_BIG_VERIFY = ("import sys; import formation_env.cli.verify as v; "
               "v.available_sections = lambda: {'big': lambda: {'ok': True, 'x': ['y' * 100] * 10000}}; "
               "from formation_env.cli import main; sys.exit(main(['verify', '--json']))")


def test_broken_pipe_ends_quietly():
    p1 = subprocess.Popen([sys.executable, "-c", _BIG_VERIFY], stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT)
    p2 = subprocess.Popen(["head", "-c", "10"], stdin=p1.stdout, stdout=subprocess.PIPE)
    p1.stdout.close()  # head holds the only reading end
    head_out = p2.communicate(timeout=120)[0]
    err = p1.stderr.read().decode()
    p1.stderr.close()
    rc = p1.wait(timeout=120)
    assert head_out == b'{\n  "big":'
    assert err == "", err  # no "[Errno 32] Broken pipe", no "Exception ignored"
    assert rc == 1  # the Python docs' recipe (signal module, "Note on SIGPIPE")


def _fake_report(monkeypatch, n_out: int):
    import formation_env.report as report

    def build_report(out, **kw):
        Path(out).mkdir(parents=True, exist_ok=True)
        (Path(out) / "report.md").write_text("# report\n")
        return {"out": str(out), "counts": {"ok": 40, "out": n_out}, "figures": []}

    monkeypatch.setattr(report, "build_report", build_report)


@pytest.mark.parametrize(("n_out", "strict", "code"), [(3, False, 0), (3, True, 1), (0, True, 0), (0, False, 0)])
def test_report_exit_status(monkeypatch, tmp_path, capsys, n_out, strict, code):
    _fake_report(monkeypatch, n_out)
    argv = ["report", "--out", str(tmp_path / "r")] + (["--strict"] if strict else [])
    assert main(argv) == code
    captured = capsys.readouterr()
    assert "report.md" in captured.out
    assert ("outside the tolerance" in captured.err) == bool(n_out)


@pytest.mark.parametrize(("ok", "code"), [(False, 1), (True, 0)])
def test_verify_exits_1_on_a_mismatch(monkeypatch, capsys, ok, code):
    import formation_env.cli.verify as verify

    section = {"ok": ok, "row": {"computed": [1.0], "thesis": [2.0], "ok": ok}}
    monkeypatch.setattr(verify, "available_sections", lambda: {"s": lambda: section})
    assert main(["verify"]) == code
    assert main(["verify", "--json"]) == code
    capsys.readouterr()


def test_bench_progress_on_stderr(monkeypatch, capsys):
    import types

    import formation_env.cli.bench as bench

    def envs_bench(quick, baseline, busy, log):
        for k in range(1, 3):
            log(f"envs {k}/2: threads=2 case{k}")
        return {"case": "c", "configurations": {"threads=2": {"case1": {"new": 1.0}, "case2": {"new": 2.0}}}}

    fake = {"formation_env.wake.bench": types.SimpleNamespace(run_benchmarks=lambda quick: {"x": 1}),
            "formation_env.envs.bench": types.SimpleNamespace(run_benchmarks=envs_bench)}
    monkeypatch.setattr(bench, "import_available", lambda names: fake)
    assert main(["bench", "--json", "--quick"]) == 0
    captured = capsys.readouterr()
    import json

    data = json.loads(captured.out)  # stdout is the JSON alone
    assert data["wake"] == {"x": 1} and data["envs"]["case"] == "c"
    lines = captured.err.splitlines()
    assert "1/2 wake" in lines[0] and "2/2 envs" in lines[1]
    assert "2/2 envs 1/2: threads=2 case1" in lines[2] and "envs 2/2" in lines[3] and "done" in lines[-1]


def test_bench_subprocess_streams_case_progress():
    from formation_env.envs import bench

    seen = []
    with pytest.raises(RuntimeError, match="unknown bench case kind"):  # case 0 starts, then fails
        bench._run(None, [{"kind": "nope"}, {"kind": "nope"}], 1, False, 0.01, 1, seen.append)
    assert seen == [0]


def test_allow_scenario_mismatch_flies_when_the_sizes_agree(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    zip_ = ROOT / "train" / "policies" / "wake_surfing_ppo_setpoints_seed0.zip"
    argv = ["evaluate", "--policy", str(zip_), "--scenario", "formation_keeping", "--episodes", "1", "--duration", "0.2",
            "--no-plots", "--out", str(tmp_path / "e")]
    assert main(argv) == 2 and "'wake_surfing'" in capsys.readouterr().err
    assert main([*argv, "--allow-scenario-mismatch"]) == 0
    assert (tmp_path / "e" / "results.json").is_file()


def test_bench_peer_python_needs_peers_and_an_interpreter(capsys, tmp_path):
    assert main(["bench", "--peer-python", "/usr/bin/env"]) == 2
    assert "--peer-python: only with --peers" in capsys.readouterr().err
    assert main(["bench", "--peers", "--peer-python", str(tmp_path / "nope")]) == 2
    assert "not an executable file" in capsys.readouterr().err
