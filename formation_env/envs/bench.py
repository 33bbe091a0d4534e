"""Environment benchmarks (``formation-env bench``): the single PettingZoo env in every action mode
and with a PID-flown leader, and the SB3 vector env over batch sizes, with 1 and 2 threads, with
and without a competing busy process, optionally against an older checkout measured in the same
session (``--baseline PATH``: ratios new / old). Each configuration runs in its own subprocess
(:mod:`formation_env.envs.bench_cases`), so thread settings and the compiled-kernel caches of the two
checkouts never mix. No assertions: speed is reported, not tested.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

__all__ = ["run_benchmarks", "run_peers", "BATCH_SIZES", "SINGLE_CASES", "TURBULENCE_CASES", "FORMATION_SIZE_CASES"]

PEERS = {
    "PyFlyt 2-aircraft dogfight (joint steps/s)": 408,
    "gym-pybullet-drones, 4 drones with downwash (steps/s)": 688,
    "VMAS CPU flocking, 1,024 envs (env-steps/s)": 44_500,
    "JaxMARL MPE CPU (env-steps/s)": 443_000,
}
SINGLE_CASES = [{"kind": "single", "mode": m, "learning": "all"} for m in ("surfaces", "residual", "setpoints")] + [
    {"kind": "single", "mode": "setpoints", "learning": "followers"}]
BATCH_SIZES = (1, 8, 15, 16, 32, 256, 1024)
TURBULENCE_CASES = ("von_karman", "lanes")  # EnvConfig.turbulence_field values measured at B = 256, sigma 1 m/s
# formations of 3, 5 and 9 at B = 256 (issues 25 and 26: decisions/s and UAV physics steps/s against 2 UAVs), and the
# 2-UAV close_formation, whose wake is theirs (the converged fidelity and load-weighted coupling; formation_keeping's is
# the thesis's lattice and effective wind): the per-UAV cost of a formation against 2 UAVs at the same wake model
FORMATION_SIZE_CASES = ("close_formation", "echelon3", "vee5", "vee9")
SAME_WAKE_TWO = "close_formation"


def _vector_cases(sizes) -> list[dict]:
    return [{"kind": "vector", "formations": n, "mode": "setpoints", "learning": "followers"} for n in sizes]


def _busy() -> subprocess.Popen:
    """A process that keeps one core busy (pure Python spin)."""
    return subprocess.Popen([sys.executable, "-c", "while True: pass"])


def _run(code_root: str | None, cases: list[dict], threads: int, busy: bool, budget_s: float, repeats: int,
         on_case=None) -> list[dict]:
    """Run ``cases`` in a fresh interpreter importing formation_env from ``code_root`` (None: this one);
    ``on_case(k)`` is called as the subprocess starts case k (its progress lines on stderr)."""
    env = dict(os.environ, NUMBA_NUM_THREADS=str(threads), OMP_NUM_THREADS=str(threads))
    src = Path(__file__).with_name("bench_cases.py")
    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / "bench_cases_script.py"
        shutil.copy(src, script)  # run outside both packages: the checkout under test is on PYTHONPATH
        root = code_root if code_root is not None else str(Path(__file__).resolve().parents[2])
        env["PYTHONPATH"] = root + os.pathsep + env.get("PYTHONPATH", "")
        env["FORMATION_ENV_BENCH_ROOT"] = root  # where a case's task_file lies
        spin = _busy() if busy else None
        errors: list[str] = []
        try:
            with open(Path(tmp) / "stdout.txt", "w+", encoding="utf-8") as stdout:
                proc = subprocess.Popen([sys.executable, str(script), json.dumps(
                    {"cases": cases, "budget_s": budget_s, "repeats": repeats})], env=env, cwd=tmp, stdout=stdout,
                    stderr=subprocess.PIPE, text=True)
                for line in proc.stderr:  # progress lines as they come; the rest is kept for an error
                    parts = line.split()
                    if len(parts) == 3 and parts[0] == "bench-case" and parts[1].isdigit():
                        if on_case is not None:
                            on_case(int(parts[1]))
                    else:
                        errors.append(line)
                returncode = proc.wait()
                stdout.seek(0)
                text = stdout.read()
        finally:
            if spin is not None:
                spin.kill()
                spin.wait()
    if returncode != 0:
        raise RuntimeError(f"bench subprocess failed ({code_root or 'this checkout'}):\n{''.join(errors)[-2000:]}")
    return json.loads(text.strip().splitlines()[-1])


def _key(case: dict) -> str:
    if case["kind"] == "machine":
        return "machine: fixed numpy workload"
    if case["kind"] == "single":
        return f"single {case['mode']} learning={case['learning']}"
    return f"vector B={case['formations']} {case['mode']} learning={case['learning']}" + (
        f" {case['scenario']}" if case.get("scenario") else "") + (
        " benefit" if case.get("benefit") else "") + (f" turbulence={case['turbulence']}" if case.get("turbulence") else "")


def baseline_commit(path: str | None) -> str | None:
    """The git commit (short hash) checked out at ``path``, or None where it is not a git work tree."""
    if path is None:
        return None
    try:
        out = subprocess.run(["git", "-C", path, "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                             timeout=30)
    except (OSError, subprocess.SubprocessError):
        return None
    if out.returncode != 0:
        return None
    return out.stdout.strip() or None


def run_benchmarks(quick: bool = False, baseline: str | None = None, busy: bool = True, log=None) -> dict:
    """Every configuration: {case: {"new": ..., "old": ..., "ratio": new/old}} for (threads, busy).
    ``log(line)``, when given, gets one progress line per measured case ("envs k/N: <config> <case>")."""
    sizes = (1, 16, 256) if quick else BATCH_SIZES
    budget, repeats = (0.2, 2) if quick else (0.6, 3)
    cases = SINGLE_CASES + _vector_cases(sizes) + [{"kind": "vector", "formations": 256, "mode": "setpoints",
                                                    "learning": "followers", "benefit": True}] + [
        # the turbulence models at sigma 1 m/s (their cost against the B = 256 case without turbulence)
        {"kind": "vector", "formations": 256, "mode": "setpoints", "learning": "followers", "turbulence": field}
        for field in TURBULENCE_CASES] + [
        {"kind": "vector", "formations": 256, "mode": "setpoints", "learning": "followers", "scenario": name}
        for name in FORMATION_SIZE_CASES] + [
        # a task written in Python (examples/custom_task.py: wake_surfing's scenario with Python reward, observation,
        # termination and metric terms) beside the built-in task it starts from
        {"kind": "vector", "formations": 256, "mode": "setpoints", "learning": "followers", "scenario": "wake_surfing"},
        {"kind": "vector", "formations": 256, "mode": "setpoints", "learning": "followers", "scenario": "fuel_slot",
         "task_file": "examples/custom_task.py"}] + [
        # the machine's own decision-to-decision spread (a fixed numpy workload), beside the env's
        {"kind": "machine"}]
    configs = [(2, False), (1, False)] + ([(2, True), (1, True)] if busy else [])
    out: dict = {"case": "formation_keeping, 2 Aerosondes, ELL wake every 50 Hz physics step, 10 Hz decisions",
                 "baseline": baseline, "baseline_commit": baseline_commit(baseline), "peers_reported": PEERS,
                 "configurations": {}}
    total = len(configs) * len(cases) * (2 if baseline else 1)
    done = [0]

    def progress(name: str, which: str):
        if log is None:
            return None

        def on_case(k: int) -> None:
            done[0] += 1
            log(f"envs {done[0]}/{total}: {name}{which} {_key(cases[k])}")

        return on_case

    for threads, is_busy in configs:
        name = f"threads={threads}" + (" busy" if is_busy else "")
        new = _run(None, cases, threads, is_busy, budget, repeats, progress(name, " (this checkout)" if baseline else ""))
        # the older code may lack newer cases (the benefit case is measured on both when possible)
        old = _run(baseline, cases, threads, is_busy, budget, repeats, progress(name, " (baseline)")) if baseline else None
        rows = {}
        for i, case in enumerate(cases):
            if case["kind"] == "machine":
                out.setdefault("machine_spread", {})[name] = {"new": new[i], **({"old": old[i]} if old else {})}
                continue
            metric = "physics_steps_per_s" if case["kind"] == "single" else "uav_physics_steps_per_s"
            if "unsupported" in new[i]:
                raise RuntimeError(f"bench case {_key(case)}: {new[i]['unsupported']}")
            row = {"new": new[i][metric]}
            if case["kind"] == "vector":
                row["uavs"] = new[i].get("uavs", 2)
                row["agent_decisions_per_s"] = new[i]["agent_decisions_per_s"]
            if "decision_max_over_min" in new[i]:  # issue 26: the slowest of 40 consecutive decisions over the fastest
                row["spread"] = new[i]["decision_max_over_min"]
                if old is not None and "decision_max_over_min" in old[i]:
                    row["spread_old"] = old[i]["decision_max_over_min"]
            if old is not None and "unsupported" not in old[i]:
                row["old"] = old[i][metric]
                row["ratio"] = row["new"] / row["old"]
            elif old is not None:
                row["old_unsupported"] = old[i]["unsupported"]
            rows[_key(case)] = row
        out["configurations"][name] = rows
    return out


def run_peers(python: str | None = None, quick: bool = False) -> dict:
    """The peers' environments (:mod:`formation_env.envs.bench_peers`) timed with the interpreter ``python`` (None:
    this one), 2 and 1 threads, nothing competing: {"python": ..., "threads=N": [row per peer]}."""
    python = python or sys.executable
    budget, repeats = (0.2, 2) if quick else (0.6, 3)
    out: dict = {"python": python}
    src = Path(__file__).with_name("bench_peers.py")
    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / "bench_peers_script.py"
        shutil.copy(src, script)  # run outside the package: the peers' interpreter need not have formation_env
        for threads in (2, 1):
            env = dict(os.environ, OMP_NUM_THREADS=str(threads), MKL_NUM_THREADS=str(threads))
            env.pop("PYTHONPATH", None)
            proc = subprocess.run([python, str(script), json.dumps({"budget_s": budget, "repeats": repeats,
                                                                   "threads": threads})],
                                  env=env, cwd=tmp, capture_output=True, text=True)
            if proc.returncode != 0:
                raise RuntimeError(f"bench peers ({python}) failed:\n{proc.stderr[-2000:]}")
            out[f"threads={threads}"] = json.loads(proc.stdout.strip().splitlines()[-1])
    return out


def format_peers(peers: dict) -> str:
    """Text lines of :func:`run_peers` results."""
    lines = [f"peers, measured in this run ({peers['python']}):"]
    confs = [k for k in peers if k.startswith("threads=")]
    for i, row in enumerate(peers[confs[0]]):
        cells = []
        for c in confs:
            r = peers[c][i]
            if "unsupported" in r:
                cells.append(f"{c}: {r['unsupported']}")
            elif "env_steps_per_s" in r:
                cells.append(f"{c}: {r['env_steps_per_s']:,.0f} env-steps/s ({r['agent_steps_per_s']:,.0f} agent-steps/s)")
            else:
                cells.append(f"{c}: {r['joint_steps_per_s']:,.0f} joint steps/s")
        version = f" {row['version']}" if "version" in row else ""
        lines.append(f"  {row['peer']}{version}, {row['case']}: " + "; ".join(cells))
    return "\n".join(lines)


def format_table(res: dict) -> str:
    """Markdown table of :func:`run_benchmarks` results."""
    confs = list(res["configurations"])
    head = "| case (physics steps/s; vector: UAV physics steps/s) | " + " | ".join(confs) + " |"
    lines = [head, "|" + "---|" * (len(confs) + 1)]
    for key in res["configurations"][confs[0]]:
        cells = []
        for c in confs:
            r = res["configurations"][c][key]
            cells.append(f"{r['new']:,.0f}" + (f" ({r['ratio']:.1f}x)" if "ratio" in r else ""))
        lines.append(f"| {key} | " + " | ".join(cells) + " |")
    # issue 26: decision-to-decision spread, the slowest of 40 consecutive decisions over the fastest
    for key in res["configurations"][confs[0]]:
        if "spread" in res["configurations"][confs[0]][key] and key.startswith("vector B=1024 "):
            cells = [f"{res['configurations'][c][key]['spread']:.2f}" + (
                f" (old {res['configurations'][c][key]['spread_old']:.2f})" if "spread_old" in res["configurations"][c][key] else "")
                for c in confs]
            lines.append(f"| {key}: max/min of 40 decisions | " + " | ".join(cells) + " |")
    # formations of 3-9 UAVs: per-UAV throughput over the 2-UAV case at the same B (1 when a UAV costs the same
    # in any formation) and the learners' decisions/s (the followers, each a row of the VecEnv)
    first = res["configurations"][confs[0]]
    two = "vector B=256 setpoints learning=followers"
    same = f"{two} {SAME_WAKE_TWO}"
    for key in first:
        if key.startswith(two + " ") and first[key].get("uavs", 2) > 2 and two in first:
            cells = []
            for c in confs:
                rows = res["configurations"][c]
                cell = f"{rows[key]['new'] / rows[two]['new']:.2f}x"
                if same in rows:  # against 2 UAVs with the same (converged) wake
                    cell += f" ({rows[key]['new'] / rows[same]['new']:.2f}x {SAME_WAKE_TWO}'s)"
                cells.append(cell + f", {rows[key]['agent_decisions_per_s']:,.0f} decisions/s")
            lines.append(f"| {key}: UAV physics steps/s over 2 UAVs' (formation_keeping; in brackets over "
                         f"{SAME_WAKE_TWO}'s, the same wake), follower decisions/s | " + " | ".join(cells) + " |")
    ms = res.get("machine_spread")
    if ms:
        lines.append("| the machine: max/min of 40 runs of a fixed numpy workload | "
                     + " | ".join(f"{ms[c]['new']['decision_max_over_min']:.2f}" if c in ms else "" for c in confs) + " |")
    return "\n".join(lines)
