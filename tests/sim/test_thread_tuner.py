"""The decision step's serial/threaded tuner (formation_env.sim.dispatch.ThreadTuner): it picks the faster
setting, re-measures the other one rarely while threads run (each re-measurement is a whole call in the
slower setting: the decision-time spikes of issue 26), backs off while serial is confirmed, and follows a
change of the machine. Kernels here are Python functions whose wall time is set by sleeping (which
releases the GIL, as the compiled kernels do)."""

import time

import pytest

import formation_env.sim.dispatch as dispatch


class _Kernel:
    """kernel(start, stop): sleeps ``per_row`` s per row plus ``per_call`` s per call; records each call's
    setting (a call covering every row is a serial run)."""

    def __init__(self, n, per_row, per_call=0.0):
        self.n, self.per_row, self.per_call, self.serial = n, per_row, per_call, []

    def __call__(self, start, stop):
        if start == 0 and stop == self.n:
            self.serial.append(True)
        time.sleep(self.per_call + self.per_row * (stop - start))


@pytest.fixture
def two_threads(monkeypatch):
    monkeypatch.setattr(dispatch, "threads", lambda: 2)


def _calls(tuner, kernel, n_calls):
    for _ in range(n_calls):
        before = len(kernel.serial)
        tuner.run(kernel, kernel.n, ())
        yield len(kernel.serial) > before


def test_threaded_faster_is_kept_without_serial_spikes(two_threads):
    tuner = dispatch.ThreadTuner()
    k = _Kernel(8, per_row=3e-3)  # serial 24 ms, threaded ~12 ms: a 12 ms margin over scheduling noise on a busy machine
    serial = list(_calls(tuner, k, 200))
    assert serial[:5] == [True, False, True, False, True]  # the warm-up measures both
    assert not any(serial[5:])  # then threads only: no serial re-measurement within EXPLORE_MAX calls
    assert dispatch.ThreadTuner.EXPLORE_MAX > 200


def test_serial_faster_backs_off_its_remeasurements(two_threads):
    tuner = dispatch.ThreadTuner()
    k = _Kernel(8, per_row=0.0, per_call=6e-3)  # every chunk pays the per-call cost: threaded (~12 ms) is slower
    serial = list(_calls(tuner, k, 240))
    threaded_after_warmup = [i + 1 for i, s in enumerate(serial) if not s and i >= 5]
    # re-measured after 32 calls, then 64, 128: the interval doubles while serial is confirmed
    assert threaded_after_warmup == [37, 101, 229]


def test_follows_the_machine_when_threads_get_slower(two_threads):
    tuner = dispatch.ThreadTuner()
    # timings a few times the scheduling noise of a busy 2-core machine (another test process beside this one)
    k = _Kernel(8, per_row=3e-3)
    list(_calls(tuner, k, 20))
    k.per_row, k.per_call = 0.0, 12e-3  # now threads lose (~48 ms against the 24 ms serial measured before): their own average rises above serial's, no waiting
    serial = list(_calls(tuner, k, 20))
    assert all(serial[8:])
