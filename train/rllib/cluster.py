"""Where Ray runs: the dependency check, the ``--address`` forms and joining (or starting) Ray.

``None`` / ``"local"``: a private Ray instance on this machine; ``"auto"``: the cluster this machine
belongs to; ``"HOST:PORT"``: the head node of an existing cluster (its GCS port). Ray is imported only
inside functions."""

from __future__ import annotations

import os
import socket
from collections.abc import Callable

from formation_env.errors import ClusterUnreachableError, MissingDependencyError

__all__ = ["require_rllib", "parse_address", "check_reachable", "connect", "runner_node", "ClusterUnreachableError",
           "DISTRIBUTED_INSTALL"]

DISTRIBUTED_INSTALL = 'pip install -e ".[distributed]"'
# Ray puts the driver's script directory and working directory first on each worker's sys.path, where a user's own
# train.py or agents/ would stand in for the project's packages when a worker unpickles the env: each worker binds
# the names to the project's packages before it runs anything (formation_env.own_packages)
WORKER_RUNTIME_ENV = {"worker_process_setup_hook": "formation_env.own_packages.bind"}


def require_rllib() -> None:
    """Raise MissingDependencyError (with the install command) unless Ray RLlib and torch import."""
    try:
        import ray  # noqa: F401
        import ray.rllib  # noqa: F401
        import torch  # noqa: F401
    except ImportError as exc:
        raise MissingDependencyError(
            f"the RLlib backend needs Ray RLlib, which is not installed here ({exc}); install the optional "
            f"extra with: {DISTRIBUTED_INSTALL}") from exc

def parse_address(address: str | None):
    """``None`` (a local instance), ``"auto"`` or ``(host, port)``; ValueError naming a malformed one."""
    if address is None or address == "local":
        return None
    if not isinstance(address, str) or not address.strip():
        raise ValueError(f"--address must be 'auto', 'local' or HOST:PORT, got {address!r}")
    address = address.strip()
    if address == "auto":
        return "auto"
    if "://" in address:
        raise ValueError(f"--address {address!r}: give the head's GCS address HOST:PORT (e.g. 10.0.0.5:6379) or "
                         "'auto' on a cluster node; Ray Client (ray://) and dashboard (http://) addresses are not "
                         "supported")
    host, sep, port = address.rpartition(":")
    host = host.strip("[]")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"--address must be 'auto', 'local' or HOST:PORT (e.g. 10.0.0.5:6379), got {address!r}")
    return host, int(port)


# The HTTP/2 client preface and an empty SETTINGS frame: a gRPC server (Ray's GCS is one) answers with
# a SETTINGS frame (9-byte header, type 4); an HTTP/1 server, a dashboard or a database answers otherwise.
_H2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + b"\x00\x00\x00\x04\x00\x00\x00\x00\x00"


def check_reachable(host: str, port: int, timeout_s: float = 5.0) -> None:
    """Check that ``host:port`` accepts TCP connections and speaks gRPC, as a Ray head's GCS port
    does, so that a wrong address fails in seconds with a clear message (``ray.init`` itself retries
    for about a minute on a closed port, and for longer on a port where something else listens)."""
    try:
        with socket.create_connection((host, port), timeout=timeout_s) as sock:
            sock.settimeout(timeout_s)
            sock.sendall(_H2_PREFACE)
            head = b""
            try:
                while len(head) < 9 and (chunk := sock.recv(9 - len(head))):
                    head += chunk
            except (socket.timeout, ConnectionResetError):
                pass
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise ClusterUnreachableError(
            f"cannot reach a Ray cluster at {host}:{port} ({reason}). Start its head node with "
            f"`ray start --head --port={port}`, check that this machine can reach that port, or leave out "
            f"--address to train on a local Ray instance") from exc
    if os.environ.get("RAY_USE_TLS", "0").lower() in ("1", "true"):
        return  # a TLS cluster answers the plaintext preface with a TLS alert; the TCP check is what we can do
    if len(head) < 9 or head[3] != 0x04:
        raise ClusterUnreachableError(
            f"{host}:{port} accepts connections but is not a Ray head's GCS port (it does not speak gRPC; "
            f"answered {head[:16]!r}). Give the port the head was started with (`ray start --head --port=P`, "
            "6379 by default); the dashboard (8265) and Ray Client (10001) ports are not it")


