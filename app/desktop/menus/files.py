"""The File menu's work: open/save grammar and session, export, screenshots, recent files.

:class:`FileActions` asks for paths with file dialogs (or takes them as
arguments, for scripts and tests) and calls the model through the
controller.  Recent files are kept in the window's ``QSettings``.  It never calls the
window: messages leave as the :attr:`~FileActions.status` and :attr:`~FileActions.refused`
signals, edits still in their pause are asked for with :attr:`~FileActions.flush_requested`
(connected directly, so they are sent before the save goes on) and a changed recent-files list
is said with :attr:`~FileActions.recent_changed`.
"""

from __future__ import annotations

import errno
import os
import pathlib
from typing import TYPE_CHECKING

from PySide6.QtCore import QObject, Signal
from PySide6.QtWidgets import QFileDialog, QMessageBox

from ramure.errors import RamureError, ValueRefused
from ramure.io import write_with
from ramure.app.document import CodeNotAllowed, CodeTrust, runs_code, session_runs_code
from ramure.app.model import local_edits_message

if TYPE_CHECKING:
    from PySide6.QtCore import QSettings
    from PySide6.QtWidgets import QWidget
    from ramure.app.desktop.controller import Controller
    from ramure.app.desktop.panels.editor import GrammarEditor
    from ramure.app.desktop.view.plant_view import PlantView
    from ramure.app.desktop.workers import Job

#: File ▸ Open's title: it opens a plant from a grammar, an L-Py model or an MTG, not only a grammar.
OPEN_TITLE = "Open plant"
GRAMMAR_FILTER = (  # .l: L-studio/cpfg (ramure.lsys.language.cpfg); .lpy: L-Py models; .mtg: OpenAlea MTGs
    "Plants (*.lsys *.l *.lpy *.mtg);;L-system grammars (*.lsys *.l);;L-Py models (*.lpy);;OpenAlea MTG (*.mtg);;All files (*)"
)
#: The settings key of the folders whose L-Py models the user allowed to run (asked once per folder).
TRUSTED_KEY = "trusted_code_folders"
SESSION_FILTER = "Ramure sessions (*.json);;All files (*)"
EXPORT_FILTER = "glTF binary (*.glb);;glTF (*.gltf);;Wavefront OBJ (*.obj);;VTK PolyData (*.vtp *.vtk);;PLY (*.ply);;STL (*.stl)"
PNG_FILTER = "PNG images (*.png)"
MAX_RECENT = 8
TITLE = "Ramure"


