"""Study mode: the participant's screens and the Study menu.

A participant session (:class:`ParticipantWindow`) shows the pages of a
:class:`ramure.studies.design.ParticipantFlow`, with the study's own words
(:class:`ramure.studies.design.StudyConfig`, the same as in the notebook):

1. **Consent** — the study's text, contact and data retention, and an "I agree" box;
2. the **instructions** and the **practice** page;
3. per picture set, in the participant's Latin-square order, **sorting** — the 27
   pictures in the participant's seeded order, all in view, dragged into groups
   (drop on "New group" to start one); a double click shows a picture larger;
4. per group, a **representative** (click an image, "Make representative"),
   the **three Likert questions** and the words that describe it;
5. **Finish** — refused, listing what is missing, until everything is answered; then
   a short page ("Set 1 of 3 done", Continue) before the next set, so a
   double click on Finish never reaches the next test.  "Set N of M" stays in view;
6. the attention checks (after the first set), the demographics questions, and the last
   page: the completion code, and any set the time budget skipped.

Every answer goes straight to :class:`ramure.studies.TestSession` (one SQLite
transaction each), and the screen is rebuilt from what is stored, so a crash
loses at most the qualifier being typed.  A timer shows the participant's
remaining budget.  :class:`~ramure.app.desktop.menus.analyst.AnalystWindow` shows a
study's report.
"""

from __future__ import annotations

import os
import pathlib
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING

from PySide6.QtCore import QMimeData, QObject, QSize, Qt, QTimer, Signal
from PySide6.QtGui import QIcon, QPixmap
from PySide6.QtWidgets import (
    QAbstractItemView,
    QApplication,
    QButtonGroup,
    QCheckBox,
    QComboBox,
    QDialog,
    QFormLayout,
    QGridLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QLayout,
    QLineEdit,
    QListView,
    QListWidget,
    QListWidgetItem,
    QMessageBox,
    QPushButton,
    QRadioButton,
    QScrollArea,
    QStackedWidget,
    QVBoxLayout,
    QWidget,
)

from ramure.app.desktop.view.thumbnails import placeholder_image, skeleton_image
from ramure.app.desktop.workers import Task
from ramure.errors import RamureError
from ramure.studies.design import WORDS, ParticipantFlow, Question, StudyConfig, set_title, split_words

if TYPE_CHECKING:
    from PySide6.QtGui import QCloseEvent, QDragEnterEvent, QDragMoveEvent, QDropEvent, QImage
    from PySide6.QtWidgets import QMenu
    from ramure.app.desktop.menus.analyst import AnalystWindow
    from ramure.studies import Study
    from ramure.studies.session import Group, TestSession

MIME = "application/x-ramure-images"
ICON = 96
#: Size the pictures are loaded at: what a double click shows (the pool shows them smaller).
LARGE = 480


def html_text(title: str, text: str) -> str:
    """A page's title and plain text (paragraphs at blank lines) as escaped rich text."""
    import html

    paragraphs = "".join(f"<p>{html.escape(p).replace(chr(10), '<br>')}</p>" for p in text.split("\n\n") if p.strip())
    return f"<h3>{html.escape(title)}</h3>{paragraphs}"


