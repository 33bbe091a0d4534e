"""Every bad command line is one line on stderr naming the bad value, exit status 2, never a traceback.

The table below is walked in-process through :func:`formation_env.cli.main` (argparse's usage errors
raise ``SystemExit(2)``; the subcommands' own checks return 2). Each case fails before any heavy work.
``python tests/cli/test_cli_errors.py`` prints the table with the messages (docs/ecosystem.md, "Bad input").
"""

from __future__ import annotations

import contextlib
import io
import re
import sys
from pathlib import Path

import pytest

from formation_env.cli import main

ROOT = Path(__file__).resolve().parents[2]
FILE = "{file}"   # an existing regular file (placeholder, filled per test)
MISSING = "{missing}"  # a path that does not exist
BADYAML = "{badyaml}"  # a file that is not valid YAML
ZIP = str(ROOT / "train" / "policies" / "close_formation_ppo_setpoints_seed0.zip")
WS_ZIP = str(ROOT / "train" / "policies" / "wake_surfing_ppo_setpoints_seed0.zip")  # trained for wake_surfing

# (argv, text the one-line message must contain)
CASES: list[tuple[list[str], str]] = [
    # run
    (["run", "--scenario", "airshow"], "airshow"),
    (["run"], "--scenario"),
    (["run", "--scenario", "tracking", "--duration", "-1"], "'-1'"),
    (["run", "--scenario", "tracking", "--duration", "0"], "'0'"),
    (["run", "--scenario", "tracking", "--duration", "nan"], "'nan'"),
    (["run", "--scenario", "tracking", "--duration", "inf"], "'inf'"),
    (["run", "--scenario", "tracking", "--duration", "1e9"], "'1e9'"),
    (["run", "--scenario", "tracking", "--duration", "ten"], "'ten'"),
    (["run", "--scenario", "tracking", "--duration", "0.001"], "0.001"),
    (["run", "--scenario", "tracking", "--out", FILE], "afile"),
    (["run", "--scenario", "tracking", "--out", FILE + "/sub"], "afile"),
    (["evaluate", "--policy", "pid", "--scenario", "close_formation", "--wake-fidelity", "fine"], "'fine'"),
    (["evaluate", "--policy", "pid", "--scenario", "close_formation", "--throttle-max", "5"], "throttle_max must be in [0.8, 2]"),
    (["evaluate", "--policy", "pid", "--scenario", "close_formation", "--throttle-max", "nan"], "got nan"),
    # replay
    (["replay", "--scenario", "tracking", "--gif", "--max-frames", "0"], "'0'"),
    (["replay", "--scenario", "tracking", "--gif", "--max-frames", "-3"], "'-3'"),
    (["replay", "--scenario", "tracking", "--gif", "--max-frames", "1000000"], "'1000000'"),
    (["replay", "--scenario", "tracking", "--max-frames", "many"], "'many'"),
    (["replay", "--scenario", "tracking", "--duration", "1e9"], "'1e9'"),
    (["replay", "--scenario", "tracking", "--duration", "-5"], "'-5'"),
    (["replay", "--scenario", "tracking", "--duration", "0.001"], "0.001"),
    (["replay", "--scenario", "tracking", "--stride", "0"], "'0'"),
    (["replay", "--scenario", "tracking", "--stride", "1.5"], "'1.5'"),
    (["replay", "--scenario", "airshow"], "airshow"),
    (["replay"], "--scenario"),
    (["replay", "--scenario", "formation_keeping", "--policy", MISSING + ".zip"], "missing.zip"),
    (["replay", "--scenario", "formation_keeping", "--policy", "pid_formatio"], "pid_formatio"),
    (["replay", "--scenario", "formation_keeping", "--policy", FILE], "afile"),
    (["replay", "--scenario", "tracking", "--policy", "pid_formation"], "tracking"),
    (["replay", "--policy", "pid_formation"], "--scenario"),
    (["replay", "--policy", ZIP, "--scenario", "airshow"], "airshow"),
    (["replay", "--policy", ZIP, "--seed", "-1"], "'-1'"),
    (["replay", "--policy", ZIP, "--turbulence", "-1"], "'-1'"),
    (["replay", "--policy", ZIP, "--turbulence", "nan"], "'nan'"),
    (["replay", "--policy", ZIP, "--action-mode", "thrust"], "'thrust'"),
    (["replay", "--scenario", "tracking", "--turbulence", "1"], "--turbulence"),
    (["replay", "--scenario", "tracking", "--seed", "5"], "--seed 5"),  # the pid replay draws no random numbers
    (["replay", "--scenario", "tracking", "--allow-scenario-mismatch"], "--allow-scenario-mismatch"),
    (["replay", "--policy", WS_ZIP, "--scenario", "formation_keeping"], "'wake_surfing'"),
    (["replay", "--policy", WS_ZIP, "--scenario", "vee", "--allow-scenario-mismatch"], "71"),
    (["replay", "--scenario", "tracking", "--out", FILE], "afile"),
    (["replay", "--scenario", "tracking", "--out", FILE + "/sub/dir"], "afile"),
    # evaluate
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--episodes", "2", "--seeds", "1", "2", "3"],
     "--episodes 2"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--episodes", "0"], "'0'"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--episodes", "-4"], "'-4'"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--episodes", "1e9"], "'1e9'"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--episodes", "100000000"], "'100000000'"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--seeds", "-1"], "'-1'"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--seeds", "7", "7"], "[7]"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--seeds", "1" + "0" * 30], "1" + "0" * 30),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--turbulence", "-1"], "'-1'"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--turbulence", "inf"], "'inf'"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--turbulence", "0", "1", "0"], "duplicate"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--turbulence", "0", "-2"], "'-2'"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--duration", "1e9"], "'1e9'"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--duration", "0"], "'0'"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--duration", "0.001"], "0.001"),
    (["evaluate", "--policy", WS_ZIP, "--scenario", "formation_keeping"], "'wake_surfing'"),
    (["evaluate", "--policy", "pid", "--policy", WS_ZIP, "--scenario", "close_formation"], "'wake_surfing'"),
    (["evaluate", "--policy", WS_ZIP, "--scenario", "vee", "--allow-scenario-mismatch"], "71"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--turbulence-field", "gusty"], "'gusty'"),
    (["evaluate", "--policy", "pid", "--scenario", "airshow"], "airshow"),
    (["evaluate", "--policy", MISSING + ".zip", "--scenario", "formation_keeping"], "missing.zip"),
    (["evaluate", "--policy", "pid", "--scenario", "formation_keeping", "--out", FILE + "/sub"], "afile"),
    (["evaluate", "--scenario", "formation_keeping"], "--policy"),
    # train
    (["train", "--scenario", "airshow", "--algo", "ppo"], "airshow"),
    (["train", "--scenario", "formation_keeping", "--algo", "dqn"], "'dqn'"),
    (["train", "--scenario", "formation_keeping", "--algo", "ppo", "--steps", "0"], "'0'"),
    (["train", "--scenario", "formation_keeping", "--algo", "ppo", "--steps", "-5"], "'-5'"),
    (["train", "--scenario", "formation_keeping", "--algo", "ppo", "--steps", "lots"], "'lots'"),
    (["train", "--scenario", "formation_keeping", "--algo", "ppo", "--steps", "9" * 23], "'" + "9" * 23 + "'"),
    (["train", "--scenario", "formation_keeping", "--algo", "ppo", "--steps", "1000000001"], "[1, 1000000000]"),
    (["train", "--scenario", "formation_keeping", "--algo", "ppo", "--seed", "-1"], "'-1'"),
    (["train", "--scenario", "formation_keeping", "--algo", "ppo", "--config", MISSING + ".yml"], "missing.yml"),
    (["train", "--scenario", "formation_keeping", "--algo", "ppo", "--out", FILE + "/run"], "afile"),
    (["train", "--scenario", "formation_keeping", "--algo", "ppo", "--config", FILE], "afile"),
    (["train", "--scenario", "formation_keeping", "--algo", "ppo", "--config", BADYAML], "bad.yml"),
    (["train", "--scenario", "formation_keeping", "--algo", "ppo", "--config", ZIP], "seed0.zip"),
    (["train", "--scenario", "formation_keeping", "--algo", "ppo", "--resume", "--overwrite"], "--overwrite"),
    (["train", "--scenario", "formation_keeping", "--algo", "ppo", "--iterations", "3"], "--iterations"),
    (["train", "--backend", "jax", "--scenario", "formation_keeping"], "'jax'"),
    (["train", "--backend", "rllib", "--num-env-runners", "-1"], "'-1'"),
    # bench
    (["bench", "--runners", "1"], "--runners"),
    (["bench", "--rllib", "--runners", "-1"], "'-1'"),
    (["bench", "--rllib", "--envs-per-runner", "0"], "'0'"),
    (["bench", "--baseline", MISSING], "missing"),
    # verify, report
    (["verify", "--section", "table_9_9"], "table_9_9"),
    (["report", "--section", "appendix_z"], "appendix_z"),
    (["report", "--out", FILE], "afile"),
    # trim, modes
    (["trim", "--speed", "nan"], "'nan'"),
    (["trim", "--speed", "1e9"], "1000000000"),
    (["trim", "--speed", "fast"], "'fast'"),
    (["trim", "--fuel", "0"], "fuel"),
    (["trim", "--altitude", "-5"], "-5"),
    (["trim", "--climb-angle", "80"], "flight_path_angle"),
    (["trim", "--turn-rate", "1e6"], "turn_rate"),
    (["trim", "--turn-rate=-inf"], "'-inf'"),
    (["trim", "--gravity", "moon"], "'moon'"),
    (["modes", "--speed", "500"], "500"),
    (["modes", "--fuel", "-1"], "-1"),
    (["modes", "--altitude", "inf"], "'inf'"),
    # publish (train/publish/, train/evaluation/ceilings.py)
    (["publish"], "ACTION"),
    (["publish", "ship"], "'ship'"),
    (["publish", "run", "somewhere"], "NAME"),
    (["publish", "run", MISSING, "n", "--wall-s", "-1"], "'-1'"),
    (["publish", "run", MISSING, "n", "--stopped-at", "-5"], "'-5'"),
    (["publish", "run", MISSING, "n", "--model", "last"], "'last'"),
    (["publish", "run", MISSING, "n", "--guard", "{clip"], "{clip"),
    (["publish", "run", MISSING, "n"], "missing"),
    (["publish", "levels", MISSING, MISSING + ".json"], "levels.json"),
    (["publish", "levels", MISSING, MISSING + ".json", "--about", "A"], "--task"),
    (["publish", "committed", "--episodes", "0"], "'0'"),
    (["publish", "committed", "--validation-episodes", "1e9"], "'1e9'"),
    (["publish", "committed", "--out", MISSING, "--tasks", "airshow"], "airshow"),
    (["publish", "committed", "--out", FILE], "afile"),
    (["publish", "recompute"], "--out"),
    (["publish", "recompute", "--out", MISSING, "--n-boot", "5"], "'5'"),
    (["publish", "recompute", "--out", MISSING, "--noise-seeds", "1"], "'1'"),
    (["publish", "recompute", "--out", MISSING, "--tasks", "airshow"], "airshow"),
    (["publish", "ceilings", "--episodes", "0"], "'0'"),
    (["publish", "ceilings", "--episodes", "1001"], "'1001'"),
    (["publish", "ceilings", "--sigma", "nan"], "'nan'"),
    (["publish", "ceilings", "--sigma", "3.5"], "'3.5'"),
    (["publish", "ceilings", "--seed", "-1"], "'-1'"),
    # data, verify --converged-saving
    (["data"], "ACTION"),
    (["data", "optimum", "airshow"], "airshow"),
    (["data", "residual-table", "--processes", "0"], "'0'"),
    (["data", "residual-table", "--processes", "65"], "'65'"),
    (["data", "residual-table", "--table", FILE], "--force"),
    (["data", "saving-map", "."], "directory"),
    (["verify", "--converged-saving", "--json"], "--converged-saving"),
    # demo, top level
    (["demo", "--out", FILE], "afile"),
    (["demo", "--out", FILE + "/sub"], "afile"),
    (["run", "--scenario", "tracking", "--out", "/proc/formation-env-no-such-dir/out"], "formation-env-no-such-dir"),
    (["replay", "--scenario", "tracking", "--out", "/proc/formation-env-no-such-dir/out"], "formation-env-no-such-dir"),
    (["run", "--scenario", "tracking", "--out", ""], "''"),
    (["fly"], "'fly'"),
]


