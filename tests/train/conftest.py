from pathlib import Path

import pytest

# Tiny runs: 2 formations, 3 s episodes, one-layer nets; a few hundred steps each.
TINY = {
    "ppo": {"n_formations": 2, "n_steps": 32, "batch_size": 32, "n_epochs": 1, "eval_freq": 128, "eval_episodes": 2,
            "checkpoint_freq": 128, "policy_kwargs": {"net_arch": [16]}, "env_kwargs": {"duration_s": 3.0}},
    "recurrent_ppo": {"n_formations": 2, "n_steps": 32, "batch_size": 32, "n_epochs": 1, "eval_freq": 128,
                      "eval_episodes": 2, "checkpoint_freq": 128,
                      "policy_kwargs": {"net_arch": [16], "lstm_hidden_size": 8}, "env_kwargs": {"duration_s": 3.0}},
    "sac": {"n_formations": 2, "buffer_size": 2000, "learning_starts": 64, "batch_size": 32, "gradient_steps": 1,
            "eval_freq": 128, "eval_episodes": 2, "checkpoint_freq": 128, "policy_kwargs": {"net_arch": [16]},
            "env_kwargs": {"duration_s": 3.0}},
    "td3": {"n_formations": 2, "buffer_size": 2000, "learning_starts": 64, "batch_size": 32, "gradient_steps": 1,
            "eval_freq": 128, "eval_episodes": 2, "checkpoint_freq": 128, "policy_kwargs": {"net_arch": [16]},
            "env_kwargs": {"duration_s": 3.0}},
}


@pytest.fixture
def tiny():
    import copy

    return lambda algo: copy.deepcopy(TINY[algo])


@pytest.fixture
def seeded_candidates(monkeypatch):
    """``seeded_candidates(step)``: ``load_policy('cand_seed<k>')`` (or another group's ``cand<x>_seed<k>``) gives the
    PID plus a constant throttle residual of ``step * k`` (a different controller per seed); every other spec loads as
    usual."""
    import numpy as np

    import train.evaluation.evaluate as ev
    from train.evaluation.evaluate import EvalPolicy

    real = ev.load_policy

    def install(step):
        def load(spec, **kw):
            if spec.startswith("cand") and "_seed" in spec:  # cand_seed<k>, or another group: candb_seed<k>
                k = int(spec.rsplit("_seed", 1)[1])
                return EvalPolicy(spec, "residual", lambda o: np.tile([0.0, 0.0, 0.0, step * k], (o.shape[0], 1)))
            return real(spec, **kw)

        monkeypatch.setattr(ev, "load_policy", load)

    return install


# --- Ray processes of a test (tests/train/test_rllib.py, tests/train/test_multinode.py) -------------

@pytest.fixture
def ray_tmpdir():
    """A private, short Ray temp dir (Unix socket paths must stay under ~100 characters); every Ray
    process started with it carries its path, which is how the tests find leftovers."""
    import shutil
    import tempfile

    path = tempfile.mkdtemp(prefix="fe-ray-", dir="/tmp")
    yield path
    shutil.rmtree(path, ignore_errors=True)


