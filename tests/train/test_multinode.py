"""A real multi-node Ray run (issue 26, item 4): a two-node Ray cluster on this machine, on loopback,
trains the RLlib backend for 2 iterations with one env runner on each node, checked by node id.

The cluster is two ``ray start`` processes, as on a real cluster: a head (``ray start --head``, 1 CPU,
custom resource ``fe_head_node``) and a second node joining it (``ray start --address``, 1 CPU,
``fe_worker_node``), each with its own temp dir and its own ports. Both offer one ``fe_runner_slot``
and every env runner asks for one (``custom_resources_per_env_runner``), so the two runners must land
on different nodes whatever the nodes' CPU counts. Training goes through the command line as a user
runs it (``formation-env train --backend rllib --address 127.0.0.1:PORT``); the backend records, in
``summary.json``, the node id each env runner reported from inside itself.

The scenario is ``vee``: five UAVs, four learning followers sharing one policy. (Issue 25's N-UAV tasks
do not exist yet; vee is the largest formation there is.)

Layout: the test runs this file as a script (``python test_multinode.py``) inside a network namespace
whose only interface is loopback, where the machine allows one (``loopback_only_prefix``); the script
starts the two nodes, reads their ids, trains, and reports in a JSON file. The cluster's daemons
outlive the script; the test stops them by process id (``ray_processes``, tests/train/conftest.py: the
processes carrying the test's Ray temp dir on their command line or in their environment, and their
children), in ``ray stop``'s order, but never with ``ray stop``, which stops every Ray process on the
machine. The cluster uses a fresh token (RAY_AUTH_MODE=token, RAY_AUTH_TOKEN), so ~/.ray is left alone.

Skips, with the reason, where Ray cannot start: no ``ray`` command, ``ray start`` failing, or the two
nodes not forming a cluster within a minute. FORMATION_ENV_REQUIRE_RAY_CLUSTER=1 turns those skips into
failures (for CI, where the cluster must come up).
"""

from __future__ import annotations

import json
import os
import secrets
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SCENARIO = "vee"  # 5 UAVs; 4 followers learn
FOLLOWERS = 4
ITERATIONS = 2
BATCH = 200  # env steps per iteration (100 per runner)
# Tiny PPO (as in test_rllib.py), plus the custom resource that puts one env runner on each node.
CONFIG = {"training": {"train_batch_size_per_learner": BATCH, "minibatch_size": 100, "num_epochs": 1},
          "model": {"fcnet_hiddens": [16]}, "env_kwargs": {"duration_s": 3.0}, "checkpoint_every": 0,
          "custom_resources_per_env_runner": {"fe_runner_slot": 1}}
HEAD_RESOURCES = {"fe_head_node": 1, "fe_runner_slot": 1}
WORKER_RESOURCES = {"fe_worker_node": 1, "fe_runner_slot": 1}
REQUIRE_ENV = "FORMATION_ENV_REQUIRE_RAY_CLUSTER"


def _ray_cli() -> str | None:
    """The ``ray`` command of the Python running the tests (the venv's), else one on PATH."""
    own = Path(sys.executable).parent / "ray"
    return str(own) if own.is_file() and os.access(own, os.X_OK) else shutil.which("ray")