def _fill(argv: list[str], tmp: Path) -> list[str]:
    return [a.replace(FILE, str(tmp / "afile")).replace(MISSING, str(tmp / "missing"))
            .replace(BADYAML, str(tmp / "bad.yml")) for a in argv]


def run_case(argv: list[str], tmp: Path) -> tuple[int, str]:
    """(exit status, stderr) of ``formation-env ARGV`` run in-process."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = main(_fill(argv, tmp))
        except SystemExit as exc:
            code = exc.code
    return code, err.getvalue()


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    (tmp_path / "afile").write_text("a file, not a directory\n")
    (tmp_path / "bad.yml").write_text("learning_rate: [0.1\n")
    monkeypatch.chdir(tmp_path)  # default output directories (none should be created) land here
    return tmp_path


def test_table_size():
    print(f"\n{len(CASES)} bad command lines in the table")
    assert len(CASES) >= 40
    assert len({tuple(a) for a, _ in CASES}) == len(CASES)


@pytest.mark.parametrize(("argv", "excerpt"), CASES, ids=[" ".join(a)[:60] for a, _ in CASES])
def test_bad_input_is_one_line_exit_2(argv, excerpt, workdir):
    code, err = run_case(argv, workdir)
    assert code == 2, err
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1, err
    # the subcommand, and its action where it has them ("formation-env publish run: error: ...")
    assert re.match(rf"formation-env( {argv[0]}( [a-z-]+)?)?: error: ", lines[0]), err
    assert _fill([excerpt], workdir)[0] in lines[0], err
    assert sorted(p.name for p in workdir.iterdir()) == ["afile", "bad.yml"], "an error must not create output"


def test_unwritable_out_is_one_line(workdir, monkeypatch):
    import os

    locked = workdir / "locked"
    locked.mkdir()
    real_access = os.access
    monkeypatch.setattr(os, "access", lambda p, mode, **kw: False if Path(p) == locked else real_access(p, mode, **kw))
    for argv in (["run", "--scenario", "tracking"], ["replay", "--scenario", "tracking"], ["demo"],
                 ["evaluate", "--policy", "pid", "--scenario", "formation_keeping"], ["report"],
                 ["train", "--scenario", "formation_keeping", "--algo", "ppo"]):
        code, err = run_case([*argv, "--out", str(locked / "out")], workdir)
        assert code == 2 and len(err.splitlines()) == 1 and "not writable" in err and "locked" in err, err
        code, err = run_case([*argv, "--out", str(locked)], workdir)
        assert code == 2 and len(err.splitlines()) == 1 and "not writable" in err, err
    assert list(locked.iterdir()) == []


def test_duration_caps_agree():
    from formation_env.cli._args import MAX_DURATION_S, MAX_GIF_FRAMES
    from formation_env.replay.animation import MAX_FRAMES
    from formation_env.runs.runner import MAX_DURATION_S as RUNNER_MAX
    from train.evaluation.evaluate import MAX_DURATION_S as EVAL_MAX

    assert MAX_DURATION_S == RUNNER_MAX == EVAL_MAX == 3600.0
    assert MAX_GIF_FRAMES == MAX_FRAMES


def _markdown_table(tmp: Path) -> str:
    rows = ["| subcommand | arguments | message (excerpt) |", "|---|---|---|"]
    tracebacks = 0
    for argv, _ in CASES:
        code, err = run_case(argv, tmp)
        tracebacks += "Traceback" in err
        msg = err.strip().split(": error: ", 1)[-1].replace(str(tmp) + "/", "").replace(str(ROOT) + "/", "")
        msg = re.sub(r" \(see formation-env [a-z -]+ --help\)", "", msg).replace("|", "\\|")
        if len(msg) > 110:
            msg = msg[:107] + "..."
        args = " ".join(a if a else "''" for a in argv[1:]).replace(FILE, "FILE").replace(MISSING, "MISSING").replace(BADYAML, "BAD.yml").replace(str(ROOT) + "/", "")
        args = args.replace("|", "\\|")
        rows.append(f"| {argv[0]} | `{args}` | {msg} (exit {code}) |")
    rows.append("")
    rows.append(f"{len(CASES)} bad command lines tried, {tracebacks} tracebacks.")
    return "\n".join(rows)


if __name__ == "__main__":  # print the table for docs/ecosystem.md
    import os
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        (Path(d) / "afile").write_text("x\n")
        (Path(d) / "bad.yml").write_text("learning_rate: [0.1\n")
        os.chdir(d)
        sys.stdout.write(_markdown_table(Path(d)) + "\n")
