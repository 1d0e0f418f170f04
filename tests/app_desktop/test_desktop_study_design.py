"""Issue 38 §2-§3 in the desktop: the study's own words, order, pages, pictures all in view."""

from __future__ import annotations

import pytest
from PySide6.QtCore import Qt
from PySide6.QtTest import QTest
from PySide6.QtWidgets import QAbstractButton, QGroupBox, QLabel
from test_desktop_study import answer_group, answer_questions, participant_window

from ramure.studies import Study, lattice_picks
from ramure.studies.design import StudyConfig, jargon_in

pytestmark = pytest.mark.gui


def make_study(path, participants=1, **kwargs):
    with Study.create(path, grammars={f"g{i}": lattice_picks(seed=i) for i in (1, 2, 3)}, **kwargs) as study:
        for _ in range(participants):
            study.add_participant(consent=True)
    return path


def texts(widget):
    """Every text a participant can read on ``widget``'s visible labels, buttons and boxes."""
    found = []
    for child in widget.findChildren(QLabel) + widget.findChildren(QAbstractButton) + widget.findChildren(QGroupBox):
        if child.isVisible():
            found.append(child.title() if isinstance(child, QGroupBox) else child.text())
    return found


def finish_set(qtbot, page, word="petit"):
    page.move_images(list(range(1, 28)), "new")
    answer_group(qtbot, page, 1, 5, word)
    qtbot.mouseClick(page.finish_button, Qt.MouseButton.LeftButton)


def test_participant_pages_show_no_jargon_and_no_grammar_name(qtbot, tmp_path):
    config = StudyConfig(contact="lab@example.org")
    win = participant_window(qtbot, make_study(tmp_path / "s.db", config=config), code="P101")
    seen = texts(win)
    win.page.move_images([1, 2, 3], "new")
    qtbot.waitUntil(lambda: win.page.panels[1].make_rep.isVisible(), timeout=3000)
    seen += texts(win)  # a group's panel: its questions, buttons and hints
    assert any("How useful" in t for t in seen)
    finish_set(qtbot, win.page)
    seen += texts(win)
    qtbot.waitUntil(win.continue_button.isEnabled, timeout=3000)
    qtbot.mouseClick(win.continue_button, Qt.MouseButton.LeftButton)
    seen += texts(win)
    assert [t for t in seen if jargon_in(t) or any(f"g{i}" in t.split() for i in (1, 2, 3))] == []
    assert "Set 1 of 3" in seen and "Finish this set" in seen
    win.close()


def test_consent_shows_the_study_contact_and_retention(qtbot, tmp_path):
    path = tmp_path / "s.db"
    with Study.create(path, grammars={"g1": lattice_picks(seed=1)}, config=StudyConfig(contact="ada@lab.org")) as study:
        study.add_participant("P1")
    study = Study.open(path)
    from ramure.app.desktop.menus.study import ParticipantWindow

    win = ParticipantWindow(study, "P1", ask=False)
    qtbot.addWidget(win)
    text = win.consent_page.findChild(QLabel, "consentText").text()
    assert "ada@lab.org" in text and "five years" in text and "withdraw" in text
    win.close()
    study.close()


def test_the_second_participant_gets_another_order(qtbot, tmp_path):
    win = participant_window(qtbot, make_study(tmp_path / "s.db", participants=2), code="P102")
    assert win.page.session.grammar == "g2" and win.grammars == ["g2", "g3", "g1"]
    win.close()


def test_words_typed_with_a_comma_are_two_words_and_the_front_end_is_stored(qtbot, tmp_path):
    win = participant_window(qtbot, make_study(tmp_path / "s.db"), code="P101")
    page = win.page
    page.move_images([1, 2, 3], "new")
    qtbot.waitUntil(lambda: page.panels[1].qualifier.isVisible(), timeout=3000)
    QTest.keyClicks(page.panels[1].qualifier, "dense, taller")
    QTest.keyClick(page.panels[1].qualifier, Qt.Key.Key_Return)
    assert page.session.groups()[0].qualifiers == ["dense", "taller"]
    assert {e["front_end"] for e in win.study.events("P101") if e["grammar"]} == {"desktop"}
    win.close()


