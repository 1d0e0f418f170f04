"""Study ▸ New study from this exploration…: explore, fill the dialog with keys, create, copy the serve command."""

from __future__ import annotations

import json
import urllib.error
import urllib.request

import pytest
from PySide6.QtCore import QProcess, Qt
from PySide6.QtWidgets import QApplication

from desktop_helpers import settle

pytestmark = pytest.mark.gui


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("RAMURE_CACHE", str(tmp_path / "cache"))


def menu_action(window, menu_title, text):
    for top in window.menuBar().actions():
        if top.text().replace("&", "") == menu_title:
            for action in top.menu().actions():
                if action.text().replace("&", "") == text:
                    return action
    raise AssertionError(f"no {menu_title} > {text}")


def _get(qtbot, url, seconds=30):
    """The body at ``url`` once the server listens (it announces its address just before)."""
    for _ in range(seconds * 10):
        try:
            with urllib.request.urlopen(url, timeout=10) as reply:
                return reply.read()
        except urllib.error.URLError:
            qtbot.wait(100)
    raise AssertionError(f"{url} never answered")


def test_new_study_explores_first_then_builds_a_servable_study(make_window, qtbot, tmp_path):
    from ramure.studies.serve import check_servable
    from ramure.studies.storage import Study

    w = make_window(n=3)
    assert w.variants.variant_set is None
    menu_action(w, "Study", "New study from this exploration…").trigger()  # no exploration yet: it explores
    qtbot.waitUntil(lambda: w.new_study.dialog is not None, timeout=60000)
    settle(qtbot, w)
    dialog = w.new_study.dialog
    qtbot.waitExposed(dialog)
    folder = tmp_path / "honda study"
    qtbot.keyClicks(dialog.folder, str(folder))
    dialog.title.selectAll()
    qtbot.keyClicks(dialog.title, "Honda pilot")
    qtbot.mouseClick(dialog.create_button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: dialog.served.isVisible(), timeout=60000)
    db = folder / "study.db"
    assert dialog.command.text() == f"ramure study serve '{db}'"
    assert (folder / "honda_sympodial" / "picks.json").is_file()  # the exploration is saved with the study
    with Study.open(db, readonly=True) as study:
        assert study.name == "Honda pilot" and study.grammars == ["honda_sympodial"]
        assert [p.variant for p in study.picks("honda_sympodial")] == [p["variant"] for p in w.variants.variant_set.picks]
        check_servable(study)
    qtbot.mouseClick(dialog.copy_button, Qt.MouseButton.LeftButton)
    assert QApplication.clipboard().text() == dialog.command.text()
    pytest.importorskip("uvicorn")
    qtbot.mouseClick(dialog.serve_button, Qt.MouseButton.LeftButton)  # served here, as a child process
    try:
        qtbot.waitUntil(lambda: dialog.server_addresses is not None, timeout=60000)
        address = dialog.server_addresses["participants"]
        assert address.startswith("http://127.0.0.1:") and address in dialog.addresses.text()
        assert json.loads(_get(qtbot, address + "api/study"))["title"] == "Honda pilot"
    finally:
        process = dialog.server
        qtbot.mouseClick(dialog.stop_button, Qt.MouseButton.LeftButton)
    assert process.state() == QProcess.ProcessState.NotRunning and dialog.serve_button.isEnabled()
    # the same folder again: refused in the dialog, the study untouched
    before = db.read_bytes()
    again = w.new_study.new_study()
    qtbot.keyClicks(again.folder, str(folder))
    qtbot.mouseClick(again.create_button, Qt.MouseButton.LeftButton)
    assert "already holds a study" in again.note.text() and not again.served.isVisible()
    assert again.create_button.isEnabled()  # another folder may be tried
    assert db.read_bytes() == before
    again.add_to.click()  # the same pictures as one more part, under another name
    assert not again.title.isEnabled()
    again.set_name.selectAll()
    qtbot.keyClicks(again.set_name, "second")
    qtbot.mouseClick(again.create_button, Qt.MouseButton.LeftButton)
    assert again.note.text().startswith("Added to the study"), again.note.text()
    with Study.open(db, readonly=True) as study:
        assert study.name == "Honda pilot" and study.grammars == ["honda_sympodial", "second"]
    again.close()


def test_save_exploration_folder_writes_picks_json(make_window, qtbot, tmp_path):
    from ramure.studies.picks import load_picks

    w = make_window(n=3)
    assert not w.new_study.save_exploration(tmp_path / "nothing")  # nothing explored yet: refused
    assert "Explore the variants first" in w.last_message
    w.variants.explore(n_jobs=1)
    qtbot.waitUntil(lambda: w.variants.variant_set is not None and not w.variants.busy(), timeout=60000)
    settle(qtbot, w)
    assert w.new_study.save_exploration(tmp_path / "explored")
    picks = load_picks(tmp_path / "explored")
    assert [p.variant for p in picks] == [p["variant"] for p in w.variants.variant_set.picks]
    assert all(p.image and p.image.endswith(f"pick_{p.id:02d}.png") for p in picks)
