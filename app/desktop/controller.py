"""The window's link to the model: one :class:`~ramure.app.model.Explorer`, changed by one worker.

:class:`Controller` owns the explorer and a :class:`~ramure.app.desktop.workers.JobQueue`.
Everything that re-derives or edits the plant (grammar text, constants,
derivation count, regrow, prune, undo, sessions) is a job run in the worker
thread under the model lock; each job ends with a fresh
:class:`~ramure.app.desktop.state.Snapshot`, which :attr:`Controller.plant_changed`
hands to the widgets.  Quick reads and selection changes run in the GUI
thread under the same lock, and only when the plant on screen is the
model's current plant (so a click never lands on a plant that is gone).

Errors: a :class:`~ramure.lsys.errors.RamureError` (bad input) leaves the model as
it was and is reported through :attr:`refused`; anything else is a bug,
reported through :attr:`crashed` with its traceback; in both cases the last
good plant stays on screen.
"""

from __future__ import annotations

import os
import pathlib
import threading
import time
import traceback
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, TypeVar

from PySide6.QtCore import QObject, Signal

from ramure.app.desktop import state
from ramure.app.desktop.workers import JobQueue
from ramure.app.model import Explorer, leaves_in_rectangle, warm_up_in_background
from ramure.errors import RamureError

if TYPE_CHECKING:
    import numpy as np

    from ramure.app.desktop.state import Snapshot
    from ramure.app.desktop.workers import Job
    from ramure.app.history import Timeline
    from ramure.lsys.regeneration.mincut import CutResult

T = TypeVar("T")


#: Plants up to this many tree nodes get their cut preview at once, in the GUI thread.
INLINE_PREVIEW_NODES = 200_000


class Busy(RamureError):
    """The model is being changed by a job; the request was not applied."""