def test_a_spent_budget_says_which_sets_were_skipped(qtbot, tmp_path):
    config = StudyConfig(attention_checks=(), demographics=(), completion_code="XY-12")
    path = make_study(tmp_path / "s.db", budget_minutes=0.001, config=config)
    win = participant_window(qtbot, path, code="P101")
    finish_set(qtbot, win.page)
    qtbot.waitUntil(win.continue_button.isEnabled, timeout=3000)
    qtbot.mouseClick(win.continue_button, Qt.MouseButton.LeftButton)
    assert win.stack.currentWidget() is win.done_page
    text = win.done_page.text()
    assert "set 2 of 3, set 3 of 3 were not shown" in text and "XY-12" in text
    assert "All your answers are saved" not in text
    win.close()


def test_attention_and_demographics_answers_are_stored(qtbot, tmp_path):
    config = StudyConfig(completion_code="OK-1")
    with Study.create(tmp_path / "s.db", grammars={"g1": lattice_picks(seed=1)}, config=config) as study:
        study.add_participant("P1", consent=True)
    win = participant_window(qtbot, tmp_path / "s.db")
    finish_set(qtbot, win.page)
    answer_questions(qtbot, win)  # nothing chosen: refused, asked again
    assert "please answer" in win.last_message
    answer_questions(qtbot, win, attention_1="poor")
    answer_questions(qtbot, win, age="60 or over", expertise="very")
    assert win.stack.currentWidget() is win.done_page and "OK-1" in win.done_page.text()
    answers = win.study.participant_answers("P1")
    assert answers["attention"] == {"attention_1": "poor"} and answers["demographics"]["age"] == "60 or over"
    win.close()


def test_all_27_pictures_are_in_view_and_a_double_click_enlarges_one(qtbot, tmp_path):
    win = participant_window(qtbot, make_study(tmp_path / "s.db"), code="P101")
    pool = win.page.pool
    qtbot.wait(50)
    area = pool.viewport().rect()
    inside = [pool.item(i) for i in range(pool.count()) if area.contains(pool.visualItemRect(pool.item(i)))]
    assert pool.count() == 27 and len(inside) == 27
    assert pool.iconSize().width() >= 64
    item = pool.item(4)
    where = pool.visualItemRect(item).center()
    QTest.mouseClick(pool.viewport(), Qt.MouseButton.LeftButton, pos=where)  # a double click: press, release,
    QTest.mouseDClick(pool.viewport(), Qt.MouseButton.LeftButton, pos=where)  # then the double-click event
    dialog = win.page.enlarged
    shown = dialog.findChild(QLabel, "enlarged").pixmap()
    assert dialog.isVisible() and shown.width() > pool.iconSize().width() * 2
    assert dialog.windowTitle() == win.page.session.labels()[item.data(Qt.ItemDataRole.UserRole)]
    dialog.close()
    win.close()


def test_withdrawing_from_the_window_erases_the_answers(qtbot, tmp_path):
    win = participant_window(qtbot, make_study(tmp_path / "s.db", participants=2), code="P101")
    win.page.move_images([1, 2], "new")
    win.withdraw(delete=True)
    assert win.stack.currentWidget() is win.done_page and "deleted" in win.done_page.text()
    assert [p["code"] for p in win.study.participants()] == ["P102"]
    win.close()


def test_the_practice_sort_comes_first_then_set_1(qtbot, tmp_path):
    config = StudyConfig(practice_set="g3", attention_checks=(), demographics=())
    win = participant_window(qtbot, make_study(tmp_path / "s.db", config=config), code="P101")
    assert win.page.session.grammar == "g3" and win.progress_label.text() == "Practice"
    finish_set(qtbot, win.page)
    assert "Practice done" in win.between_label.text()
    qtbot.waitUntil(win.continue_button.isEnabled, timeout=3000)
    qtbot.mouseClick(win.continue_button, Qt.MouseButton.LeftButton)
    assert win.page.session.grammar == "g1" and win.progress_label.text() == "Set 1 of 2"
    win.close()


def test_the_study_menu_enrols_by_external_id_and_marks_pilots(make_window, qtbot, tmp_path):
    path = make_study(tmp_path / "s.db", participants=0)
    w = make_window(n=2)
    first = w.study_menu.participant(path, external_id="5f3a9c1e2b")
    qtbot.addWidget(first)
    first.close()
    again = w.study_menu.participant(path, external_id="5f3a9c1e2b")  # the same person comes back
    qtbot.addWidget(again)
    trial = w.study_menu.participant(path, pilot=True)
    qtbot.addWidget(trial)
    rows = again.study.participants()
    assert again.code == first.code and [(p["external_id"], p["pilot"]) for p in rows] == [("5f3a9c1e2b", False), (None, True)]
    again.close()
    trial.close()
