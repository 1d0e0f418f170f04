"""One input's bounds for the fuzzers: ``Hang`` after too much CPU, or far too long a wait.

The fuzzers count an input as ``hang`` when it is stopped here.  The bound is CPU seconds of
this process (``ITIMER_PROF``), so a loaded machine cannot turn a quick input into a hang;
a wall-clock alarm ten times longer still stops an input that blocks without computing
(a named pipe, a lock).
"""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Iterator

#: How much longer than the CPU bound the wall-clock backstop waits.
WALL_FACTOR = 10


class Hang(Exception):
    """An input stopped by its bound."""


def _stop(_signum, _frame):
    raise Hang()


@contextlib.contextmanager
def bounded(cpu_seconds: float) -> Iterator[None]:
    """Raise :class:`Hang` inside the block after ``cpu_seconds`` of CPU (or ten times that of wall)."""
    previous = {sig: signal.signal(sig, _stop) for sig in (signal.SIGPROF, signal.SIGALRM)}
    signal.setitimer(signal.ITIMER_PROF, cpu_seconds)
    signal.setitimer(signal.ITIMER_REAL, cpu_seconds * WALL_FACTOR)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.setitimer(signal.ITIMER_REAL, 0)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