def test_two_node_ray_cluster_trains_with_env_runners_on_both_nodes(tmp_path, ray_tmpdir, ray_processes,
                                                                    loopback_only_prefix):
    pytest.importorskip("ray.rllib", reason="needs the 'distributed' extra (ray[rllib]); `make test` installs it")
    required = os.environ.get(REQUIRE_ENV, "") not in ("", "0")

    def cannot_start(reason: str):
        if required:
            pytest.fail(f"{reason} ({REQUIRE_ENV} is set)")
        pytest.skip(reason)

    ray_cli = _ray_cli()
    if ray_cli is None:
        cannot_start("no `ray` command (the 'distributed' extra installs it)")
    (tmp_path / "tiny.yml").write_text(json.dumps(CONFIG))  # JSON is YAML
    result = tmp_path / "cluster.json"
    env = dict(os.environ, RAY_TMPDIR=ray_tmpdir, PYTHONPATH=str(REPO), RAY_AUTH_MODE="token",
               RAY_AUTH_TOKEN=secrets.token_hex(32), RAY_USAGE_STATS_ENABLED="0", FE_RAY_CLI=ray_cli)
    for name in ("RAY_ADDRESS", "RAY_AUTH_TOKEN_PATH"):
        env.pop(name, None)
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(loopback_only_prefix + [sys.executable, str(Path(__file__).resolve()), str(tmp_path)],
                              cwd=tmp_path, env=env, capture_output=True, text=True, timeout=420)
        wall = time.perf_counter() - t0
    finally:
        # The nodes' daemons outlive the script: stop them by process id, whatever happened above.
        stopped = ray_processes.stop()
        res = json.loads(result.read_text()) if result.is_file() else {}
    out = proc.stdout[-3000:] + proc.stderr[-3000:]
    assert proc.returncode == 0 and "timings_s" in res, out
    if "cannot_start" in res:
        cannot_start(res["cannot_start"])
    train = res["train"]
    assert train["returncode"] == 0, train["output"]

    # Both nodes were up, the teardown found their daemons, and nothing of this cluster is left.
    head, worker = res["nodes"]["head"], res["nodes"]["worker"]
    assert head != worker
    cmds = [cmd for _, cmd in stopped["found"].values()]
    assert sum("gcs_server" in c for c in cmds) == 1 and sum("raylet/raylet" in c for c in cmds) == 2, cmds
    ray_processes.assert_none_left(timeout_s=5.0)
    for node in (head, worker):  # processes carrying a node's id (the Ray Client server has the head's)
        left = type(ray_processes)(node).left()
        assert not left, left

    # The env runners ran on both nodes: each reported its node id from inside itself.
    run = tmp_path / "run"
    summary = json.loads((run / "summary.json").read_text())
    placement = {p["runner"]: p["node_id"] for p in summary["env_runner_nodes"]}
    assert sorted(placement) == [1, 2] and len(summary["env_runner_nodes"]) == 2, summary["env_runner_nodes"]
    assert set(placement.values()) == {head, worker} and summary["nodes_used"] == 2
    ips = {p["node_ip"] for p in summary["env_runner_nodes"]}
    assert len(ips) == 1, ips  # two nodes, one machine
    if loopback_only_prefix:  # in the namespace loopback is the only address there is
        assert ips == {"127.0.0.1"}
    assert "joined the Ray cluster at 127.0.0.1:" in train["output"] and "2 node(s)" in train["output"]

    # Two iterations of the N-UAV task: 4 followers acted at every env step.
    rows = (run / "progress.csv").read_text().splitlines()
    assert len(rows) == 1 + ITERATIONS
    header = rows[0].split(",")
    last = dict(zip(header, rows[-1].split(",")))
    assert int(last["iteration"]) == ITERATIONS and int(last["env_steps_lifetime"]) == ITERATIONS * BATCH
    assert int(last["agent_steps"]) == FOLLOWERS * int(last["env_steps"])
    assert summary["iterations"] == ITERATIONS and summary["modules"] == ["shared"]
    assert (Path(summary["checkpoint"]) / "formation_env.json").is_file()

    # What docs/distributed.md reports (shown with pytest -rP / -s).
    print(json.dumps({"test_wall_s": round(wall, 1), "timings_s": res["timings_s"], "nodes": res["nodes"],
                      "env_runner_nodes": summary["env_runner_nodes"], "progress": rows,
                      "processes_stopped": [c[:110] for c in cmds], "stop_s": stopped["seconds"],
                      "sigkilled": [stopped["found"][pid][1] for pid in stopped["killed"]],
                      "loopback_namespace": bool(loopback_only_prefix)}, indent=1))


def test_custom_resources_per_env_runner_are_checked(tmp_path, monkeypatch):
    pytest.importorskip("ray.rllib", reason="needs the 'distributed' extra (ray[rllib]); `make test` installs it")
    import ray

    from train.rllib.backend import RLlibTrainConfig, build_algo_config, train_rllib

    cfg = RLlibTrainConfig(scenario=SCENARIO, custom_resources_per_env_runner={"fe_runner_slot": 1})
    assert build_algo_config(cfg).custom_resources_per_env_runner == {"fe_runner_slot": 1}
    for bad, msg in (({"CPU": 1}, "'CPU' is one of Ray's built-in resources"),
                     ({"slot": 0}, r"\['slot'\] must be a finite number > 0, got 0"),
                     ({"slot": float("inf")}, "finite number > 0, got inf"),
                     ({"": 1}, "non-empty strings, got ''"),
                     (["slot"], "must be a mapping .* got list")):
        with pytest.raises(ValueError, match=msg):
            RLlibTrainConfig(scenario=SCENARIO, custom_resources_per_env_runner=bad)
    # A local instance offers no custom resources: the runners would wait forever, so it is refused
    # before Ray starts and before anything is written.
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    with pytest.raises(ValueError, match="a local Ray instance does not offer"):
        train_rllib(scenario=SCENARIO, iterations=1, out_dir=tmp_path / "run", log=lambda m: None,
                    overrides={"custom_resources_per_env_runner": {"fe_runner_slot": 1}})
    assert not ray.is_initialized() and not (tmp_path / "run").exists()