class FileActions(QObject):
    """Open, save, export and the recent-files list of one window.

    ``editor`` is the grammar editor (its own text is saved while it holds an error), ``view``
    the 3D view (screenshots, the fruit volumes on export) and ``parent`` the widget dialogs
    open over.  ``ask=False`` never shows a modal question (tests, scripts).
    """

    #: A message for the status bar and how long it stays (ms; 0: until replaced).
    status = Signal(str, int)
    #: A user error (a path that cannot be read or written): the window reports it.
    refused = Signal(str)
    #: Send the typing or sliding still in its pause now (connect it directly: it runs first).
    flush_requested = Signal()
    #: The recent-files list changed.
    recent_changed = Signal()

    def __init__(
        self,
        controller: Controller,
        settings: QSettings,
        editor: GrammarEditor,
        view: PlantView,
        parent: QWidget,
        ask: bool = True,
    ) -> None:
        super().__init__(parent)
        self.controller = controller
        self.settings = settings
        self.editor = editor
        self.view = view
        self.parent_widget = parent
        self.ask = ask
        self.yup = False  #: export with Y up (File > Export with Y up)

    def set_yup(self, on: bool) -> None:
        """Export with Y up (for tools that take Y as up: Blender, glTF) or Z up."""
        self.yup = bool(on)

    # -- recent files -----------------------------------------------------------
    def recent(self) -> list[str]:
        """The recent files the settings file names that still exist.  The file is read from
        disk: an entry that is not a path (another type Qt decodes, a NUL byte, a name too
        long for the system) is skipped, and only the first entries are looked at."""
        try:
            value = self.settings.value("recent", [])
        except RuntimeError:  # a @Variant Qt cannot convert ("Can't find converter for 'qfloat16'")
            return []
        if isinstance(value, str):  # QSettings gives one stored path back as a plain string
            value = [value]
        paths = value[: 4 * MAX_RECENT] if isinstance(value, list) else []
        return [v for v in paths if isinstance(v, str) and _exists(v)]

    def remember(self, path: str | os.PathLike) -> None:
        """Put ``path`` first in the recent files (at most ``MAX_RECENT``)."""
        path = str(pathlib.Path(path).resolve())
        items = [path] + [p for p in self.recent() if p != path]
        self.settings.setValue("recent", items[:MAX_RECENT])
        self.settings.sync()
        self.recent_changed.emit()

    # -- unsaved changes --------------------------------------------------------
    def unsaved(self) -> bool:
        """Unsaved changes: the model's plant differs from the file (see
        :attr:`Explorer.dirty <ramure.app.model.Explorer.dirty>`), or typing not yet sent or
        not parsed."""
        snap = self.controller.snapshot
        return snap.dirty or self.editor.pending() or snap.error is not None

    def confirm_discard(self) -> bool:
        """True if there are no unsaved changes or the user agrees to lose them."""
        self.flush_requested.emit()  # a change still in its pause or its job counts
        self.controller.wait_idle()
        if not self.unsaved() or not self.ask:
            return True
        answer = QMessageBox.question(
            self.parent_widget,
            TITLE,
            "The plant has unsaved changes. Save the grammar first?",
            QMessageBox.StandardButton.Save | QMessageBox.StandardButton.Discard | QMessageBox.StandardButton.Cancel,
            QMessageBox.StandardButton.Save,
        )
        if answer == QMessageBox.StandardButton.Save:
            return self.save_grammar() is not None
        return answer == QMessageBox.StandardButton.Discard

    # -- dialogs ----------------------------------------------------------------
    def _ask_open(self, title, filters):
        path, _ = QFileDialog.getOpenFileName(self.parent_widget, title, self._folder(), filters)
        return path or None

    def _path_to_open(self, path, title, filters):
        """``path``, or one asked for, once unsaved changes may be dropped (None: cancelled)."""
        if not self.confirm_discard():
            return None
        return path or self._ask_open(title, filters) or None

    def _ask_save(self, title, filters, suffix):
        path, _ = QFileDialog.getSaveFileName(self.parent_widget, title, self._folder(), filters)
        if not path:
            return None
        chosen = pathlib.Path(path)
        return chosen if chosen.suffix else chosen.with_suffix(suffix)

    def _folder(self):
        snap = self.controller.snapshot
        return str(pathlib.Path(snap.path).parent) if snap.path else str(pathlib.Path.cwd())

    # -- code in files (L-Py models) ---------------------------------------------
    def code_trust(self) -> CodeTrust:
        """The folders whose L-Py models may run, as the settings remember them."""
        try:
            value = self.settings.value(TRUSTED_KEY, [])
        except RuntimeError:  # a value Qt cannot convert: nothing is trusted
            value = []
        return CodeTrust([value] if isinstance(value, str) else value if isinstance(value, list) else [])

    def may_run_code(self, path: str | os.PathLike) -> bool:
        """Whether ``path`` (an L-Py model, or a session of one) may run its code: its folder was
        allowed before, or the user allows it now (remembered for the folder).  A window that may
        not ask refuses, on the status line."""
        trust = self.code_trust()
        folder_file = pathlib.Path(path).with_suffix(".lpy")  # a session: its own folder is asked about
        if trust.allows(folder_file):
            return True
        refusal = CodeNotAllowed(path, how="open it only if you would run it as a script")
        if not self.ask:
            self.refused.emit(str(refusal))
            return False
        answer = QMessageBox.question(
            self.parent_widget,
            "Run the model's code?",
            f"{refusal}.\n\nRun L-Py models from this folder?\n{refusal.folder}\n\n"
            "Ramure remembers the answer Yes for this folder.",
            QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.No,
            QMessageBox.StandardButton.No,
        )
        if answer != QMessageBox.StandardButton.Yes:
            self.status.emit(f"Not opened: {pathlib.Path(path).name} was not allowed to run code", 0)
            return False
        trust.allow(folder_file)
        self.settings.setValue(TRUSTED_KEY, trust.folders)
        self.settings.sync()
        return True

    # -- grammar ----------------------------------------------------------------
    def open_grammar(self, path: str | os.PathLike | None = None) -> Job | None:
        """Load a plant file (a grammar, an L-Py model or an MTG: :data:`GRAMMAR_FILTER`) as a
        fresh plant, after the unsaved-changes prompt (File ▸ Open plant…)."""
        path = self._path_to_open(path, OPEN_TITLE, GRAMMAR_FILTER)
        if path is None:
            return None
        path = pathlib.Path(path)
        if not path.is_file():
            self.refused.emit(f"{path}: no such grammar file")
            return None
        if runs_code(path) and not self.may_run_code(path):
            return None
        job = self.controller.load_grammar(path, run_code=True)  # allowed just above, or not code at all
        self.remember(path)
        return job

    def save_grammar(self, path: str | os.PathLike | None = None, ask: bool = False) -> pathlib.Path | None:
        """Write the grammar with the plant's ``n``, seed and constants in it (what the editor
        shows).  A plant with regrown or pruned parts cannot be a grammar: say so and offer
        Save session instead (the window stays unsaved)."""
        self.flush_requested.emit()  # a slider or typing still in its pause is part of what is saved
        self.controller.wait_idle()
        snap = self.controller.snapshot
        if snap.local_edits:
            return self._offer_session(local_edits_message(snap.local_edits))
        if path is None and (ask or snap.path is None):
            path = self._ask_save("Save grammar", GRAMMAR_FILTER, ".lsys")
            if path is None:
                return None
        target = path or snap.path
        assert target is not None  # asked above when the grammar has no file yet
        path = pathlib.Path(target)
        text = self.editor.text()  # the editor's own text only when it holds an error
        own = text if snap.error is not None and text != snap.text else None
        try:
            self.controller.read(lambda ex: ex.save_grammar(path, text=own), wait=None)
        except (OSError, RamureError) as exc:
            self.refused.emit(f"cannot save {path}: {getattr(exc, 'strerror', None) or exc}")
            return None
        self.controller.refresh()  # the title loses its "*"
        self.remember(path)
        self.status.emit(f"Saved {path}", 4000)
        return path

    def _offer_session(self, message: str) -> pathlib.Path | None:
        """Say why the grammar cannot be saved; when the window may ask, offer Save session."""
        if not self.ask:
            self.refused.emit(message)
            return None
        self.status.emit(message, 8000)
        answer = QMessageBox.question(
            self.parent_widget,
            "Save grammar",
            message + "\n\nSave a session instead?",
            QMessageBox.StandardButton.Save | QMessageBox.StandardButton.Cancel,
            QMessageBox.StandardButton.Save,
        )
        if answer == QMessageBox.StandardButton.Save:
            return self.save_session()
        return None

    # -- session ----------------------------------------------------------------
    def save_session(self, path: str | os.PathLike | None = None) -> pathlib.Path | None:
        """Save the whole exploration (history, regrown parts, settings) as a session file."""
        path = path or self._ask_save("Save session", SESSION_FILTER, ".json")
        if path is None:
            return None
        self.controller.wait_idle()
        try:
            self.controller.read(lambda ex: ex.save_session(path), wait=None)
        except (OSError, RamureError) as exc:
            self.refused.emit(f"cannot save the session to {path}: {exc}")
            return None
        self.controller.refresh()  # the title loses its "*"
        self.remember(path)
        self.status.emit(f"Saved session {path}", 4000)
        return pathlib.Path(path)

    def load_session(self, path: str | os.PathLike | None = None) -> Job | None:
        """Load a session file (after the unsaved-changes prompt)."""
        path = self._path_to_open(path, "Load session", SESSION_FILTER)
        if path is None:
            return None
        if session_runs_code(path) and not self.may_run_code(path):
            return None
        job = self.controller.load_session(path, run_code=True)  # allowed just above, or no code in it
        self.remember(path)
        return job

    def open_recent(self, path: str | os.PathLike) -> Job | None:
        """Open a file of the recent list: a session (``.json``) or a grammar."""
        if str(path).endswith(".json"):
            return self.load_session(path)
        return self.open_grammar(path)

    # -- export -----------------------------------------------------------------
    def export_mesh(self, path: str | os.PathLike | None = None) -> pathlib.Path | None:
        """Export the plant's mesh (and the fruit volumes when shown), Y up if asked."""
        path = path or self._ask_save("Export plant", EXPORT_FILTER, ".vtp")
        if path is None:
            return None
        self.controller.wait_idle()
        from ramure.app.export import export_mesh

        fruit = self.view.fruit  # the volumes, when shown (None otherwise)
        try:
            out = export_mesh(self.controller.snapshot.mesh, path, fruit_surface=fruit, yup=self.yup)
        except (OSError, RamureError, ValueError) as exc:
            self.refused.emit(f"cannot export to {path}: {exc}")
            return None
        self.status.emit(f"Exported {out}", 4000)
        return out

    def screenshot(self, path: str | os.PathLike | None = None, whole_window: bool = False) -> pathlib.Path | None:
        """Save the 3D view (or the whole window) as PNG."""
        path = path or self._ask_save("Save screenshot", PNG_FILTER, ".png")
        if path is None:
            return None
        path = pathlib.Path(path)
        if path.suffix.lower() != ".png":
            self.refused.emit(str(ValueRefused(f"screenshots are PNG files, not '{path.suffix}'")))
            return None
        image = self.view.grab_window() if whole_window else self.view.grab_image()
        path.parent.mkdir(parents=True, exist_ok=True)

        def save(tmp: str) -> None:  # through a temporary file: a kill never leaves half a picture
            if not image.save(tmp, "PNG"):  # type: ignore[call-overload]  # PySide6's stub wants bytes; the binding refuses them, takes str
                raise OSError(errno.EIO, "Qt could not write the picture")

        try:
            write_with(path, save)
        except RamureError as exc:
            self.refused.emit(str(exc))
            return None
        self.status.emit(f"Saved screenshot {path}", 4000)
        return path


def _exists(path: str) -> bool:
    """``path`` exists; False for what cannot be a path here (a NUL byte, a name too long)."""
    try:
        return pathlib.Path(path).exists()
    except (OSError, ValueError):
        return False
