"""File ▸ Open reads L-Py models (asking once per folder before their code runs) and MTGs."""

from __future__ import annotations

import pytest

from desktop_helpers import settle

pytestmark = pytest.mark.gui

MODEL = "Axiom: A(1)\nderivation length: 2\nproduction:\nA(x) --> F(x)[+A(x+1)]A(x+1)\nendlsystem\n"
MTG = (
    "CLASSES:\nSYMBOL\tSCALE\tDECOMPOSITION\tINDEXATION\tDEFINITION\n$\t0\tFREE\tFREE\tIMPLICIT\n"
    "P\t1\tFREE\tFREE\tIMPLICIT\nE\t2\tFREE\tFREE\tIMPLICIT\n\nDESCRIPTION:\nLEFT\tRIGHT\tRELTYPE\tMAX\n\n"
    "FEATURES:\nNAME\tTYPE\n\nMTG:\nENTITY-CODE\n/P1/E1\n^<E2\n\t+E3\n"
)


def _models(folder):
    folder.mkdir()
    for name in ("a.lpy", "b.lpy"):
        (folder / name).write_text(MODEL.replace("A(1)", "A(1)" if name == "a.lpy" else "A(5)"))
    return folder / "a.lpy", folder / "b.lpy"


def test_an_lpy_is_refused_when_the_window_may_not_ask(make_window, qtbot, tmp_path):
    a, _ = _models(tmp_path / "models")
    w = make_window(n=3)
    before = w.controller.explorer.derivation.to_string()
    assert w.files.open_grammar(a) is None
    settle(qtbot, w)
    assert "a.lpy is an L-Py model" in w.last_message
    assert w.controller.explorer.derivation.to_string() == before


def test_the_desktop_asks_once_per_folder(make_window, qtbot, tmp_path, monkeypatch):
    from PySide6.QtWidgets import QMessageBox

    from ramure.app.desktop.menus import files

    a, b = _models(tmp_path / "models")
    w = make_window(n=3)
    w.ask = True
    asked = []

    def question(parent, title, text, *args):
        asked.append(text)
        return QMessageBox.StandardButton.Yes

    monkeypatch.setattr(files.QMessageBox, "question", question)
    w.files.open_grammar(a)
    settle(qtbot, w)
    assert len(asked) == 1 and str(a.parent.resolve()) in asked[0]
    assert w.controller.explorer.derivation.to_string() == "F(1)[+F(2)[+A(3)]A(3)]F(2)[+A(3)]A(3)"
    assert w.editor.text() == MODEL
    w.files.open_grammar(b)  # the same folder: not asked again
    settle(qtbot, w)
    assert len(asked) == 1
    assert w.controller.explorer.derivation.to_string().startswith("F(5)[+F(6)")
    assert w.settings.value("trusted_code_folders") in ([str(a.parent.resolve())], str(a.parent.resolve()))
    w.ask = False


def test_a_no_keeps_the_plant(make_window, qtbot, tmp_path, monkeypatch):
    from PySide6.QtWidgets import QMessageBox

    from ramure.app.desktop.menus import files

    a, _ = _models(tmp_path / "models")
    w = make_window(n=3)
    before = w.controller.explorer.derivation.to_string()
    w.ask = True
    monkeypatch.setattr(files.QMessageBox, "question", lambda *args: QMessageBox.StandardButton.No)
    assert w.files.open_grammar(a) is None
    settle(qtbot, w)
    w.ask = False
    assert w.controller.explorer.derivation.to_string() == before
    assert not w.files.code_trust().folders


def test_an_mtg_opens_as_a_plant(make_window, qtbot, tmp_path):
    path = tmp_path / "plant.mtg"
    path.write_text(MTG)
    w = make_window(n=3)
    w.files.open_grammar(path)
    settle(qtbot, w)
    ex = w.controller.explorer
    assert ex.path is None and len(ex.skeleton) == 3  # E1, E2 and the branch E3
    assert "w:" in w.editor.text()  # the grammar the MTG became


def test_file_open_is_named_for_every_plant_file_it_opens(make_window, qtbot, monkeypatch):
    # the first File entry opens grammars, L-Py models and MTGs: "Open plant…", not "Open grammar…"
    from PySide6.QtGui import QKeySequence

    w = make_window(n=3)
    file_top = next(a for a in w.menuBar().actions() if a.text() == "&File")
    first = file_top.menu().actions()[0]
    assert first.text() == "&Open plant…"
    assert first.shortcut() == QKeySequence(QKeySequence.StandardKey.Open)
    asked = []
    monkeypatch.setattr(w.files, "_ask_open", lambda title, filters: asked.append((title, filters)))
    first.trigger()  # the dialog is asked for with the same name and every plant format
    ((title, filters),) = asked
    assert title == "Open plant"
    assert all(f"*.{suffix}" in filters.split(";;")[0] for suffix in ("lsys", "l", "lpy", "mtg"))