# --- the script the test runs (inside the loopback-only namespace, where there is one) -------------

def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _run(cmd: list[str], timeout: float) -> tuple[int, str]:
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired as exc:
        return 124, f"timed out after {timeout:.0f} s: {exc.stdout or ''}{exc.stderr or ''}"
    return p.returncode, p.stdout + p.stderr


def _start_cluster_and_train(work: Path, report: dict, save) -> None:
    """Start the head and the second node, read their ids, train; fills ``report`` (saved at each
    step, so that the test learns the address and node ids even if this script dies). The daemons
    are left running: the test stops them."""
    ray_cli, tmp = os.environ["FE_RAY_CLI"], os.environ["RAY_TMPDIR"]
    timings: dict[str, float] = {}
    gcs_port = _free_port()
    address = f"127.0.0.1:{gcs_port}"
    report.update(address=address, timings_s=timings)
    save()
    common = ["--node-ip-address", "127.0.0.1", "--num-cpus", "1", "--num-gpus", "0",
              "--min-worker-port", "0", "--max-worker-port", "0",  # workers take free ports (two raylets here)
              "--object-store-memory", str(100 * 1024 * 1024), "--disable-usage-stats"]
    # The dashboard agent's port is fixed (52365) unless given: one each.
    # No dashboard. `ray start --head` always starts a Ray Client server (the backend does not use
    # it; Ray refuses port 0): on a free port, not the fixed 10001.
    head = [ray_cli, "start", "--head", "--port", str(gcs_port), "--temp-dir", f"{tmp}/h",
            "--include-dashboard", "false", "--ray-client-server-port", str(_free_port()),
            "--dashboard-agent-listen-port", str(_free_port()), "--resources", json.dumps(HEAD_RESOURCES), *common]
    worker = [ray_cli, "start", "--address", address, "--temp-dir", f"{tmp}/w",
              "--dashboard-agent-listen-port", str(_free_port()), "--include-log-monitor", "false",
              "--resources", json.dumps(WORKER_RESOURCES), *common]
    for name, cmd in (("head", head), ("worker", worker)):
        t = time.perf_counter()
        rc, out = _run(cmd, timeout=120)
        timings[f"start_{name}"] = round(time.perf_counter() - t, 1)
        save()
        if rc != 0:
            report["cannot_start"] = f"`ray start` of the {name} node failed (exit {rc}): {out[-1500:]}"
            return

    t = time.perf_counter()
    nodes = _node_ids(address)
    timings["wait_nodes"] = round(time.perf_counter() - t, 1)
    if isinstance(nodes, str):
        report["cannot_start"] = nodes
        return
    report["nodes"] = nodes
    save()

    cmd = [sys.executable, "-m", "formation_env.cli", "train", "--backend", "rllib", "--scenario", SCENARIO,
           "--address", address, "--num-env-runners", "2", "--iterations", str(ITERATIONS), "--seed", "0",
           "--config", str(work / "tiny.yml"), "--out", str(work / "run")]
    t = time.perf_counter()
    rc, out = _run(cmd, timeout=300)
    timings["train"] = round(time.perf_counter() - t, 1)
    report["train"] = {"returncode": rc, "output": out[-6000:]}


def _node_ids(address: str, timeout_s: float = 60.0) -> dict | str:
    """{"head": id, "worker": id} once both nodes are alive in the GCS, else why not."""
    import ray

    try:
        ray.init(address=address, logging_level="ERROR", log_to_driver=False)
    except Exception as exc:  # noqa: BLE001 - reported as the skip reason
        return f"could not connect to the two-node cluster at {address}: {type(exc).__name__}: {exc}"
    try:
        deadline = time.time() + timeout_s
        while True:
            alive = [n for n in ray.nodes() if n.get("Alive")]
            ids = {role: n["NodeID"] for n in alive for role in ("head", "worker")
                   if n.get("Resources", {}).get(f"fe_{role}_node")}
            if len(ids) == 2 or time.time() > deadline:
                break
            time.sleep(0.5)
        if len(ids) != 2:
            return f"the two nodes did not form a cluster within {timeout_s:.0f} s (alive: {len(alive)})"
        return ids
    finally:
        ray.shutdown()


if __name__ == "__main__":
    work_dir = Path(sys.argv[1])
    report: dict = {}

    def save() -> None:
        tmp = work_dir / "cluster.json.tmp"
        tmp.write_text(json.dumps(report, indent=1))
        tmp.replace(work_dir / "cluster.json")

    _start_cluster_and_train(work_dir, report, save)
    save()
