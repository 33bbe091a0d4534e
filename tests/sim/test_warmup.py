"""formation_env.sim.warmup: every stage runs, the wake's, the PID's and the energy account's in a second process when
asked (on a warm cache here, so each stage loads its kernels; the compile itself is the suite's own first step after make
install); every task flies one compiled decision step."""

import io

import pytest

from formation_env.sim import Simulation
from formation_env.sim import warmup


def _stage_lines(text: str, what: str) -> list[str]:
    """The progress lines of the stage named ``what`` (its position in the report depends on the processes)."""
    n = len(warmup.STAGES)
    starts = [ln.strip() for ln in text.splitlines() if ln.strip().startswith("[") and f"/{n}] compiling {what}" in ln]
    assert len(starts) == 1, text
    tag = starts[0].split("]")[0] + "]"
    return [ln for ln in text.splitlines() if ln.strip().startswith(tag)]


@pytest.mark.parametrize("processes", [1, 2])
def test_warm_up_runs_every_stage_and_the_second_process(processes):
    out = io.StringIO()
    seconds = warmup.warm_up(Simulation, out, processes=processes)
    text = out.getvalue()
    assert seconds > 0
    for k, (what, _) in enumerate(warmup.STAGES):  # each stage starts and ends, once
        lines = _stage_lines(text, what)
        assert any("done in" in ln for ln in lines), text
        assert ("second process" in lines[0]) == (processes == 2 and k in warmup.SECOND_PROCESS_STAGES), text
    assert "failed" not in text, text  # the second process flew its stages (exit status 0)
    assert warmup.is_warm()


def test_every_task_flies_one_compiled_decision_step():
    # the thesis's lattice and the energy tasks' converged wake (the sheet law, the residual table of pairs) are
    # values of the same types: one specialisation of each entry point serves both, so the warm-up compiles it once
    import numpy as np

    from formation_env.sim import EnvConfig
    from formation_env.sim.step import decide_packed, refresh_packed

    for name in ("formation_keeping", "close_formation", "wake_surfing", "vee5", "tracking"):
        sim = Simulation(EnvConfig(scenario=name, compute_benefit=True, duration_s=0.2), batch_size=1)
        sim.reset(seeds=[0])
        sim.step(np.zeros((1, sim.n_agents, 4)))
    assert len(decide_packed.signatures) == 1 and len(refresh_packed.signatures) == 1, \
        (decide_packed.signatures, refresh_packed.signatures)


def test_processes_out_of_range_is_refused():
    with pytest.raises(ValueError, match="processes must be 1 or 2, got 3"):
        warmup.warm_up(Simulation, None, processes=3)


def test_a_failed_second_process_is_reported_and_its_stage_compiled_here(monkeypatch):
    import subprocess
    import sys
    import tempfile

    def failing():
        log = tempfile.TemporaryFile()
        return subprocess.Popen([sys.executable, "-c", "import sys; sys.stderr.write('boom\\n'); sys.exit(3)"],
                                stderr=log), log

    monkeypatch.setattr(warmup, "_second_process", failing)
    out = io.StringIO()
    warmup.warm_up(Simulation, out, processes=2)
    text = out.getvalue()
    assert "the second process failed (compiling here instead): ['boom']" in text, text
    for k in warmup.SECOND_PROCESS_STAGES:
        assert any("done in" in ln for ln in _stage_lines(text, warmup.STAGES[k][0])), text
