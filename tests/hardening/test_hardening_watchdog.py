"""The fuzzers' bound counts CPU seconds, so a loaded machine cannot make a quick input hang."""

from __future__ import annotations

import signal
import time

import pytest

from tests.hardening.watchdog import Hang, bounded


def test_a_busy_input_is_stopped_after_its_cpu_seconds():
    start = time.process_time()
    with pytest.raises(Hang), bounded(0.2):
        while True:
            pass
    assert 0.15 <= time.process_time() - start < 1.0  # the profiling timer and process_time count apart


def test_waiting_is_not_cpu_but_the_wall_backstop_stops_it():
    start = time.perf_counter()
    with pytest.raises(Hang), bounded(0.02):
        time.sleep(5)
    assert 0.2 <= time.perf_counter() - start < 1.0  # ten times the CPU bound, not the CPU bound


def test_a_quick_input_leaves_no_timer_behind():
    before = signal.getsignal(signal.SIGALRM)
    with bounded(0.5):
        pass
    assert signal.getitimer(signal.ITIMER_PROF) == (0.0, 0.0)
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)
    assert signal.getsignal(signal.SIGALRM) is before
