"""The File menu's work: open/save grammar and session, export, screenshots, recent files.

:class:`FileActions` asks for paths with file dialogs (or takes them as
arguments, for scripts and tests) and calls the model through the
controller.  Recent files are kept in the window's ``QSettings``.
"""

from __future__ import annotations

import errno
import os
import pathlib
from typing import TYPE_CHECKING

from PySide6.QtWidgets import QFileDialog, QMessageBox

from ramure.errors import RamureError, ValueRefused
from ramure.io import write_with
from ramure.app.model import local_edits_message

if TYPE_CHECKING:
    from PySide6.QtCore import QSettings
    from ramure.app.desktop.controller import Controller
    from ramure.app.desktop.window import MainWindow
    from ramure.app.desktop.workers import Job

GRAMMAR_FILTER = "L-system grammars (*.lsys *.l);;All files (*)"  # .l: L-studio/cpfg (ramure.lsys.cpfg)
SESSION_FILTER = "Ramure sessions (*.json);;All files (*)"
EXPORT_FILTER = "glTF binary (*.glb);;glTF (*.gltf);;Wavefront OBJ (*.obj);;VTK PolyData (*.vtp *.vtk);;PLY (*.ply);;STL (*.stl)"
PNG_FILTER = "PNG images (*.png)"
MAX_RECENT = 8


class FileActions:
    """Open, save, export and the recent-files list of one window."""

    def __init__(self, window: MainWindow, settings: QSettings) -> None:
        self.window = window
        self.settings = settings

    @property
    def controller(self) -> Controller:
        return self.window.controller

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
        path = str(pathlib.Path(path).resolve())
        items = [path] + [p for p in self.recent() if p != path]
        self.settings.setValue("recent", items[:MAX_RECENT])
        self.settings.sync()
        self.window.update_recent_menu()

    # -- dialogs ----------------------------------------------------------------
    def _ask_open(self, title, filters):
        path, _ = QFileDialog.getOpenFileName(self.window, title, self._folder(), filters)
        return path or None

    def _path_to_open(self, path, title, filters):
        """``path``, or one asked for, once unsaved changes may be dropped (None: cancelled)."""
        if not self.window.confirm_discard():
            return None
        return path or self._ask_open(title, filters) or None

    def _ask_save(self, title, filters, suffix):
        path, _ = QFileDialog.getSaveFileName(self.window, title, self._folder(), filters)
        if not path:
            return None
        chosen = pathlib.Path(path)
        return chosen if chosen.suffix else chosen.with_suffix(suffix)

    def _folder(self):
        snap = self.controller.snapshot
        return str(pathlib.Path(snap.path).parent) if snap.path else str(pathlib.Path.cwd())

    # -- grammar ----------------------------------------------------------------
    def open_grammar(self, path: str | os.PathLike | None = None) -> Job | None:
        """Load a grammar file as a fresh plant (after the unsaved-changes prompt)."""
        path = self._path_to_open(path, "Open grammar", GRAMMAR_FILTER)
        if path is None:
            return None
        path = pathlib.Path(path)
        if not path.is_file():
            self.window.report_refused(f"{path}: no such grammar file")
            return None
        job = self.controller.load_grammar(path)
        self.window.pending_open = (job.id, path)
        self.remember(path)
        return job

    def save_grammar(self, path: str | os.PathLike | None = None, ask: bool = False) -> pathlib.Path | None:
        """Write the grammar with the plant's ``n``, seed and constants in it (what the editor
        shows).  A plant with regrown or pruned parts cannot be a grammar: say so and offer
        Save session instead (the window stays unsaved)."""
        self.window.flush_edits()  # a slider or typing still in its pause is part of what is saved
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
        text = self.window.editor.text()  # the editor's own text only when it holds an error
        own = text if snap.error is not None and text != snap.text else None
        try:
            self.controller.read(lambda ex: ex.save_grammar(path, text=own), wait=None)
        except (OSError, RamureError) as exc:
            self.window.report_refused(f"cannot save {path}: {getattr(exc, 'strerror', None) or exc}")
            return None
        self.window.mark_saved()
        self.remember(path)
        self.window.status(f"Saved {path}")
        return path

    def _offer_session(self, message: str) -> pathlib.Path | None:
        """Say why the grammar cannot be saved; when the window may ask, offer Save session."""
        if not self.window.ask:
            self.window.report_refused(message)
            return None
        self.window.status(message, 8000)
        answer = QMessageBox.question(
            self.window,
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
        path = path or self._ask_save("Save session", SESSION_FILTER, ".json")
        if path is None:
            return None
        self.controller.wait_idle()
        try:
            self.controller.read(lambda ex: ex.save_session(path), wait=None)
        except (OSError, RamureError) as exc:
            self.window.report_refused(f"cannot save the session to {path}: {exc}")
            return None
        self.window.mark_saved()
        self.remember(path)
        self.window.status(f"Saved session {path}")
        return pathlib.Path(path)

    def load_session(self, path: str | os.PathLike | None = None) -> Job | None:
        path = self._path_to_open(path, "Load session", SESSION_FILTER)
        if path is None:
            return None
        job = self.controller.load_session(path)
        self.remember(path)
        self.window.after_load = job.id
        return job

    def open_recent(self, path: str | os.PathLike) -> Job | None:
        if str(path).endswith(".json"):
            return self.load_session(path)
        return self.open_grammar(path)

    # -- export -----------------------------------------------------------------
    def export_mesh(self, path: str | os.PathLike | None = None) -> pathlib.Path | None:
        path = path or self._ask_save("Export plant", EXPORT_FILTER, ".vtp")
        if path is None:
            return None
        self.controller.wait_idle()
        from ramure.app.export import export_mesh

        window = self.window
        fruit = window.view.fruit if window.variants.show_fruit else None  # the volumes, when shown
        yup = window.yup_action.isChecked()
        try:
            out = export_mesh(self.controller.snapshot.mesh, path, fruit_surface=fruit, yup=yup)
        except (OSError, RamureError, ValueError) as exc:
            self.window.report_refused(f"cannot export to {path}: {exc}")
            return None
        self.window.status(f"Exported {out}")
        return out

    def screenshot(self, path: str | os.PathLike | None = None, whole_window: bool = False) -> pathlib.Path | None:
        """Save the 3D view (or the whole window) as PNG."""
        path = path or self._ask_save("Save screenshot", PNG_FILTER, ".png")
        if path is None:
            return None
        path = pathlib.Path(path)
        if path.suffix.lower() != ".png":
            self.window.report_refused(str(ValueRefused(f"screenshots are PNG files, not '{path.suffix}'")))
            return None
        image = self.window.grab_window() if whole_window else self.window.view.grab_image()
        path.parent.mkdir(parents=True, exist_ok=True)

        def save(tmp: str) -> None:  # through a temporary file: a kill never leaves half a picture
            if not image.save(tmp, "PNG"):  # type: ignore[call-overload]  # PySide6's stub wants bytes; the binding refuses them, takes str
                raise OSError(errno.EIO, "Qt could not write the picture")

        try:
            write_with(path, save)
        except RamureError as exc:
            self.window.report_refused(str(exc))
            return None
        self.window.status(f"Saved screenshot {path}")
        return path


def _exists(path: str) -> bool:
    """``path`` exists; False for what cannot be a path here (a NUL byte, a name too long)."""
    try:
        return pathlib.Path(path).exists()
    except (OSError, ValueError):
        return False