class Controller(QObject):
    """Runs the explorer's edits in a worker and publishes snapshots."""

    plant_changed = Signal(object)  # Snapshot (a new plant version)
    state_changed = Signal(object)  # Snapshot (same plant; text, error, selection, undo... changed)
    selection_changed = Signal(tuple)
    job_done = Signal(object)  # Job (after the signals above)
    refused = Signal(str)  # a user error's message
    crashed = Signal(str, str)  # message, traceback
    busy_changed = Signal(bool)
    # A regrow or a prune was asked for: after it, Undo goes back to the plant shown now, so
    # whatever a view keeps of the plant before it (for an instant undo) can go at once, before
    # the edit makes its new version (the view then holds two versions during the edit, not three).
    edit_started = Signal()
    replaying = Signal(int, int)  # a session's edits replayed so far, of how many (worker thread)

    def __init__(self, explorer: Explorer, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.explorer = explorer
        self.lock = threading.RLock()
        self.jobs = JobQueue(self._execute, self)
        self.jobs.finished.connect(self._finished)
        self.jobs.busy_changed.connect(self.busy_changed)
        self.snapshot = state.take_snapshot(explorer)
        self.last_job_seconds = 0.0
        self._gesture_edits: dict[int, dict] = {}  # slider-drag gesture -> its edit (see set_constant)

    # -- running jobs ------------------------------------------------------
    @property
    def idle(self) -> bool:
        """True when no job is queued or running."""
        return self.jobs.idle

    def submit(self, name: str, fn: Callable[[Explorer], Any], key: str | None = None) -> Job:
        """Run ``fn(explorer)`` in the worker; returns the :class:`~ramure.app.desktop.workers.Job`."""
        return self.jobs.submit(name, fn, key)

    def _execute(self, job) -> None:  # worker thread
        with self.lock:
            ex = self.explorer
            try:
                job.result = job.fn(ex)
            except Exception as exc:  # noqa: BLE001 - reported to the user, never fatal
                job.error = exc
                job.details = traceback.format_exc()
            try:
                job.snapshot = state.take_snapshot(ex, self.snapshot, job.name)
            except Exception as exc:  # noqa: BLE001
                if job.error is None:
                    job.error = exc
                    job.details = traceback.format_exc()

    @property
    def timeline(self) -> Timeline:
        """The model's history of replaced sessions (:attr:`Explorer.timeline`)."""
        return self.explorer.timeline

    def _finished(self, job) -> None:  # GUI thread
        self.last_job_seconds = time.perf_counter() - job.submitted
        snap = self._fresh_light(job.snapshot)
        if snap is not None and not (job.stale and job.error is None):
            self._publish(snap)
        if job.error is not None and not job.stale:
            if isinstance(job.error, RamureError):
                self.refused.emit(str(job.error))
            else:
                self.crashed.emit(f"{type(job.error).__name__}: {job.error}", job.details)
        self.job_done.emit(job)

    def _fresh_light(self, snap):
        """``snap`` with its light parts (dirty, undo...) read again when the plant is the same: a
        save or a selection in the GUI thread may have come between the job's end and now."""
        if snap is None or snap.version != self.snapshot.version or not self.lock.acquire(blocking=False):
            return snap
        try:
            if self.explorer.version != snap.version:
                return snap
            return state.take_snapshot(self.explorer, snap, snap.job)
        finally:
            self.lock.release()

    def _publish(self, snap) -> None:
        old = self.snapshot
        self.snapshot = snap
        if snap.version != old.version:
            self.plant_changed.emit(snap)
        else:
            self.state_changed.emit(snap)

    def refresh(self) -> Snapshot:
        """Re-read the light parts of the model (selection, status...) in the GUI thread."""
        with self.lock:
            snap = state.take_snapshot(self.explorer, self.snapshot)
        self._publish(snap)
        return snap

    # -- edits (jobs) ------------------------------------------------------
    def set_text(self, text: str) -> Job:
        """Parse and derive new grammar text; the job's result is the GrammarError or None.

        Text that differs from the plant's only in ``#define`` values is a constants edit
        on the same plant (its regrown parts stay, one undo step); other text is a new
        grammar: a fresh plant, the old one one Undo away.
        """

        def run(ex):
            shown = state.shown_text(ex)
            if text == shown and ex.error is None:
                return None
            if state.constants_only_change(shown, text):
                return state.set_constants_from_text(ex, text)
            return ex.set_text(text)

        return self.submit("grammar", run, key="text")

    def set_constant(self, name: str, value: float, gesture: int = 0) -> Job:
        """Change a constant.  Changes sharing a non-zero ``gesture`` (one slider drag) make one
        undo step: each replaces the previous one's edit while that is still the last edit."""

        def run(ex) -> None:
            edit = state.set_constant_merging(ex, name, value, self._gesture_edits.get(gesture) if gesture else None)
            if gesture:
                self._gesture_edits = {gesture: edit}  # worker thread only

        return self.submit(f"constant {name}", run, key=f"const:{name}")

    def set_derivation(self, n: int | None = None, seed: int | None = None) -> Job:
        """Derive again with ``n`` steps and ``seed`` (None keeps the current one), as a job."""
        return self.submit("derivation", lambda ex: ex.set_derivation(n, seed), key="derivation")

    def regrow(
        self, seed: int | None = None, constants: Mapping[str, float] | None = None, params: Mapping[str, float] | None = None
    ) -> Job:
        """Regrow the selection (or the whole plant); what grew back stays selected, so the
        next Regrow ("again, another seed") regrows the same part."""

        def run(ex):
            return ex.regrow(seed=seed, constants=constants, params=params)  # the model keeps the part selected

        self.edit_started.emit()
        return self.submit("regrow", run)

    def prune(self) -> Job:
        """Delete the selection's cut subtrees, as a job."""
        self.edit_started.emit()
        return self.submit("prune", lambda ex: ex.prune())

    def undo(self) -> Job:
        """Undo the last plant edit, or go back to the plant before the last text, n or seed
        change; the job's result says what was undone (:attr:`Explorer.history_note`)."""
        return self.submit("undo", lambda ex: _noted(ex.undo, ex))

    def redo(self) -> Job:
        """Redo what Undo took back, in the order it was done; the job's result says what."""
        return self.submit("redo", lambda ex: _noted(ex.redo, ex))

    def load_session(self, path: str | os.PathLike, run_code: bool = False) -> Job:
        """Load a session file in the worker; :attr:`replaying` follows the replay of its edits.
        ``run_code``: the session's L-Py model may run (the caller asked the user)."""
        return self.submit("load session", lambda ex: ex.load_session(path, progress=self.replaying.emit, run_code=run_code))

    def load_grammar(self, path: str | os.PathLike, run_code: bool = False) -> Job:
        """Replace the plant by a grammar file: a fresh session and a fresh history (see
        :meth:`Explorer.open_grammar`); the job's result is the text.  ``run_code``: an L-Py
        model may run (the caller asked the user)."""
        path = pathlib.Path(path)

        def run(ex):
            ex.open_grammar(path, run_code=run_code)
            return ex.text

        return self.submit("open grammar", run, key="text")

    # -- quick reads and selection (GUI thread) -------------------------------
    def _acquire(self, wait):
        if wait is None:
            ok = self.lock.acquire()
        elif wait <= 0:
            ok = self.lock.acquire(blocking=False)
        else:
            ok = self.lock.acquire(timeout=wait)
        if not ok:
            raise Busy("the plant is being recomputed; try again in a moment")

    def read(self, fn: Callable[[Explorer], T], wait: float | None = 0.0) -> T:
        """``fn(explorer)`` under the lock in the GUI thread (``wait`` seconds at most; None = forever)."""
        self._acquire(wait)
        try:
            return fn(self.explorer)
        finally:
            self.lock.release()

    def _current(self, ex):
        if ex.version != self.snapshot.version:
            raise Busy("the plant on screen is being replaced; try again in a moment")

    def _select(self, fn):
        grammar = []

        def run(ex):
            self._current(ex)
            fn(ex)
            grammar.append((ex.text, ex.session.n))
            return state.take_snapshot(ex, self.snapshot)

        self.snapshot = self.read(run)
        self.selection_changed.emit(self.snapshot.selection)
        if self.snapshot.selection:  # a regrow usually follows: make it as fast as the later ones
            warm_up_in_background(*grammar[0])
        return self.snapshot.selection

    def select(self, leaf_ids: int | Iterable[int], mode: str = "replace") -> tuple[int, ...]:
        """Select ``leaf_ids`` (``mode``: replace, add or toggle); returns the new selection."""
        return self._select(lambda ex: ex.select(leaf_ids, mode))

    def clear_selection(self) -> tuple[int, ...]:
        """Select nothing; returns the (empty) selection."""
        return self._select(lambda ex: ex.clear_selection())

    def pick_cell(self, cell_id: int, mode: str = "replace") -> int:
        """Select the history leaf that drew mesh cell ``cell_id``; returns that leaf."""
        picked = []

        def run(ex) -> None:
            picked.append(ex.leaf_of_cell(cell_id))
            ex.select([picked[0]], mode)

        self._select(run)
        return picked[0]

    def select_rectangle(
        self, screen_xy: np.ndarray, rect: Sequence[float], mode: str = "replace", leaf_ids: np.ndarray | None = None
    ) -> list[int]:
        """Select the leaves whose projected points fall in ``rect`` (x0, y0, x1, y1): the segment
        midpoints, or the points of ``leaf_ids`` (midpoints then organ centres, as the window gives)."""
        found = []

        def run(ex) -> None:
            if leaf_ids is None:
                found.extend(ex.leaves_in_rectangle(screen_xy, rect))
            else:
                found.extend(leaves_in_rectangle(leaf_ids, screen_xy, rect))
            ex.select(found, mode)

        self._select(run)
        return found

    def set_rho(self, fraction: float) -> Job:
        """ρ, a fraction in (0, 1]; a job, so a regrow asked for after it uses it."""
        return self.submit("rho", lambda ex: ex.set_rho(fraction), key="rho")

    def kinship_colors(self) -> np.ndarray | None:
        """Per-cell kinship RGB of the plant on screen (None unless exactly one leaf is selected)."""

        def run(ex):
            self._current(ex)
            return state.kinship_cell_colors(ex, self.snapshot.mesh)

        return self.read(run, wait=0.05)

    def selection_box(self) -> np.ndarray | None:
        """The selection's OBB as (12, 2, 3) line segments, or None."""
        snap = self.snapshot
        return state.selection_box_lines(snap.skeleton, snap.selection)

    def selected_modules(self) -> list[str]:
        """The selection's modules as text, one per line (the String dock)."""
        return self.read(state.selected_modules, wait=0.05)

    def plan(self) -> CutResult | None:
        """The minimum cut a regrow of the selection would make (None without a selection)."""
        return self.read(lambda ex: ex.plan(), wait=2.0)

    def preview(self, inline: bool = True) -> Job | tuple:
        """The cut preview of the selection: ``(version, selection, rho, CutPreview or None)``.

        On a plant of at most :data:`INLINE_PREVIEW_NODES` nodes it is computed here at once
        (``inline``, a few ms: a job would hold the plant while the user clicks on); else, or
        when the plant is busy, in the worker: the job's result is that tuple."""

        def run(ex):
            return ex.version, tuple(ex.selection), ex.rho, ex.preview()

        if inline:
            try:
                return self.read(lambda ex: run(ex) if len(ex.derivation.tree) <= INLINE_PREVIEW_NODES else None, wait=0.05) or (
                    self.submit("preview", run, key="preview")
                )
            except Busy:
                pass
        return self.submit("preview", run, key="preview")

    def wait_idle(self, timeout: float = 30.0) -> bool:
        """Process events until every job is delivered (tests, shutdown, file saves)."""
        from PySide6.QtCore import QCoreApplication

        end = time.perf_counter() + timeout
        while not self.idle:
            if time.perf_counter() > end:
                return False
            QCoreApplication.processEvents()
            time.sleep(0.002)
        # the queue counts a job delivered in its own slot; the window's slots for the same
        # job are separate queued calls: run them too before saying "idle"
        QCoreApplication.processEvents()
        return True


def _noted(step: Callable[[], object], explorer: Explorer) -> str:
    """Run an undo or redo ``step``; what it did, in the user's words."""
    step()
    return explorer.history_note
