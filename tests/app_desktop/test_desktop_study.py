"""Study mode: consent, drag-and-drop sorting, representatives, Likert, qualifiers, timer, analyst."""

from __future__ import annotations

import json
import re
import warnings

import pytest
from PySide6.QtCore import QPoint, QPointF, Qt
from PySide6.QtGui import QDragEnterEvent, QDropEvent
from PySide6.QtTest import QTest
from PySide6.QtWidgets import QApplication

from ramure.studies import Study, lattice_picks, run_simulation

pytestmark = pytest.mark.gui


@pytest.fixture
def study_path(tmp_path):
    """A study of Honda's tree whose 27 picks vary r1, a2 and wr (so thumbnails can be derived)."""
    picks = [
        {
            "id": p.id,
            "variant": p.variant,
            "pca": list(p.pca),
            "params": {
                "rule": 1,
                "constants": {
                    "r1": p.params["constants"]["r1"],
                    "a2": p.params["constants"]["a0"] * 60 / 45,
                    "wr": p.params["constants"]["wr"],
                },
            },
        }
        for p in lattice_picks(seed=3)
    ]
    path = tmp_path / "study.db"
    Study.create(path, grammars={"honda_sympodial": picks}, name="desk").close()
    return path


def drop(source, ids, target):
    """Drop images ``ids`` of list ``source`` on list ``target`` (what a mouse drag ends with)."""
    items = [source.item(i) for i in range(source.count()) if source.item(i).data(Qt.ItemDataRole.UserRole) in ids]
    mime = source.mimeData(items)
    args = (Qt.DropAction.MoveAction, mime, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        enter = QDragEnterEvent(QPoint(5, 5), *args)
    QApplication.sendEvent(target.viewport(), enter)
    assert enter.isAccepted()
    QApplication.sendEvent(target.viewport(), QDropEvent(QPointF(5, 5), *args))


def to_test(qtbot, win):
    """Click Continue on the instructions and practice pages, as the participant does."""
    for _ in range(3):
        if win.stack.currentWidget() is not win.info_page:
            break
        qtbot.mouseClick(win.info_button, Qt.MouseButton.LeftButton)
    return win.page


def answer_questions(qtbot, win, **answers):
    """Fill the page of questions (attention checks, demographics) and press Continue."""
    page = win.questions_page
    assert win.stack.currentWidget() is page
    for key, value in answers.items():
        field = page.fields[key]
        if hasattr(field, "setCurrentText"):
            field.setCurrentText(value)
        else:
            QTest.keyClicks(field, value)
    qtbot.mouseClick(page.next_button, Qt.MouseButton.LeftButton)


def stored(path, code):
    """The groups as another connection sees them (committed answers only)."""
    with Study.open(path) as study:
        return study.session(code, "honda_sympodial").groups()


def test_participant_session_writes_every_answer(make_window, qtbot, study_path, artifacts):
    w = make_window(n=4)
    win = w.study_menu.participant(study_path, code="P7")
    qtbot.addWidget(win)
    assert win.stack.currentWidget() is win.consent_page
    assert not win.start_button.isEnabled()
    win.agree.setChecked(True)
    qtbot.mouseClick(win.start_button, Qt.MouseButton.LeftButton)
    page = to_test(qtbot, win)
    assert page is not None and page.pool.count() == 27
    assert re.fullmatch(r"Time left: \d\d:\d\d", win.timer_label.text())
    qtbot.waitUntil(lambda: not win.image_task.running, timeout=20000)
    # the pool shows the participant's seeded order
    assert page.pool.image_ids() == page.session.order()

    drop(page.pool, list(range(1, 14)), page.new_group)
    assert [g.images for g in stored(study_path, "P7")] == [list(range(1, 14))]
    drop(page.pool, list(range(14, 28)), page.new_group)
    assert len(stored(study_path, "P7")) == 2 and page.pool.count() == 0
    # move one image from group 2 to group 1 by dropping it on group 1's list
    drop(page.panels[2].images, [27], page.panels[1].images)
    groups = stored(study_path, "P7")
    assert 27 in groups[0].images and 27 not in groups[1].images

    assert "Still to do" in page.todo.text()
    page.finish()
    assert "not complete" in win.last_message and not page.session.finished

    for label in (1, 2):
        panel = page.panels[label]
        first = panel.images.item(0)
        first.setSelected(True)
        qtbot.mouseClick(panel.make_rep, Qt.MouseButton.LeftButton)
        panel = page.panels[label]  # the screen is rebuilt from the database after each answer
        for key in ("usefulness", "difference", "representative"):
            page.panels[label].rows[key].buttons.button(3).click()
        panel = page.panels[label]
        panel.qualifier.setText("dense" if label == 1 else "petit")
        QTest.keyClick(panel.qualifier, Qt.Key.Key_Return)
    groups = stored(study_path, "P7")
    qtbot.wait(50)  # let the rebuilt group panels show
    win.grab().save(str(artifacts / "desktop_study.png"))
    assert [g.qualifiers for g in groups] == [["dense"], ["petit"]]
    assert all(g.usefulness == 3 and g.difference == 3 and g.representative_quality == 3 for g in groups)
    assert all(g.representative is not None for g in groups)
    page.panels[1].qualifiers.item(0).setSelected(True)
    page.remove_qualifier(1, "dense")
    assert stored(study_path, "P7")[0].qualifiers == []
    page.add_qualifier(1, "dense")
    qtbot.mouseClick(page.finish_button, Qt.MouseButton.LeftButton)
    answer_questions(qtbot, win, attention_1="fair")
    answer_questions(qtbot, win, age="25-39", expertise="a little")
    assert win.stack.currentWidget() is win.done_page
    with Study.open(study_path) as study:
        assert study.tests()[0]["finished_at"] is not None
    win.close()


def test_refused_answers_change_nothing(make_window, qtbot, study_path):
    w = make_window(n=4)
    win = w.study_menu.participant(study_path, code="P8")
    qtbot.addWidget(win)
    win.give_consent()
    page = to_test(qtbot, win)
    page.move_images([1, 2, 3], "new")
    assert page.set_representative(1, 9) is None and "not in group 1" in win.last_message
    assert not page.add_qualifier(1, "   ")
    assert stored(study_path, "P8")[0].representative is None
    qtbot.waitUntil(lambda: not win.image_task.running, timeout=20000)
    win.close()


def test_analyst_view_shows_the_report(make_window, qtbot, study_path, artifacts):
    with Study.open(study_path) as study:
        run_simulation(study, participants=3, seed=1)
    w = make_window(n=4)
    win = w.study_menu.analyst(study_path)
    qtbot.addWidget(win)
    qtbot.waitUntil(lambda: win.summary is not None, timeout=30000)
    assert win.participants.rowCount() == 3
    assert "co-occurrence" in win.report.toPlainText().lower() or "cooccurrence" in win.report.toHtml()
    win.grab().save(str(artifacts / "desktop_analyst.png"))
    assert win.summary["tests"] == 3
    win.open_study(study_path.parent / "nothing.db")
    assert "no such study" in win.last_message
    win.close()


@pytest.fixture
def three_grammars(tmp_path):
    """A study of three grammars with no grammar file (placeholder pictures: quick to show)."""
    path = tmp_path / "three.db"
    with Study.create(path, grammars={f"g{i}": lattice_picks(seed=i) for i in (1, 2, 3)}) as study:
        study.add_participant("P1", consent=True)
    return path


def participant_window(qtbot, path, code="P1"):
    from ramure.app.desktop.menus.study import ParticipantWindow

    study = Study.open(path)
    win = ParticipantWindow(study, code, ask=False)
    win.closed.connect(study.close)
    qtbot.addWidget(win)
    win.show()
    qtbot.waitExposed(win)
    to_test(qtbot, win)
    qtbot.waitUntil(lambda: not win.image_task.running, timeout=20000)
    qtbot.wait(50)  # the pictures' arrival rebuilds the page once more
    return win


def click(qtbot, find):
    """Click the widget ``find()`` returns once it is shown (the panels are rebuilt after each answer)."""
    qtbot.waitUntil(lambda: find().isVisible(), timeout=3000)
    qtbot.mouseClick(find(), Qt.MouseButton.LeftButton)


def answer_group(qtbot, page, label, rep, word):
    """Representative, three ratings and a word, through the group panel's widgets."""
    qtbot.waitUntil(lambda: page.panels[label].make_rep.isVisible(), timeout=3000)
    panel = page.panels[label]  # select and click on the same panel, with no event in between
    panel.images.item(panel.images.image_ids().index(rep)).setSelected(True)
    qtbot.mouseClick(panel.make_rep, Qt.MouseButton.LeftButton)
    for key, level in (("usefulness", 4), ("difference", 2), ("representative", 3)):
        click(qtbot, lambda key=key, level=level: page.panels[label].rows[key].buttons.button(level))
    qtbot.waitUntil(lambda: page.panels[label].qualifier.isVisible(), timeout=3000)
    QTest.keyClicks(page.panels[label].qualifier, word)
    QTest.keyClick(page.panels[label].qualifier, Qt.Key.Key_Return)


def shown(panel):
    """What a group panel shows: representative, the three levels checked, the words."""
    levels = tuple(panel.rows[key].buttons.checkedId() for key in ("usefulness", "difference", "representative"))
    words = [panel.qualifiers.item(i).text() for i in range(panel.qualifiers.count())]
    return panel.rep_label.text(), levels, words


def test_moving_a_picture_keeps_both_groups_answers(qtbot, three_grammars):
    win = participant_window(qtbot, three_grammars)
    page = win.page
    drop(page.pool, list(range(1, 10)), page.new_group)
    drop(page.pool, list(range(10, 19)), page.new_group)
    answer_group(qtbot, page, 1, 5, "petit")
    answer_group(qtbot, page, 2, 14, "grand")
    label = page.session.labels()  # what the participant sees under each pick
    drop(page.panels[1].images, [3], page.panels[2].images)  # a plain picture moves
    assert shown(page.panels[1]) == (f"Representative: {label[5]}", (4, 2, 3), ["petit"])
    assert shown(page.panels[2]) == (f"Representative: {label[14]}", (4, 2, 3), ["grand"])
    drop(page.panels[2].images, [14], page.panels[1].images)  # group 2's representative moves
    assert shown(page.panels[1]) == (f"Representative: {label[5]}", (4, 2, 3), ["petit"])
    assert shown(page.panels[2]) == ("Representative: —", (4, 2, -1), ["grand"])
    assert "group 2: choose a representative" in page.todo.text()
    groups = {g.label: g for g in page.session.groups()}
    assert sorted(groups[1].images) == sorted([i for i in range(1, 10) if i != 3] + [14])
    assert (groups[2].usefulness, groups[2].qualifiers, groups[2].representative) == (4, ["grand"], None)
    moves = [e for e in win.study.events("P1") if e["action"] == "group"]
    assert len(moves) == 4 and moves[-1]["detail"]["representative_cleared"] == [2]
    win.close()


def test_a_double_click_on_finish_cannot_finish_the_next_grammar(qtbot, three_grammars):
    win = participant_window(qtbot, three_grammars)
    assert win.progress_label.text() == "Set 1 of 3"
    page = win.page
    for g in range(3):
        page.move_images(list(range(1 + 9 * g, 10 + 9 * g)), "new")
    for label in (1, 2, 3):
        answer_group(qtbot, page, label, 9 * label, f"word{label}")
    assert not page.session.missing()
    # Two quick clicks where Finish is: the second goes to whatever is there by then.
    where = page.finish_button.mapTo(win, page.finish_button.rect().center())
    qtbot.waitUntil(page.finish_button.isVisible, timeout=3000)
    qtbot.mouseClick(page.finish_button, Qt.MouseButton.LeftButton)
    target = win.childAt(where) or win
    qtbot.mouseClick(target, Qt.MouseButton.LeftButton, pos=target.mapFrom(win, where))
    assert win.last_message is None  # no "Not saved – images not in any group: ..."
    assert win.stack.currentWidget() is win.between_page
    assert "Set 1 of 3 done" in win.between_label.text()
    assert [t["grammar"] for t in win.study.tests()] == ["g1"]  # the next test is not even started
    assert target is not win.continue_button or not win.continue_button.isEnabled()
    qtbot.waitUntil(win.continue_button.isEnabled, timeout=3000)
    qtbot.mouseClick(win.continue_button, Qt.MouseButton.LeftButton)
    answer_questions(qtbot, win, attention_1="fair")  # the attention checks come after the first set
    assert win.stack.currentWidget() is win.page and win.page.session.grammar == "g2"
    assert win.progress_label.text() == "Set 2 of 3"
    assert win.page.session.groups() == [] and not win.page.session.finished
    win.close()


# -- issue 37, item 4: pca.json confined ------------------------------------------------------
def exploration_study(folders, doc, db="study.db"):
    """A study ``folders/db`` whose grammar's picks come from ``folders/explore`` (its ``pca.json`` is ``doc``)."""
    explore = folders / "explore"
    picks = [
        dict(id=p.id, variant=p.variant, pca=list(p.pca), params={"rule": None, "constants": {}, "tag": p.id})
        for p in lattice_picks()
    ]
    (explore / "picks.json").write_text(json.dumps(picks))
    (explore / "pca.json").write_text(json.dumps(doc))
    (folders / db).parent.mkdir(exist_ok=True)
    return Study.create(folders / db, grammars={"honda": explore})


@pytest.mark.parametrize(
    "doc, db, reads",
    [
        ({"grammar": "../outside/evil", "n": 2}, "study.db", False),
        ({"grammar": "evil", "n": "lots"}, "study.db", False),
        ({"grammar": "evil", "n": 2}, "study.db", True),
        ({"grammar": "evil", "n": 2}, "elsewhere/study.db", False),  # the exploration is outside the study's folder
    ],
)
def test_the_study_panel_reads_no_grammar_outside_its_folders(qapp, tmp_path, monkeypatch, doc, db, reads):
    """The grammars folder here is ``outside``: ``evil`` names a grammar there, ``../outside/evil`` does not."""
    folders = tmp_path
    for sub in ("explore", "outside"):
        (folders / sub).mkdir()
    (folders / "outside" / "evil.lsys").write_text("n: 2\nw: A\np:\n  A -> F[+A]A\n")
    from ramure.app.desktop.menus.study import pick_images
    from ramure.lsys import LSystem

    read = []
    real = LSystem.from_file.__func__
    monkeypatch.setattr(
        LSystem, "from_file", classmethod(lambda cls, path, *a, **k: read.append(path) or real(cls, path, *a, **k))
    )
    with exploration_study(folders, doc, db) as study:
        images = pick_images(study, "honda", size=16, grammars_dir=folders / "outside")
    assert sorted(images) == list(range(1, 28))
    assert [p.name for p in read] == (["evil.lsys"] if reads else [])  # refused: placeholders, the file never read


def test_the_participant_pages_share_one_reading_column(qtbot):
    from PySide6.QtWidgets import QFormLayout, QLabel, QPushButton, QWidget

    from ramure.app.desktop.launch import make_application
    from ramure.app.desktop.menus.study import READING_WIDTH, reading_column

    make_application()
    page, text, button, form = QWidget(), QLabel("consent"), QPushButton("Start"), QFormLayout()
    reading_column(page, text, 16, form, button)
    (column,) = [page.layout().itemAt(i).widget() for i in range(page.layout().count()) if page.layout().itemAt(i).widget()]
    assert column.maximumWidth() == READING_WIDTH == 760
    inner = column.layout()
    kinds = []
    for i in range(inner.count()):
        item = inner.itemAt(i)
        kinds.append(item.widget() or item.layout() or (item.spacerItem().sizeHint().height() or "stretch"))
    assert kinds == ["stretch", text, 16, form, button, "stretch"]
    assert [inner.stretch(i) for i in (0, 5)] == [1, 2]  # a third of the free height above
