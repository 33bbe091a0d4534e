"""formation_env.sim.warmup: every stage runs, the second decision step in a second process when asked (on a warm
cache here, so each stage loads its kernels; the compile itself is the suite's own first step after make install)."""

import io

import pytest

from formation_env.sim import Simulation
from formation_env.sim import warmup


def _stage_lines(text: str, k: int) -> list[str]:
    return [ln for ln in text.splitlines() if ln.strip().startswith(f"[{k}/{len(warmup.STAGES)}]")]


@pytest.mark.parametrize("processes", [1, 2])
def test_warm_up_runs_every_stage_and_the_second_process(processes):
    out = io.StringIO()
    seconds = warmup.warm_up(Simulation, out, processes=processes)
    text = out.getvalue()
    assert seconds > 0
    for k in range(1, len(warmup.STAGES) + 1):  # each stage starts and ends
        lines = _stage_lines(text, k)
        assert any("compiling" in ln for ln in lines) and any("done in" in ln for ln in lines), text
    second = _stage_lines(text, warmup.SECOND_PROCESS_STAGE + 1)[0]
    assert ("second process" in second) == (processes == 2), text
    assert "failed" not in text, text  # the second process flew its stage (exit status 0)
    assert warmup.is_warm()


def test_the_two_decision_steps_are_separate_stages():
    # the second process compiles the energy tasks' step; the thesis's step stays in the first one
    names = [fn.__name__ for _, fn in warmup.STAGES]
    assert names[warmup.SECOND_PROCESS_STAGE] == "_decision_energy" and "_decision_thesis" in names


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
    assert any("done in" in ln for ln in _stage_lines(text, warmup.SECOND_PROCESS_STAGE + 1))
