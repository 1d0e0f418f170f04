"""Study ▸ New study from this exploration…: the study made from the window's variants, then served.

:class:`NewStudyDialog` asks for a folder, a title and a time budget, calls
:func:`ramure.app.new_study.new_study` (the function the notebook calls too) and then shows the
``ramure study serve`` command, with a button that copies it, and one that starts the server
here (127.0.0.1 only, a child process stopped with the dialog).  Without an exploration made in
this window, the action explores first.  Variants ▸ Save exploration folder… writes the same
files (``picks.json`` and the pictures) without a study.
"""

from __future__ import annotations

import json
import os
from typing import TYPE_CHECKING

from PySide6.QtCore import QObject, QProcess, Qt, Signal
from PySide6.QtWidgets import (
    QApplication,
    QCheckBox,
    QDialog,
    QDoubleSpinBox,
    QFileDialog,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

from ramure.errors import RamureError

if TYPE_CHECKING:
    from PySide6.QtGui import QCloseEvent
    from PySide6.QtWidgets import QMenu

    from ramure.app.desktop.panels.variants import VariantsController
    from ramure.app.new_study import NewStudy
    from ramure.metrics.exploration import Exploration


class NewStudyDialog(QDialog):
    """Folder, title and budget of a new study; after *Create*, the command that serves it.

    What it did and what it refused leave as :attr:`status` and :attr:`refused`."""

    #: A message for the status bar and how long it stays (ms).
    status = Signal(str, int)
    #: A user error (a folder that cannot hold a study...): the window reports it.
    refused = Signal(str)

    def __init__(self, parent: QWidget | None, exploration: Exploration, grammar: str) -> None:
        super().__init__(parent)
        self.exploration = exploration
        self.grammar = grammar
        self.made: NewStudy | None = None
        self.setWindowTitle("New study")
        self.folder = QLineEdit()
        self.folder.setPlaceholderText("a new folder for the study")
        browse = QPushButton("Choose…")
        browse.clicked.connect(self.choose_folder)
        row = QHBoxLayout()
        row.addWidget(self.folder)
        row.addWidget(browse)
        self.title = QLineEdit(f"{grammar} study")
        self.minutes = QDoubleSpinBox()
        self.minutes.setRange(1.0, 1440.0)
        self.minutes.setValue(30.0)
        self.minutes.setSuffix(" min")
        form = QFormLayout()
        form.addRow("Folder", _wrap(row))
        form.addRow("Title", self.title)
        self.set_name = QLineEdit(grammar)
        self.set_name.setToolTip("Names these 27 pictures in the study (a folder of it; participants never see it)")
        form.addRow("Name of these pictures", self.set_name)
        form.addRow("Time per participant", self.minutes)
        self.add_to = QCheckBox("Add these pictures to the study already in this folder (one more part)")
        self.add_to.toggled.connect(self._adding)
        form.addRow("", self.add_to)
        self.create_button = QPushButton("Create study")
        self.create_button.setDefault(True)
        self.create_button.clicked.connect(self.make_study)
        self.note = QLabel(f"The 27 picks of {grammar} are drawn once into the folder: every participant sees these pictures.")
        self.note.setWordWrap(True)
        self.command = QLineEdit()
        self.command.setReadOnly(True)
        self.copy_button = QPushButton("Copy serve command")
        self.copy_button.clicked.connect(self.copy_command)
        self.served = QWidget()
        served = QVBoxLayout(self.served)
        served.setContentsMargins(0, 0, 0, 0)
        served.addWidget(QLabel("Serve it to participants (in a terminal; Ctrl+C stops it):"))
        served.addWidget(self.command)
        served.addWidget(self.copy_button)
        self.serve_button = QPushButton("Serve now on this computer")
        self.serve_button.setToolTip("Start the server here (127.0.0.1 only) until this dialog closes")
        self.serve_button.clicked.connect(self.serve_here)
        self.stop_button = QPushButton("Stop serving")
        self.stop_button.clicked.connect(self.stop_serving)
        self.stop_button.hide()
        self.addresses = QLabel()
        self.addresses.setWordWrap(True)
        self.addresses.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        buttons = QHBoxLayout()
        buttons.addWidget(self.serve_button)
        buttons.addWidget(self.stop_button)
        served.addLayout(buttons)
        served.addWidget(self.addresses)
        self.server: QProcess | None = None
        self.server_addresses: dict | None = None
        self._server_output = b""
        self.served.hide()
        layout = QVBoxLayout(self)
        layout.addLayout(form)
        layout.addWidget(self.note)
        layout.addWidget(self.create_button)
        layout.addWidget(self.served)

    def _adding(self, on: bool) -> None:
        """The title and budget belong to the study already there when adding to it."""
        self.title.setEnabled(not on)
        self.minutes.setEnabled(not on)

    def choose_folder(self) -> None:
        """Ask for the study's folder."""
        folder = QFileDialog.getExistingDirectory(self, "Folder of the new study")
        if folder:
            self.folder.setText(folder)

    def make_study(self) -> NewStudy | None:
        """Make the study (the pictures are drawn here, in the GUI thread: VTK draws there)."""
        from ramure.app.new_study import add_to_study, new_study

        folder = self.folder.text().strip()
        if not folder:
            self._refuse("choose a folder for the study first")
            return None
        self.note.setStyleSheet("")
        self.note.setText("Drawing the 27 pictures and writing the study…")
        self.create_button.setEnabled(False)  # a second click while drawing makes nothing twice
        QApplication.setOverrideCursor(Qt.CursorShape.WaitCursor)
        QApplication.processEvents()  # show the note before the drawing holds this thread
        try:
            if self.add_to.isChecked():
                made = add_to_study(self.exploration, folder, grammar=self.set_name.text().strip())
            else:
                made = new_study(
                    self.exploration,
                    folder,
                    name=self.title.text().strip() or None,
                    grammar=self.set_name.text().strip(),
                    budget_minutes=self.minutes.value(),
                )
        except (RamureError, OSError) as exc:
            self._refuse(str(exc))
            self.create_button.setEnabled(True)
            return None
        finally:
            QApplication.restoreOverrideCursor()
        self.made = made
        self.note.setStyleSheet("")
        done = "Added to the study" if self.add_to.isChecked() else "Study created"
        self.note.setText(f"{done}: {made.db} ({made.grammar}, 27 pictures in {made.exploration.name}/).")
        self.command.setText(made.command)
        self.served.show()
        self.create_button.setEnabled(False)
        self.status.emit(f"New study {made.db}", 10000)
        return made

    def _refuse(self, message: str) -> None:
        self.note.setStyleSheet("color: #b00020;")
        self.note.setText(message)
        self.refused.emit(message)

    def copy_command(self) -> None:
        """Copy the serve command to the clipboard."""
        QApplication.clipboard().setText(self.command.text())
        self.status.emit("Serve command copied", 5000)

    # -- serving here ------------------------------------------------------------------------------
    def serve_here(self) -> QProcess | None:
        """Start ``ramure study serve`` on 127.0.0.1 as a child process; its addresses show when it listens."""
        from ramure.app.new_study import free_port, serve_argv

        if self.made is None or (self.server is not None and self.server.state() != QProcess.ProcessState.NotRunning):
            return self.server
        argv = serve_argv(self.made.db, free_port())
        process = QProcess(self)
        process.setProgram(argv[0])
        process.setArguments(argv[1:])
        process.readyReadStandardOutput.connect(self._server_said)
        process.finished.connect(self._server_ended)
        self._server_output = b""
        self.server, self.server_addresses = process, None
        self.addresses.setText("Starting the server…")
        self.serve_button.setEnabled(False)
        self.stop_button.show()
        process.start()
        return process

    def _server_said(self) -> None:
        if self.server is None:
            return
        self._server_output += bytes(self.server.readAllStandardOutput().data())
        try:
            said = json.loads(self._server_output)
        except ValueError:
            return  # not the whole announcement yet
        self.server_addresses = said
        self.addresses.setText(
            f"Participants: {said['participants']}\nResearcher's page: {said['researcher']}\n"
            "This computer only; the server stops with this dialog."
        )

    def _server_ended(self, code: int, status: QProcess.ExitStatus) -> None:
        process = self.server
        if process is None:
            return
        error = bytes(process.readAllStandardError().data()).decode("utf-8", "replace").strip()
        self.addresses.setText(error.splitlines()[-1] if code and error else "The server has stopped.")
        self.serve_button.setEnabled(True)
        self.stop_button.hide()

    def stop_serving(self) -> None:
        """Stop the server this dialog started (its answers are on disk once acknowledged)."""
        process = self.server
        if process is None or process.state() == QProcess.ProcessState.NotRunning:
            return
        process.terminate()
        if not process.waitForFinished(5000):
            process.kill()
            process.waitForFinished(2000)

    def closeEvent(self, event: QCloseEvent) -> None:  # noqa: N802 (Qt API)
        """Stop a server started here before the dialog closes."""
        self.stop_serving()
        super().closeEvent(event)


def _wrap(layout: QHBoxLayout) -> QWidget:
    widget = QWidget()
    layout.setContentsMargins(0, 0, 0, 0)
    widget.setLayout(layout)
    return widget


class NewStudyActions(QObject):
    """Study ▸ New study from this exploration… and Variants ▸ Save exploration folder…

    It works on the window's ``variants`` (the exploration, or one made first) and says what it
    did with :attr:`status` and :attr:`refused`; ``parent`` is the widget dialogs open over."""

    #: A message for the status bar and how long it stays (ms; 0: until replaced).
    status = Signal(str, int)
    #: A user error (no exploration yet, a folder that cannot be written): the window reports it.
    refused = Signal(str)

    def __init__(self, variants: VariantsController, study_menu: QMenu, variants_menu: QMenu, parent: QWidget) -> None:
        super().__init__(parent)
        self.variants = variants
        self.parent_widget = parent
        self.dialog: NewStudyDialog | None = None
        study_menu.addSeparator()
        study_menu.addAction("New study from this exploration…").triggered.connect(lambda: self.new_study())
        variants_menu.addAction("Save exploration folder…").triggered.connect(lambda: self.save_exploration())

    def _explored(self) -> tuple[Exploration, str] | None:
        variants = self.variants
        if not variants.explored():
            return None
        vs = variants.variant_set
        assert vs is not None and vs.exploration is not None  # explored()
        return vs.exploration, vs.name

    def new_study(self) -> NewStudyDialog | None:
        """Open the dialog on the window's exploration; explore first when there is none."""
        explored = self._explored()
        if explored is None:
            self.status.emit("Exploring the variants first: the study is made of the 27 picks…", 0)
            self.variants.explore(then=lambda: self.new_study())
            return None
        if self.dialog is not None:
            self.dialog.close()
        self.dialog = NewStudyDialog(self.parent_widget, *explored)
        self.dialog.status.connect(self.status)
        self.dialog.refused.connect(self.refused)
        self.dialog.show()
        return self.dialog

    def save_exploration(self, directory: str | os.PathLike | None = None) -> bool:
        """Write the exploration (``picks.json``, pictures, ``pca.json``, ``variants.csv``) to a folder."""
        from ramure.app.new_study import save_exploration

        explored = self._explored()
        if explored is None:
            self.refused.emit("Explore the variants first (Variants ▸ Explore variants of this grammar)")
            return False
        if directory is None:
            directory = QFileDialog.getExistingDirectory(self.parent_widget, "Save the exploration into")
            if not directory:
                return False
        QApplication.setOverrideCursor(Qt.CursorShape.WaitCursor)
        try:
            save_exploration(explored[0], directory)
        except (RamureError, OSError) as exc:
            self.refused.emit(str(exc))
            return False
        finally:
            QApplication.restoreOverrideCursor()
        self.status.emit(f"Exploration saved to {directory}", 10000)
        return True
