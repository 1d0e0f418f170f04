"""The analyst view: open a study database, see who took part and read its report.

The report (:func:`ramure.studies.write_report`: heat maps, box plots, ANOVA and
qualifier tables) is written to a temporary folder in a worker and shown in
a text browser; "Save report to…" copies it elsewhere.
"""

from __future__ import annotations

import os
import pathlib
import shutil
import tempfile
from typing import TYPE_CHECKING

from PySide6.QtCore import QUrl
from PySide6.QtWidgets import (
    QFileDialog,
    QHBoxLayout,
    QLabel,
    QMessageBox,
    QPushButton,
    QSplitter,
    QTableWidget,
    QTableWidgetItem,
    QTextBrowser,
    QVBoxLayout,
    QWidget,
)
from PySide6.QtCore import Qt

from ramure.app.desktop.workers import Task
from ramure.errors import RamureError

if TYPE_CHECKING:
    from PySide6.QtWidgets import QWidget


STUDY_FILTER = "Study databases (*.db *.sqlite);;All files (*)"


def ask_study_path(parent: QWidget | None) -> str | None:
    """A study database chosen in a file dialog, or None."""
    path, _ = QFileDialog.getOpenFileName(parent, "Open study", "", STUDY_FILTER)
    return path or None


class AnalystWindow(QWidget):
    """Participants, tests and the HTML report of one study."""

    def __init__(self, ask: bool = True) -> None:
        super().__init__()
        self.setWindowTitle("Ramure study — analyst")
        self.ask = ask
        self.last_message: str | None = None
        self.path: pathlib.Path | None = None
        self.report_dir: pathlib.Path | None = None
        self.summary: dict | None = None
        self.task: Task | None = None
        self.people = 0
        self.title = QLabel("Open a study database.")
        open_button = QPushButton("Open study…")
        open_button.clicked.connect(lambda: self.open_study())
        self.save_button = QPushButton("Save report to…")
        self.save_button.setEnabled(False)
        self.save_button.clicked.connect(lambda: self.save_report())
        self.participants = QTableWidget(0, 5)
        self.participants.setHorizontalHeaderLabels(["code", "consent", "tests", "finished", "minutes"])
        self.participants.verticalHeader().hide()
        self.participants.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.report = QTextBrowser()
        self.report.setObjectName("studyReport")
        self.report.setOpenExternalLinks(False)
        top = QHBoxLayout()
        top.addWidget(self.title, 1)
        top.addWidget(open_button)
        top.addWidget(self.save_button)
        split = QSplitter(Qt.Orientation.Horizontal)
        split.addWidget(self.participants)
        split.addWidget(self.report)
        split.setSizes([360, 890])
        layout = QVBoxLayout(self)
        layout.addLayout(top)
        layout.addWidget(split, 1)
        self.resize(1250, 820)

    def open_study(self, path: str | os.PathLike | None = None) -> Task | None:
        """Open a study database (asked for when ``path`` is None) and write its report in a worker."""
        from ramure.studies import Study

        path = path or ask_study_path(self)
        if path is None:
            return None
        try:
            with Study.open(path, readonly=True) as study:
                people = study.participants()
                name, grammars = study.name, study.grammars
        except RamureError as exc:
            self.refuse(str(exc))
            return None
        self.path = pathlib.Path(path)
        self.title.setText(f"<b>{name}</b> — {len(people)} participants, grammars: {', '.join(grammars)} (writing the report…)")
        self.participants.setRowCount(len(people))
        for r, p in enumerate(people):
            for c, value in enumerate(
                (p["code"], "yes" if p["consent"] else "no", p["tests"], p["finished"], f"{p['elapsed_seconds'] / 60:.1f}")
            ):
                self.participants.setItem(r, c, QTableWidgetItem(str(value)))
        self.participants.resizeColumnsToContents()
        self.people = len(people)
        out = pathlib.Path(tempfile.mkdtemp(prefix="ramure-report-"))

        study_path = self.path

        def work(progress, cancelled):
            from ramure.studies import write_report

            return write_report(study_path, out)

        task = self.task = Task("report", work, self)
        task.done.connect(lambda summary: self._shown(out, summary, name))
        task.failed.connect(lambda exc, details: self.refuse(f"cannot write the report: {exc}"))
        task.start()
        return task

    def _shown(self, out, summary, name) -> None:
        self.report_dir, self.summary = out, summary
        self.report.setSearchPaths([str(out)])
        if not summary.get("tests"):  # empty heat maps and plots would only puzzle
            self.report.setHtml(
                "<h2>No finished tests yet</h2><p>The report (co-occurrence, grouping, "
                "Likert answers, qualifier regions) fills in once participants finish "
                "a grammar. The table on the left shows who has started.</p>"
            )
        else:
            self.report.setSource(QUrl.fromLocalFile(str(out / "index.html")))
        self.title.setText(
            f"<b>{name}</b> — {self.people} participants ({summary.get('participants')} "
            f"with a finished test), {summary.get('tests')} finished tests, "
            f"{summary.get('groups')} groups"
        )
        self.save_button.setEnabled(True)

    def save_report(self, folder: str | os.PathLike | None = None) -> pathlib.Path | None:
        """Copy the report's folder into ``folder`` (asked for when None); returns where it went."""
        if self.report_dir is None:
            return None
        folder = folder or QFileDialog.getExistingDirectory(self, "Save the report in")
        if not folder:
            return None
        target = pathlib.Path(folder)
        shutil.copytree(self.report_dir, target, dirs_exist_ok=True)
        return target

    def refuse(self, message: str) -> None:
        """Say why something cannot be done: a warning box when the window may ask, and ``last_message``."""
        self.last_message = message
        if self.ask:
            QMessageBox.warning(self, "Study", message)
        return None