class RayProcesses:
    """The processes of one test's Ray, found by its private temp dir: every Ray daemon (GCS, raylet,
    agents, log monitor, ``ray start`` itself) carries the path on its command line, and every
    process started with ``RAY_TMPDIR`` set to it (the tests set it) inherits that variable, among
    them the Ray Client server, which has the path on neither. Workers rename themselves
    (``ray::IDLE``, ``ray::MultiAgentEnvRunner``) but are the raylet's children, so the descendants
    of those processes count too. Nothing else on the machine is touched: not other tests' Ray, not
    a user's cluster (``ray stop`` would stop every Ray process of the machine)."""

    def __init__(self, tmpdir: str) -> None:
        self.tmpdir = tmpdir

    @staticmethod
    def _stat(pid: int):
        """(state, parent pid, start time) of a process, or None once it is gone."""
        try:
            raw = Path(f"/proc/{pid}/stat").read_bytes().decode(errors="replace")
        except OSError:
            return None
        fields = raw[raw.rindex(")") + 2:].split()  # the name, in parentheses, may hold spaces
        return fields[0], int(fields[1]), int(fields[19])

    @staticmethod
    def _cmdline(pid: int) -> str:
        try:
            return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            return ""

    @staticmethod
    def _environ(pid: int) -> list[bytes]:
        try:
            return Path(f"/proc/{pid}/environ").read_bytes().split(b"\0")
        except OSError:
            return []

    def find(self) -> dict[int, tuple[int, str]]:
        """pid -> (start time, command line) of every live process of this Ray (zombies excluded)."""
        import os

        me = os.getpid()
        env_entry = f"RAY_TMPDIR={self.tmpdir}".encode()
        stats, matched = {}, set()
        for name in os.listdir("/proc"):
            if not name.isdigit() or int(name) == me:
                continue
            pid = int(name)
            st = self._stat(pid)
            if st is None or st[0] in "ZX":
                continue
            stats[pid] = st
            if self.tmpdir in self._cmdline(pid) or env_entry in self._environ(pid):
                matched.add(pid)
        children: dict[int, list[int]] = {}
        for pid, (_, ppid, _) in stats.items():
            children.setdefault(ppid, []).append(pid)
        found, todo = set(), list(matched)
        while todo:
            pid = todo.pop()
            if pid not in found:
                found.add(pid)
                todo.extend(children.get(pid, ()))
        return {pid: (stats[pid][2], self._cmdline(pid)[:160]) for pid in sorted(found)}

    def alive(self, procs: dict[int, tuple[int, str]]) -> list[int]:
        """Those of ``procs`` still running (the same process: a reused pid has another start time)."""
        return [pid for pid, (start, _) in procs.items()
                if (st := self._stat(pid)) is not None and st[0] not in "ZX" and st[2] == start]

    def left(self) -> list[str]:
        return [f"{pid}: {cmd}" for pid, (_, cmd) in self.find().items()]

    def assert_none_left(self, timeout_s: float = 600.0) -> None:
        """Waits, by pid, for every process of this test's Ray (found by its temp dir: the ones the test's own
        commands started) to exit. The test process is their subreaper (:func:`become_subreaper`, set by the
        fixture), so the Ray processes its finished commands leave are its children and are reaped with
        ``waitpid``; one that is not (no subreaper support) is watched through /proc. There is no fixed
        deadline for how fast a loaded machine winds Ray down: only a process still running after ``timeout_s``
        (10 min: a hang, not slowness) fails the test, and it is stopped first."""
        import os
        import time

        deadline = time.monotonic() + timeout_s
        while (procs := self.find()) and time.monotonic() < deadline:
            for pid in procs:
                while time.monotonic() < deadline and self.alive({pid: procs[pid]}):
                    try:
                        if os.waitpid(pid, os.WNOHANG)[0] == pid:  # our child (subreaper): reaped
                            break
                    except ChildProcessError:  # not our child: its /proc entry says when it is gone
                        pass
                    time.sleep(0.1)
                try:
                    os.waitpid(pid, os.WNOHANG)  # reap it if it became a zombie of ours
                except ChildProcessError:
                    pass
        left = self.left()
        if left:
            self.stop()
        assert not left, f"Ray processes still running {timeout_s:.0f} s after the test's commands ended: {left}"

    def stop(self, grace_s: float = 30.0) -> dict:
        """Stop this Ray's processes (and only them) in ``ray stop``'s order: the raylets, then the
        rest (agents, log monitor, autoscaler monitor, workers), then the GCS, each group with
        SIGTERM and, after its share of ``grace_s``, SIGKILL to what is left. Returns what was found,
        what needed SIGKILL and how long it took."""
        import os
        import signal
        import time

        t0 = time.perf_counter()
        procs = self.find()
        groups: list[dict] = [{}, {}, {}]
        for pid, (start, cmd) in procs.items():
            exe = cmd.split(" ", 1)[0]
            groups[0 if exe.endswith("/raylet") else 2 if exe.endswith("/gcs_server") else 1][pid] = (start, cmd)

        def signal_all(sig, which):
            for pid in self.alive(which):  # not a reused pid
                try:
                    os.kill(pid, sig)
                except OSError:
                    pass

        killed = []
        for group in groups:
            signal_all(signal.SIGTERM, group)
            deadline = time.time() + grace_s / len(groups)
            while self.alive(group) and time.time() < deadline:
                time.sleep(0.1)
            stubborn = {pid: group[pid] for pid in self.alive(group)}
            signal_all(signal.SIGKILL, stubborn)
            killed += sorted(stubborn)
        return {"found": procs, "killed": killed, "seconds": round(time.perf_counter() - t0, 1)}


@pytest.fixture
def ray_processes(ray_tmpdir):
    """:class:`RayProcesses` of the test's Ray temp dir (this process made the subreaper of what it starts)."""
    become_subreaper()
    return RayProcesses(ray_tmpdir)


def become_subreaper() -> bool:
    """Makes this process the subreaper of its descendants (Linux ``PR_SET_CHILD_SUBREAPER``): a process whose
    parent exits (the Ray daemons and workers a finished command leaves) is re-parented here, not to init, so the
    test can wait on it by pid. False where the OS has no such call."""
    import ctypes
    import sys

    if not sys.platform.startswith("linux"):
        return False
    try:
        return ctypes.CDLL(None, use_errno=True).prctl(36, 1, 0, 0, 0) == 0  # PR_SET_CHILD_SUBREAPER
    except (OSError, AttributeError):
        return False


@pytest.fixture(scope="session")
def loopback_only_prefix() -> list[str]:
    """A command prefix that runs a command in a fresh network namespace whose only interface is
    loopback, where possible (root, or unprivileged user namespaces); [] elsewhere. Ray's servers
    listen on every interface and address the node by the machine's IP; there the only interface is
    127.0.0.1, so nothing of the test's Ray is reachable from outside this machine, nor can it reach
    out. Every command run under one prefix gets a namespace of its own."""
    import shutil
    import subprocess

    if not (shutil.which("unshare") and shutil.which("ip")):
        return []
    for flags in (["-n"], ["-r", "-n"]):
        try:
            ok = subprocess.run(["unshare", *flags, "ip", "link", "set", "lo", "up"], capture_output=True,
                                timeout=20).returncode == 0
        except (OSError, subprocess.SubprocessError):
            ok = False
        if ok:
            return ["unshare", *flags, "sh", "-c", 'ip link set lo up && exec "$@"', "sh"]
    return []
