"""Background work for the window: a serial job queue for the model, cancellable tasks.

:class:`JobQueue` runs model jobs (re-derive, regrow, undo...) one at a time on
a worker thread, so the explorer is only ever changed by one thread and the
UI never waits for a derivation.  Jobs that share a ``key`` (e.g. every edit
of the grammar text) replace each other while still queued, and a finished
job that a newer job of the same key has overtaken is marked ``stale``: the
window drops its result.

:class:`Task` is long work (variant sweeps, thumbnails) with a progress
callback and a cancel flag, run on a :class:`QThreadPool`; the window shows
its progress in a progress bar with a Cancel button.

Signals are emitted from the worker thread and delivered, queued, in the GUI
thread.
"""

from __future__ import annotations

import collections
import itertools
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from PySide6.QtCore import QObject, QRunnable, QThreadPool, Signal

if TYPE_CHECKING:
    from ramure.app.desktop.state import Snapshot
    from ramure.app.model import Explorer


@dataclass(eq=False)
class Job:
    """One unit of model work and, once run, its outcome."""

    id: int
    name: str
    fn: Callable[[Explorer], Any]
    key: str | None = None
    result: Any = None  # what fn returned: its type is the job's (a RegenResult, a mesh, ...)
    error: BaseException | None = None
    details: str = ""  # traceback text of an unexpected error (for the dialog's details)
    snapshot: Snapshot | None = None
    stale: bool = False
    seconds: float = 0.0
    submitted: float = field(default_factory=time.perf_counter)


class _Runnable(QRunnable):
    def __init__(self, fn) -> None:
        super().__init__()
        self._fn = fn
        self.setAutoDelete(True)

    def run(self) -> None:
        self._fn()


class JobQueue(QObject):
    """Run jobs one at a time, in submission order, on one worker thread.

    ``execute(job)`` runs in the worker thread and fills ``job.result``,
    ``job.error`` and ``job.snapshot``; :attr:`finished` is then emitted.
    """

    finished = Signal(object)  # the Job
    busy_changed = Signal(bool)

    def __init__(self, execute: Callable[[Job], None], parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._execute = execute
        self._pool = QThreadPool(self)
        self._pool.setMaxThreadCount(1)
        self._queue: collections.deque[Job] = collections.deque()
        self._mutex = threading.Lock()
        self._ids = itertools.count(1)
        self._latest: dict[str, int] = {}  # key -> id of the newest job with that key
        self._outstanding = 0  # submitted and not yet delivered
        self.finished.connect(self._delivered)

    @property
    def idle(self) -> bool:
        """True when no job is queued, running or waiting to be delivered."""
        return self._outstanding == 0

    def submit(self, name: str, fn: Callable[[Explorer], Any], key: str | None = None) -> Job:
        """Queue ``fn(explorer)``; a queued job with the same ``key`` is replaced."""
        job = Job(next(self._ids), name, fn, key)
        with self._mutex:
            if key is not None:
                self._latest[key] = job.id
                for i, old in enumerate(self._queue):
                    if old.key == key:
                        self._queue[i] = job  # the old one never runs
                        break
                else:
                    self._queue.append(job)
                    self._outstanding += 1
            else:
                self._queue.append(job)
                self._outstanding += 1
            first = self._outstanding == 1
        if first:
            self.busy_changed.emit(True)
        self._pool.start(_Runnable(self._run_next))
        return job

    def _run_next(self) -> None:
        with self._mutex:
            if not self._queue:
                return  # a replaced job's runnable
            job = self._queue.popleft()
        t0 = time.perf_counter()
        try:
            self._execute(job)
        except BaseException as exc:  # never let a worker die silently
            job.error = exc
            job.details = traceback.format_exc()
        job.seconds = time.perf_counter() - t0
        with self._mutex:
            job.stale = job.key is not None and self._latest.get(job.key) != job.id
        self.finished.emit(job)

    def _delivered(self, job) -> None:
        self._outstanding -= 1
        if self._outstanding == 0:
            self.busy_changed.emit(False)

    def wait(self, msecs: int = -1) -> bool:
        """Block until the worker thread is done (for shutdown); signals still need the event loop."""
        return self._pool.waitForDone(msecs)


class Cancelled(Exception):
    """Raised inside a task's function when it was cancelled."""


class Task(QObject):
    """Cancellable long work: ``fn(progress, cancelled)`` runs on a thread pool.

    ``progress(done, total, text="")`` reports progress; ``cancelled()`` is
    True once :meth:`cancel` was called (the function should then stop, e.g.
    by raising :class:`Cancelled`).  Exactly one of :attr:`done`,
    :attr:`failed` or :attr:`was_cancelled` is emitted at the end.
    """

    progressed = Signal(int, int, str)
    done = Signal(object)
    failed = Signal(object, str)  # exception, traceback text
    was_cancelled = Signal()

    def __init__(
        self, name: str, fn: Callable[[Callable[..., None], Callable[[], bool]], Any], parent: QObject | None = None
    ) -> None:
        super().__init__(parent)
        self.name = name
        self._fn = fn
        self._cancel = threading.Event()
        self.running = False
        self.result: Any = None
        self.quiet = False  # True: the window's status bar does not follow this task (a preview)
        self.label = ""  # what the status bar says while it runs

    @property
    def cancel_event(self) -> threading.Event:
        """The event set when the task is cancelled (for work that waits on it)."""
        return self._cancel

    def cancel(self) -> None:
        """Ask the task to stop (its work checks :meth:`cancelled`)."""
        self._cancel.set()

    def cancelled(self) -> bool:
        """True once cancelled."""
        return self._cancel.is_set()

    def start(self, pool: QThreadPool | None = None) -> Task:
        """Run the task on ``pool`` (Qt's global pool by default); returns it."""
        self.running = True
        (pool or QThreadPool.globalInstance()).start(_Runnable(self._run))
        return self

    def _progress(self, done, total, text: str = ""):
        if self._cancel.is_set():
            raise Cancelled()
        self.progressed.emit(int(done), int(total), str(text))

    def _run(self) -> None:
        try:
            result = self._fn(self._progress, self.cancelled)
        except Cancelled:
            self.running = False
            self.was_cancelled.emit()
            return
        except BaseException as exc:
            self.running = False
            if self._cancel.is_set():
                self.was_cancelled.emit()
            else:
                self.failed.emit(exc, traceback.format_exc())
            return
        self.running = False
        if self._cancel.is_set():
            self.was_cancelled.emit()
        else:
            self.result = result
            self.done.emit(result)