def fit_icon(width: int, height: int, count: int = 27, caption: int = 22, gap: int = 12, largest: int = 160) -> int:
    """The largest square icon (pixels) such that ``count`` pictures with their captions fit in
    ``width`` x ``height``, so that the participant sees every picture at once.

    >>> fit_icon(520, 700), fit_icon(1000, 700) > fit_icon(520, 700)
    (82, True)
    """
    for size in range(largest, 23, -2):
        columns = max(1, (width - 4) // (size + gap))
        rows = -(-count // columns)
        if rows * (size + caption + gap) <= height - 4:
            return size
    return 24


# -- images --------------------------------------------------------------------------
def pick_images(
    study: Study, grammar: str, size: int = LARGE, grammars_dir: str | os.PathLike | None = None
) -> dict[int, QImage]:
    """QImages of a grammar's 27 picks, by id: the pictures stored with the study (rendered once,
    the same the notebook shows), else derived, else placeholders.

    Drawing derives each variant (when a grammar file named like the grammar is found), so call
    it from a worker.
    """
    picks = study.picks(grammar)
    stored = all(p.image and pathlib.Path(p.image).is_file() for p in picks)
    lsystem, n, seed = (None, None, 0) if stored else _study_grammar(study, grammar, grammars_dir)
    images = {}
    from PySide6.QtGui import QImage

    from ramure.app.desktop.variants import variant_skeleton

    for pick in picks:
        image = QImage()
        if pick.image and pathlib.Path(pick.image).is_file():
            image = QImage(pick.image)
        if image.isNull() and lsystem is not None:  # a study made without pictures
            try:
                image = skeleton_image(variant_skeleton(lsystem, n, seed, pick.params), size)
            except (RamureError, ValueError, KeyError, ArithmeticError):
                image = QImage()
        if image.isNull():
            image = placeholder_image(size, "", "no picture")  # never the pick id: it encodes the lattice
        images[pick.id] = image.scaled(size, size, Qt.AspectRatioMode.KeepAspectRatio, Qt.TransformationMode.SmoothTransformation)
    return images


def _study_grammar(study, grammar, grammars_dir=None):
    """The LSystem, n and seed to draw a study grammar's picks with (:func:`ramure.app.stimuli.study_grammar`,
    confined to the study's folder: a participant's window does not show the experimenter's file errors)."""
    from ramure.app.stimuli import study_grammar

    return study_grammar(study, grammar, grammars_dir)


# -- drag and drop lists -----------------------------------------------------------------
class ImageList(QListWidget):
    """Thumbnails that can be dragged to another :class:`ImageList`.

    A drop does not move items itself: it emits :attr:`dropped` with the image
    ids, and the screen re-sorts the images through the study session.
    """

    dropped = Signal(list, object)  # image ids, target list
    enlarge = Signal(int)  # image id double-clicked: show it larger

    def __init__(self, target: str | int, icon: int = ICON, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.target = target  # "pool", "new" or a group label
        self.itemDoubleClicked.connect(lambda item: self.enlarge.emit(int(item.data(Qt.ItemDataRole.UserRole))))
        self.setViewMode(QListView.ViewMode.IconMode)
        self.setIconSize(QSize(icon, icon))
        self.setResizeMode(QListView.ResizeMode.Adjust)
        self.setMovement(QListView.Movement.Snap)
        self.setSpacing(3)
        self.setSelectionMode(QAbstractItemView.SelectionMode.ExtendedSelection)
        self.setDragEnabled(True)
        self.setAcceptDrops(True)
        self.setDropIndicatorShown(True)
        self.setDragDropMode(QAbstractItemView.DragDropMode.DragDrop)
        self.setDefaultDropAction(Qt.DropAction.MoveAction)

    def mimeTypes(self) -> list[str]:  # noqa: N802 (Qt API)
        """The drag format of pictures: their ids."""
        return [MIME]

    def mimeData(self, items: Sequence[QListWidgetItem]) -> QMimeData:  # noqa: N802 (Qt API)
        """The dragged pictures' ids, comma-separated."""
        data = QMimeData()
        ids = [str(item.data(Qt.ItemDataRole.UserRole)) for item in items]
        data.setData(MIME, ",".join(ids).encode())
        return data

    def dragEnterEvent(self, event: QDragEnterEvent) -> None:  # noqa: N802 (Qt API)
        """Accept a drag of pictures only."""
        if event.mimeData().hasFormat(MIME):
            event.acceptProposedAction()
        else:
            event.ignore()

    def dragMoveEvent(self, event: QDragMoveEvent) -> None:  # noqa: N802 (Qt API)
        """Accept a drag of pictures only."""
        if event.mimeData().hasFormat(MIME):
            event.acceptProposedAction()
        else:
            event.ignore()

    def dropEvent(self, event: QDropEvent) -> None:  # noqa: N802 (Qt API)
        """Pictures dropped here: hand their ids to the page, which moves them into this group."""
        if not event.mimeData().hasFormat(MIME):
            event.ignore()
            return
        text = bytes(event.mimeData().data(MIME)).decode()  # type: ignore[call-overload]  # PySide6 stubs: QByteArray is a buffer
        ids = [int(x) for x in text.split(",") if x]
        event.setDropAction(Qt.DropAction.CopyAction)  # the source keeps its items; we re-sort
        event.accept()
        self.dropped.emit(ids, self)

    def add_image(self, image_id: int, pixmap: QPixmap, label: str) -> QListWidgetItem:
        """Show pick ``image_id`` under the participant's ``label`` (never the pick id: it encodes the lattice)."""
        item = QListWidgetItem(QIcon(pixmap), label)
        item.setData(Qt.ItemDataRole.UserRole, int(image_id))
        item.setToolTip(f"{label}: double-click to see it larger")
        self.addItem(item)
        return item

    def image_ids(self) -> list[int]:
        """The ids of the pictures in the list, in order."""
        return [self.item(i).data(Qt.ItemDataRole.UserRole) for i in range(self.count())]

    def selected_ids(self) -> list[int]:
        """The ids of the selected pictures."""
        return [item.data(Qt.ItemDataRole.UserRole) for item in self.selectedItems()]


class LikertRow(QWidget):
    """One question answered on the four-level scale."""

    answered = Signal(str, int)  # question, level 1-4

    def __init__(self, key: str, question: str, levels: Sequence[str], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.key = key
        self.buttons = QButtonGroup(self)
        layout = QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        label = QLabel(question)
        label.setWordWrap(True)
        layout.addWidget(label, 1)
        for level, name in enumerate(levels, start=1):
            button = QRadioButton(name)
            self.buttons.addButton(button, level)
            layout.addWidget(button)
        self.buttons.idClicked.connect(lambda level: self.answered.emit(self.key, level))

    def set_level(self, level: int | None) -> None:
        """Check the button of ``level`` (None: none checked)."""
        self.buttons.setExclusive(False)
        for button in self.buttons.buttons():
            button.setChecked(False)
        self.buttons.setExclusive(True)
        if level:
            self.buttons.button(int(level)).setChecked(True)


class GroupPanel(QGroupBox):
    """One group: its images (a drop target), representative, ratings and qualifiers."""

    def __init__(self, page: TestPage, group: Group, pixmaps: Mapping[int, QPixmap]) -> None:
        super().__init__(f"{WORDS['group']} {group.label} — {len(group.images)} picture(s)")
        self.page, self.label = page, group.label
        config = page.config
        self.images = ImageList(group.label, icon=64)
        rows = min(3, max(1, -(-len(group.images) // 8)))
        self.images.setMinimumHeight(12 + 88 * rows)
        self.images.dropped.connect(page.images_dropped)
        self.images.enlarge.connect(page.enlarge)
        labels = page.session.labels()
        for image in page.session.in_order(group.images):  # the participant's order, not by pick id
            item = self.images.add_image(image, pixmaps[image], labels[image])
            if image == group.representative:
                item.setBackground(Qt.GlobalColor.yellow)
                item.setText(f"{labels[image]} ★")
        self.make_rep = QPushButton("Make representative")
        self.make_rep.clicked.connect(self._representative)
        self.make_rep.setEnabled(len(group.images) > 1)
        self.rep_label = QLabel(f"Representative: {labels[group.representative] if group.representative else '—'}")
        self.rep_label.setToolTip(WORDS["representative"])
        self.rows = {}
        answers = {"usefulness": group.usefulness, "difference": group.difference, "representative": group.representative_quality}
        for key, question in config.questions.items():
            if key == "representative" and len(group.images) < 2:
                continue
            row = LikertRow(key, question, config.levels)
            row.set_level(answers[key])
            row.answered.connect(lambda k, level: page.rate(self.label, k, level))
            self.rows[key] = row
        self.qualifier = QLineEdit()
        self.qualifier.setPlaceholderText(WORDS["words_hint"])
        self.qualifier.setToolTip(WORDS["words"])
        self.qualifier.returnPressed.connect(self._add_qualifier)
        add = QPushButton("Add")
        add.clicked.connect(self._add_qualifier)
        self.qualifiers = QListWidget()
        self.qualifiers.setMaximumHeight(60)
        self.qualifiers.addItems(group.qualifiers)
        remove = QPushButton("Remove selected word")
        remove.clicked.connect(self._remove_qualifier)
        grid = QGridLayout(self)
        grid.addWidget(self.images, 0, 0, 1, 3)
        grid.addWidget(self.rep_label, 1, 0)
        grid.addWidget(self.make_rep, 1, 1)
        r = 2
        for row in self.rows.values():
            grid.addWidget(row, r, 0, 1, 3)
            r += 1
        grid.addWidget(self.qualifier, r, 0, 1, 2)
        grid.addWidget(add, r, 2)
        grid.addWidget(self.qualifiers, r + 1, 0, 1, 2)
        grid.addWidget(remove, r + 1, 2)

    def _representative(self) -> None:
        chosen = self.images.selected_ids()
        if len(chosen) != 1:
            self.page.refuse("Click one image of the group first, then 'Make representative'.")
            return
        self.page.set_representative(self.label, chosen[0])

    def _add_qualifier(self) -> None:
        text = self.qualifier.text()
        if self.page.add_qualifier(self.label, text):
            self.qualifier.clear()

    def _remove_qualifier(self) -> None:
        for item in self.qualifiers.selectedItems():
            self.page.remove_qualifier(self.label, item.text())


class TestPage(QWidget):
    """Sorting, groups and answers for one grammar; everything is written as it is given."""

    finished = Signal()

    def __init__(
        self, window: ParticipantWindow, session: TestSession, pixmaps: Mapping[int, QPixmap], config: StudyConfig | None = None
    ) -> None:
        super().__init__()
        self.owner, self.session, self.pixmaps = window, session, pixmaps  # not self.window: QWidget.window()
        self.config = config or session.study.config()
        self.pool = ImageList("pool")
        self.pool.setObjectName("pool")
        self.pool.dropped.connect(self.images_dropped)
        self.pool.enlarge.connect(self.enlarge)
        self.pool.installEventFilter(self)  # resized: the pictures are resized to stay all in view
        self.new_group = ImageList("new", icon=32)
        self.new_group.setObjectName("newGroup")
        self.new_group.setMaximumHeight(70)
        self.new_group.setToolTip("Drop images here to start a new group")
        self.new_group.setStyleSheet("QListWidget { border: 2px dashed #888; background: #f4f8ff; }")
        self.new_group.dropped.connect(self.images_dropped)
        self.groups_host = QWidget()
        self.groups_layout = QVBoxLayout(self.groups_host)
        scroll = self.groups_scroll = QScrollArea()  # not self.scroll: QWidget.scroll()
        scroll.setWidgetResizable(True)
        scroll.setWidget(self.groups_host)
        self.finish_button = QPushButton(WORDS["finish"])
        self.finish_button.clicked.connect(self.finish)
        self.todo = QLabel("")
        self.todo.setWordWrap(True)
        left = QVBoxLayout()
        hint = QLabel(WORDS["sort"] + " " + "Double-click a picture to see it larger.")
        hint.setWordWrap(True)
        left.addWidget(hint)
        left.addWidget(self.pool, 1)
        left.addWidget(QLabel(f"Drop here to start a {WORDS['new_group'].lower()}:"))
        left.addWidget(self.new_group)
        right = QVBoxLayout()
        right.addWidget(scroll, 1)
        right.addWidget(self.todo)
        right.addWidget(self.finish_button)
        layout = QHBoxLayout(self)
        layout.addLayout(left, 2)
        layout.addLayout(right, 3)
        self.refresh()

    def eventFilter(self, watched: object, event: object) -> bool:  # noqa: N802 (Qt API)
        """Fit the pool's pictures when it is resized."""
        from PySide6.QtCore import QEvent

        if watched is self.pool and isinstance(event, QEvent) and event.type() == QEvent.Type.Resize:
            self.fit_pool()
        return False

    def fit_pool(self) -> None:
        """Size the pool's pictures so that all 27 are in view at once."""
        area = self.pool.viewport().size()
        size = fit_icon(area.width(), area.height(), caption=self.pool.fontMetrics().height() + 6)
        self.pool.setIconSize(QSize(size, size))
        self.pool.setGridSize(QSize(size + 10, size + self.pool.fontMetrics().height() + 10))

    def enlarge(self, image: int) -> QDialog:
        """Show picture ``image`` large, in a dialog (closed by a click or Escape)."""
        dialog = QDialog(self)
        dialog.setWindowTitle(self.session.labels()[image])
        label = QLabel()
        label.setObjectName("enlarged")
        pixmap = self.pixmaps[image]
        side = min(LARGE, max(pixmap.width(), pixmap.height(), 1))
        label.setPixmap(pixmap.scaled(side, side, Qt.AspectRatioMode.KeepAspectRatio, Qt.TransformationMode.SmoothTransformation))
        close = QPushButton("Close")
        close.clicked.connect(dialog.accept)
        layout = QVBoxLayout(dialog)
        layout.addWidget(label)
        layout.addWidget(QLabel(self.session.labels()[image]), 0, Qt.AlignmentFlag.AlignHCenter)
        layout.addWidget(close)
        self.enlarged = dialog
        dialog.show()
        return dialog

    # -- what the participant does ---------------------------------------------------
    def partition(self) -> list[list[int]]:
        """The groups as lists of picture ids."""
        return [list(g.images) for g in self.session.groups()]

    def images_dropped(self, ids: Iterable[int], target: ImageList) -> None:
        """Pictures dropped on a group's list: move them into its group."""
        self.move_images(ids, target.target)

    def move_images(self, ids: Iterable[int], target: str | int) -> None:
        """Move images to a group label, to ``"new"`` (a new group) or to ``"pool"`` (unsorted)."""
        ids = [int(i) for i in ids]
        groups = [[i for i in g if i not in ids] for g in self.partition()]
        if target == "new":
            groups.append(ids)
        elif target != "pool":
            groups[int(target) - 1].extend(ids)
        self._write(lambda: self.session.set_groups([g for g in groups if g]))

    def set_representative(self, label: int, image: int) -> None:
        """Make ``image`` the representative of group ``label`` (saved at once)."""
        self._write(lambda: self.session.set_representative(label, image))

    def rate(self, label: int, key: str, level: int) -> None:
        """Rate group ``label`` on the scale ``key`` (saved at once)."""
        self._write(lambda: self.session.rate(label, **{key: level}))

    def add_qualifier(self, label: int, text: str) -> bool:
        """Store the words typed for group ``label`` (split as in every front end: ``split_words``)."""
        words = split_words(text)
        if not words:
            return self._write(lambda: self.session.add_qualifier(label, text))  # refused, with its message

        def add() -> None:
            stored = next((g.qualifiers for g in self.session.groups() if g.label == label), [])
            for word in words:
                if word not in stored:
                    self.session.add_qualifier(label, word)

        return self._write(add)

    def remove_qualifier(self, label: int, text: str) -> None:
        """Take the qualifier ``text`` off group ``label`` (saved at once)."""
        self._write(lambda: self.session.remove_qualifier(label, text))

    def finish(self) -> None:
        """Finish this grammar's test; the window moves on when it is saved."""
        if self._write(self.session.finish, refresh=False):
            self.finished.emit()

    def _write(self, action, refresh: bool = True) -> bool:
        try:
            action()
        except RamureError as exc:
            self.refuse(str(exc))
            return False
        if refresh:
            self.refresh()
        return True

    def refuse(self, message: str) -> None:
        """Say why an answer was not saved (through the participant window)."""
        self.owner.refuse(message)

    # -- showing what is stored --------------------------------------------------------
    def refresh(self) -> None:
        """Rebuild the screen from the database (the single source of truth)."""
        position = self.groups_scroll.verticalScrollBar().value()
        unsorted = set(self.session.unsorted())
        labels = self.session.labels()
        self.pool.clear()
        for image in self.session.order():
            if image in unsorted:
                self.pool.add_image(image, self.pixmaps[image], labels[image])
        while self.groups_layout.count():
            item = self.groups_layout.takeAt(0)
            w = item.widget() if item is not None else None
            if w is not None:
                w.deleteLater()
        self.panels = {}
        for group in self.session.groups():
            panel = GroupPanel(self, group, self.pixmaps)
            self.panels[group.label] = panel
            self.groups_layout.addWidget(panel)
        if not self.panels:  # say what this empty area is for
            hint = QLabel(
                "Your groups will appear here.\n\nDrag one or more pictures from the left onto "
                "“Drop here to start a new group”; then drag more pictures onto a group, or "
                "between groups."
            )
            hint.setWordWrap(True)
            hint.setAlignment(Qt.AlignmentFlag.AlignCenter)
            hint.setStyleSheet("color: #777; font-size: 13pt; padding: 40px;")
            self.groups_layout.addWidget(hint)
        self.groups_layout.addStretch(1)
        QTimer.singleShot(0, lambda: self.groups_scroll.verticalScrollBar().setValue(position))
        todo = self.session.missing()
        self.todo.setText(
            "Still to do: " + "; ".join(todo[:6]) + (" …" if len(todo) > 6 else "")
            if todo
            else "Everything is answered: you can finish."
        )


#: The widest a participant's reading column grows (pixels): lines stay short enough to read.
READING_WIDTH = 760


def reading_column(page: QWidget, *parts: QWidget | QLayout | int) -> None:
    """Lay ``parts`` out on ``page`` in a centred column at most :data:`READING_WIDTH` wide,
    a third of the free height above and two thirds below; an ``int`` is a gap in pixels.
    The participants' pages (consent, instructions, questions) share it."""
    column = QWidget()
    column.setMaximumWidth(READING_WIDTH)
    inner = QVBoxLayout(column)
    inner.addStretch(1)
    for part in parts:
        if isinstance(part, int):
            inner.addSpacing(part)
        elif isinstance(part, QLayout):
            inner.addLayout(part)
        else:
            inner.addWidget(part)
    inner.addStretch(2)
    layout = QHBoxLayout(page)
    layout.addStretch(1)
    layout.addWidget(column, 4)
    layout.addStretch(1)


class QuestionsPage(QWidget):
    """A page of questions (attention checks, demographics): a list to choose from, or a text box."""

    def __init__(self, title: str, questions: Sequence[Question], send: Callable[[dict[str, str]], None]) -> None:
        super().__init__()
        self.send = send
        self.fields: dict[str, QComboBox | QLineEdit] = {}
        form = QFormLayout()
        for q in questions:
            if q.options:
                box = QComboBox()
                box.addItems(["", *q.options])
                self.fields[q.key] = box
            else:
                self.fields[q.key] = QLineEdit()
            label = QLabel(q.text)
            label.setWordWrap(True)
            form.addRow(label, self.fields[q.key])
        self.next_button = QPushButton("Continue")
        self.next_button.setMinimumHeight(36)
        self.next_button.clicked.connect(lambda: self.send(self.answers()))
        reading_column(self, QLabel(html_text(title, "")), form, self.next_button)

    def answers(self) -> dict[str, str]:
        """The answers typed or chosen, by question key."""
        return {k: (f.currentText() if isinstance(f, QComboBox) else f.text()) for k, f in self.fields.items()}


class ParticipantWindow(QWidget):
    """The pages of a :class:`~ramure.studies.design.ParticipantFlow`, with the remaining time always visible."""

    closed = Signal()

    def __init__(
        self,
        study: Study,
        code: str,
        grammars: Sequence[str] | None = None,
        ask: bool = True,
        grammars_dir: str | os.PathLike | None = None,
    ) -> None:
        super().__init__()
        self.setWindowTitle(f"Ramure study — participant {code}")
        self.study, self.code, self.ask = study, code, ask
        self.flow = ParticipantFlow(study, code, front_end="desktop")
        self.config = self.flow.config
        self.grammars = list(grammars or self.flow.grammars)  # the participant's Latin-square order
        self.grammars_dir = grammars_dir
        self.last_message: str | None = None
        self.page: TestPage | None = None
        self.image_task: Task | None = None
        self.is_closed = False
        self.timer_label = QLabel("")
        self.timer_label.setObjectName("studyTimer")
        self.timer_label.setStyleSheet("font-size: 14pt; font-weight: bold;")
        self.progress_label = QLabel("")
        self.progress_label.setObjectName("studyProgress")
        self.stack = QStackedWidget()
        top = QHBoxLayout()
        top.addWidget(QLabel(f"Participant <b>{code}</b>"), 1)
        top.addWidget(self.progress_label)
        top.addSpacing(24)
        top.addWidget(self.timer_label)
        layout = QVBoxLayout(self)
        layout.addLayout(top)
        layout.addWidget(self.stack, 1)
        self.consent_page = self._consent_page()
        self.stack.addWidget(self.consent_page)
        self.done_page = QLabel("")
        self.done_page.setObjectName("donePage")
        self.done_page.setWordWrap(True)
        self.done_page.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)  # the code can be copied
        self.done_page.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.stack.addWidget(self.done_page)
        self.between_page = self._between_page()
        self.stack.addWidget(self.between_page)
        self.info_page, self.info_label, self.info_button = self._info_page()
        self.stack.addWidget(self.info_page)
        self.questions_page: QuestionsPage | None = None
        self.withdraw_button = QPushButton("Withdraw from the study…")
        self.withdraw_button.setObjectName("withdrawButton")
        self.withdraw_button.clicked.connect(lambda: self.withdraw())
        top.addWidget(self.withdraw_button)
        self.tick = QTimer(self)
        self.tick.timeout.connect(self.update_timer)
        self.tick.start(1000)
        self.resize(1300, 850)
        self.show_step()
        self.update_timer()

    def _consent_page(self):
        page = QWidget()
        text = QLabel(html_text(self.config.title, self.config.consent_text()))
        text.setObjectName("consentText")
        text.setTextFormat(Qt.TextFormat.RichText)
        text.setWordWrap(True)
        font = text.font()
        font.setPointSizeF(font.pointSizeF() * 1.3)  # read by participants: large, in a column
        text.setFont(font)
        self.agree = QCheckBox("I have read this and I agree to take part.")
        self.agree.setFont(font)
        self.start_button = QPushButton("Start")
        self.start_button.setEnabled(False)
        self.start_button.setMinimumHeight(36)
        self.agree.toggled.connect(self.start_button.setEnabled)
        self.start_button.clicked.connect(self.give_consent)
        reading_column(page, text, 16, self.agree, self.start_button)
        return page

    def _info_page(self):
        """The instructions or the practice page: a text and Continue."""
        page = QWidget()
        label = QLabel("")
        label.setObjectName("infoText")
        label.setWordWrap(True)
        font = label.font()
        font.setPointSizeF(font.pointSizeF() * 1.3)
        label.setFont(font)
        button = QPushButton("Continue")
        button.setObjectName("infoContinue")
        button.setMinimumHeight(36)
        button.clicked.connect(self._acknowledge)
        reading_column(page, label, button)
        return page, label, button

    def _between_page(self):
        """'Set 1 of 3 done' and a Continue button, shown between two tests.

        Continue is placed away from where Finish was and enabled only after a
        double-click interval, so the second click of a double click on Finish
        cannot finish (or start) the next test.
        """
        page = QWidget()
        self.between_label = QLabel("")
        self.between_label.setObjectName("betweenTests")
        self.between_label.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.continue_button = QPushButton("Continue")
        self.continue_button.setObjectName("continueButton")
        self.continue_button.setMinimumHeight(36)
        self.continue_button.clicked.connect(self.continue_tests)
        column = QVBoxLayout()
        column.addStretch(1)
        column.addWidget(self.between_label)
        column.addWidget(self.continue_button)
        column.addStretch(3)
        layout = QHBoxLayout(page)
        layout.addStretch(2)
        layout.addLayout(column, 1)
        layout.addStretch(2)
        return page

    def progress(self, grammar: str) -> tuple[int, int]:
        """``(n, m)``: ``grammar`` is test n of the participant's m (n 0: the practice set)."""
        return (self.grammars.index(grammar) + 1 if grammar in self.grammars else 0), len(self.grammars)

    def title(self, grammar: str) -> str:
        """ "Set n of m", or "Practice"."""
        n, m = self.progress(grammar)
        return set_title(n, m) if n else "Practice"

    def show_between(self, grammar: str) -> None:
        """The page between tests, after ``grammar``'s test was finished."""
        self.between_label.setText(f"<h2>{self.title(grammar)} done</h2><p>{WORDS['saved']}</p>")
        self.continue_button.setEnabled(False)
        self.stack.setCurrentWidget(self.between_page)
        delay = QApplication.styleHints().mouseDoubleClickInterval() + 100
        QTimer.singleShot(delay, lambda: self.continue_button.setEnabled(not self.is_closed))

    def continue_tests(self) -> None:
        """Leave the between-tests page for the next grammar."""
        if self.stack.currentWidget() is self.between_page:
            self.next_grammar()

    def give_consent(self) -> None:
        """Record the participant's consent and show the next step."""
        try:
            self.flow.consent()
        except RamureError as exc:
            self.refuse(str(exc))
            return
        self.show_step()

    def _acknowledge(self) -> None:
        step = self.flow.step()
        if step.kind in ("instructions", "practice") and self.stack.currentWidget() is self.info_page:
            try:
                self.flow.acknowledge(step.kind)
            except RamureError as exc:
                self.refuse(str(exc))
                return
        self.show_step()

    def _answer(self, kind: str, answers: dict[str, str]) -> None:
        try:
            self.flow.answer(kind, answers)
        except RamureError as exc:
            self.refuse(str(exc))
            return
        self.show_step()

    def show_step(self) -> TestPage | None:
        """Show the page the flow says comes next (from what is stored)."""
        step = self.flow.step()
        if step.kind == "consent":
            self.stack.setCurrentWidget(self.consent_page)
        elif step.kind in ("instructions", "practice"):
            self.info_label.setText(html_text(step.title, step.text))
            self.stack.setCurrentWidget(self.info_page)
        elif step.kind in ("attention", "demographics"):
            kind = step.kind

            def send(answers: dict[str, str]) -> None:
                self._answer(kind, answers)

            page = QuestionsPage(step.title, step.questions, send)
            if self.questions_page is not None:
                self.stack.removeWidget(self.questions_page)
                self.questions_page.deleteLater()
            self.questions_page = page
            self.stack.addWidget(page)
            self.stack.setCurrentWidget(page)
        elif step.kind == "test" and step.grammar is not None:
            if self.page is not None and self.page.session.grammar == step.grammar and not self.page.session.finished:
                self.stack.setCurrentWidget(self.page)
                return self.page
            try:
                return self.open_test(self.flow.session(step.grammar))
            except RamureError as exc:
                self.refuse(str(exc))
        else:
            self.done_page.setText(html_text(step.title, step.text))
            self.progress_label.setText("")
            self.stack.setCurrentWidget(self.done_page)
        return None

    def next_grammar(self) -> TestPage | None:
        """Go on with the flow: the next set, a page of questions, or the last page."""
        return self.show_step()

    def open_test(self, session: TestSession) -> TestPage:
        """Show the test page of ``session`` (placeholders until its pictures are drawn)."""
        self.progress_label.setText(self.title(session.grammar))
        pixmaps = {i: QPixmap.fromImage(placeholder_image(ICON, "", "…")) for i in range(1, 28)}
        page = TestPage(self, session, pixmaps, self.config)
        page.finished.connect(self._test_finished)
        if self.page is not None:
            self.stack.removeWidget(self.page)
            self.page.deleteLater()
        self.page = page
        self.stack.addWidget(page)
        self.stack.setCurrentWidget(page)
        self._draw_images(session.grammar)
        return page

    def _draw_images(self, grammar) -> None:
        path = self.study.path

        def work(progress, cancelled):
            from ramure.studies import Study

            study = Study.open(path, readonly=True)  # a connection of this thread, that only reads
            try:
                return pick_images(study, grammar, grammars_dir=self.grammars_dir)
            finally:
                study.close()

        task = self.image_task = Task("study images", work, self)
        task.done.connect(lambda images: self._images_ready(grammar, images))
        task.failed.connect(lambda exc, details: self.refuse(f"cannot draw the pictures: {exc}"))
        task.start()

    def _images_ready(self, grammar, images) -> None:
        if self.is_closed or self.page is None or self.page.session.grammar != grammar:
            return
        self.page.pixmaps = {i: QPixmap.fromImage(img) for i, img in images.items()}
        self.page.refresh()

    def _test_finished(self) -> None:
        page = self.page
        left = [g for g in self.grammars if page is None or g != page.session.grammar]
        if page is not None and any(not self._finished(g) for g in left):
            self.show_between(page.session.grammar)
        else:
            self.show_step()

    def _finished(self, grammar) -> bool:
        return self.study.finished(self.code, grammar)

    def withdraw(self, delete: bool | None = None) -> None:
        """The participant withdraws (asked first when ``delete`` is None): their answers are
        left out of the analysis, or erased; the window then closes."""
        if delete is None:
            box = QMessageBox(self)
            box.setWindowTitle("Withdraw")
            box.setText("Do you want to withdraw from the study? You can also have every answer you gave deleted.")
            keep = box.addButton("Withdraw", QMessageBox.ButtonRole.AcceptRole)
            erase = box.addButton("Withdraw and delete my answers", QMessageBox.ButtonRole.DestructiveRole)
            box.addButton(QMessageBox.StandardButton.Cancel)
            box.exec()
            if box.clickedButton() not in (keep, erase):
                return
            delete = box.clickedButton() is erase
        try:
            self.study.withdraw(self.code, delete=delete)
        except RamureError as exc:
            self.refuse(str(exc))
            return
        self.page = None
        self.done_page.setText(
            html_text(
                "You have withdrawn",
                "Thank you. " + ("Your answers are deleted." if delete else "Your answers will not be used."),
            )
        )
        self.stack.setCurrentWidget(self.done_page)
        self.withdraw_button.setEnabled(False)

    def update_timer(self) -> None:
        """Show the time left (on the current test, or the study's), red in the last two minutes."""
        if self.is_closed:
            return
        if self.page is not None and not self.page.session.finished:
            seconds = self.page.session.remaining_seconds()
        else:
            try:
                seconds = self.study.remaining_seconds(self.code)
            except RamureError:  # withdrawn and deleted
                seconds = 0.0
        minutes, secs = divmod(int(seconds), 60)
        self.timer_label.setText(f"Time left: {minutes:02d}:{secs:02d}")
        self.timer_label.setStyleSheet("font-size: 14pt; font-weight: bold;" + (" color: #c00000;" if seconds < 120 else ""))

    def refuse(self, message: str) -> None:
        """Say why something was not saved: a warning box when the window may ask, and ``last_message``."""
        self.last_message = message
        if self.ask:
            QMessageBox.warning(self, "Not saved", message)

    def closeEvent(self, event: QCloseEvent) -> None:  # noqa: N802 (Qt API)
        """Stop the timer and the picture task, then say :attr:`closed` (the study closes)."""
        self.tick.stop()
        if self.image_task is not None:
            self.image_task.cancel()
        self.is_closed = True
        self.closed.emit()
        super().closeEvent(event)


# -- the Study menu -------------------------------------------------------------------------
class StudyMenu(QObject):
    """Study ▸ Participant session… / Analyst report…

    ``parent`` is the widget its dialogs open over; ``ask=False`` never asks (a new participant
    is enrolled, tests and scripts).  A study that cannot be opened is said with :attr:`refused`.
    """

    #: A user error (a study that cannot be opened): the window reports it.
    refused = Signal(str)

    def __init__(self, menu: QMenu, parent: QWidget, ask: bool = True) -> None:
        super().__init__(parent)
        self.parent_widget = parent
        self.ask = ask
        self.windows: list[QWidget] = []
        menu.addAction("Participant session…").triggered.connect(lambda: self.participant())
        menu.addAction("Analyst report…").triggered.connect(lambda: self.analyst())

    def _ask_study(self):
        from ramure.app.desktop.menus.analyst import ask_study_path

        return ask_study_path(self.parent_widget)

    def participant(
        self,
        path: str | os.PathLike | None = None,
        code: str | None = None,
        pilot: bool = False,
        external_id: str | None = None,
    ) -> ParticipantWindow | None:
        """Open a study and a participant window (a new anonymous code unless ``code`` is given).

        ``pilot``: a new participant is a trial run, kept apart from the real data.
        ``external_id`` (a recruiting platform's id, e.g. a Prolific PID): the participant
        enrolled under it is resumed, or a new one is enrolled with it."""
        from ramure.studies import Study

        path = path or self._ask_study()
        if not path:
            return None
        try:
            study = Study.open(path)
            if code is None and external_id is not None:
                known = {p["external_id"]: p["code"] for p in study.participants() if p["external_id"]}
                code = known.get(external_id) or study.add_participant(external_id=external_id, pilot=pilot)
            if code is None:
                code = self._choose_participant(study, pilot)
                if code is None:
                    study.close()
                    return None
            elif code not in [p["code"] for p in study.participants()]:
                study.add_participant(code, pilot=pilot)
        except RamureError as exc:
            self.refused.emit(str(exc))
            return None
        win = ParticipantWindow(study, code, ask=self.ask)
        win.closed.connect(study.close)
        self.windows.append(win)
        win.show()
        return win

    def _choose_participant(self, study, pilot=False):
        """A new code, or an existing one to resume, or a pilot run (asked in a small dialog)."""
        codes = [p["code"] for p in study.participants() if p["consent"] or not p["withdrawn_at"]]
        if not codes or not self.ask:
            return study.add_participant(pilot=pilot)
        from PySide6.QtWidgets import QInputDialog

        new, trial = "New participant", "New pilot run (kept apart from the real data)"
        choice, ok = QInputDialog.getItem(
            self.parent_widget, "Participant", "Resume a participant or start a new one:", [new, trial, *codes], 0, False
        )
        if not ok:
            return None
        if choice in (new, trial):
            return study.add_participant(pilot=pilot or choice == trial)
        return choice

    def analyst(self, path: str | os.PathLike | None = None) -> AnalystWindow | None:
        """Open a study's analyst window: who took part, and its report."""
        from ramure.app.desktop.menus.analyst import AnalystWindow

        path = path or self._ask_study()
        if not path:
            return None
        win = AnalystWindow(ask=self.ask)
        self.windows.append(win)
        win.show()
        win.open_study(path)
        return win


__all__ = ["GroupPanel", "ImageList", "ParticipantWindow", "QuestionsPage", "StudyMenu", "TestPage", "fit_icon", "pick_images"]