def _use_cluster_token() -> None:
    """Ray >= 2.5x protects clusters with a token, but a process joining one only sends it when
    RAY_AUTH_MODE=token; when a token is at hand (RAY_AUTH_TOKEN, RAY_AUTH_TOKEN_PATH or
    ~/.ray/auth_token, the head's copy) and the mode is unset, send it."""
    if os.environ.get("RAY_AUTH_MODE") is not None:
        return  # the user chose
    try:  # Ray's own switch also refreshes its cached config, which an env variable alone does not
        from ray._private.authentication.authentication_token_setup import (
            maybe_enable_token_auth_if_token_available,
        )
    except ImportError:  # a Ray without token auth: nothing to send
        return
    maybe_enable_token_auth_if_token_available(warn_if_disabled=False)


def _join(address: str, label: str) -> None:
    import ray

    _use_cluster_token()
    try:
        ray.init(address=address, logging_level="ERROR", runtime_env=WORKER_RUNTIME_ENV)
    except (ConnectionError, TimeoutError, RuntimeError) as exc:
        chain, e = [], exc
        while e is not None:
            chain.append(f"{type(e).__name__}: {e}")
            e = e.__cause__ or e.__context__
        text = " <- ".join(chain)
        if "auth" in text.lower() and "token" in text.lower():
            raise ClusterUnreachableError(
                f"the Ray cluster at {label} refused this machine's authentication token: copy the head's "
                "~/.ray/auth_token here (or set RAY_AUTH_TOKEN) and set RAY_AUTH_MODE=token") from exc
        if label == "auto":
            raise ClusterUnreachableError(
                "--address auto: no running Ray cluster found on this machine (start one with `ray start --head`, "
                "join this machine with `ray start --address=HEAD:6379`, set RAY_ADDRESS, or leave out --address "
                f"for a local instance): {exc}") from exc
        raise ClusterUnreachableError(f"could not join the Ray cluster at {label}: {text[:600]}") from exc


def connect(address: str | None = None, *, num_cpus: int | None = None, log: Callable[[str], None] = print) -> bool:
    """Connect to (or start) Ray. Returns True when this call started a local instance (the caller
    shuts it down). A Ray already initialised in this process is reused as it is."""
    require_rllib()
    import ray

    target = parse_address(address)
    if ray.is_initialized():
        return False
    if num_cpus is not None and target is not None:
        raise ValueError("--num-cpus applies only to a local Ray instance (without --address); a cluster has "
                         "the CPUs its nodes were started with")
    if target is None:
        # A private instance: address="local" so that a RAY_ADDRESS in the environment is not joined
        # instead, and no dashboard. Ray addresses the node by this machine's IP (it turns a requested
        # 127.0.0.1 into that) and its servers listen on every interface; its token authentication, on
        # by default, guards them.
        ray.init(address="local", num_cpus=num_cpus, include_dashboard=False, logging_level="ERROR",
                 configure_logging=True, runtime_env=WORKER_RUNTIME_ENV)
        node = ray.nodes()[0].get("NodeManagerAddress", "?")
        log(f"started a local Ray instance ({int(ray.cluster_resources().get('CPU', 0))} CPUs, node address {node})")
        return True
    if target == "auto":
        _join("auto", "auto")
    else:
        host, port = target
        check_reachable(host, port)
        _join(f"{host}:{port}", f"{host}:{port}")
    res = ray.cluster_resources()
    log(f"joined the Ray cluster at {address} ({len(ray.nodes())} node(s), {int(res.get('CPU', 0))} CPUs)")
    return False


def runner_node(runner) -> dict:
    """Where an RLlib env runner lives: ``{"runner": its index, "node_id": the Ray node's id (hex),
    "node_ip": the node's IP}``. The training loop calls it inside each runner
    (``EnvRunnerGroup.foreach_env_runner``); it lives here, in a module that imports little, because
    every runner imports it by name."""
    import ray

    return {"runner": int(runner.worker_index or 0), "node_id": ray.get_runtime_context().get_node_id(),
            "node_ip": ray.util.get_node_ip_address()}
