"""Undo and Redo say what they did, in the model's words (issue 34, section 4), and an undo that
brings back the model's text drops a grammar error typed since."""

from __future__ import annotations

import pathlib

from ramure.app.model import Explorer

ROOT = pathlib.Path(__file__).resolve().parents[2]
HONDA = ROOT / "grammars" / "honda_sympodial.lsys"


def test_undo_and_redo_say_what_they_took_back_or_brought_again():
    ex = Explorer(HONDA, n=6)
    ex.select(ex.session.leaves_with_symbol("F")[-3:])
    assert len(ex.selection) == 3
    ex.regrow()
    ex.set_constant("a2", 45)
    ex.set_derivation(n=7)
    assert ex.history_note == ""
    ex.undo()
    assert ex.history_note == "Undid: n = 7"
    ex.undo()
    assert ex.history_note == "Undid: a2 = 45"
    ex.undo()
    assert ex.history_note == "Undid: regrow of 3 leaves"
    ex.undo()
    assert ex.history_note == "Nothing to undo"
    ex.redo()
    assert ex.history_note == "Redid: regrow of 3 leaves"
    ex.redo()
    assert ex.history_note == "Redid: a2 = 45"
    ex.redo()
    assert ex.history_note == "Redid: n = 7"
    ex.set_constant("a2", 30)
    assert ex.history_note == ""  # any other change ends the note


def test_undo_of_typing_names_the_change_and_prune_counts_leaves():
    ex = Explorer(HONDA, n=6)
    ex.set_text(ex.text + "\n// a note\n")
    ex.select(ex.session.leaves_with_symbol("F")[-2:])
    ex.prune()
    ex.undo()
    assert ex.history_note == "Undid: prune of 2 leaves"
    ex.undo()
    assert ex.history_note == "Undid: a change of the grammar text"


def test_an_undo_that_fixes_the_text_drops_the_stale_error():
    ex = Explorer(HONDA, n=6)
    good = ex.document_text()
    ex.set_constant("a2", 45)
    error = ex.set_text(good.replace("F(l)[&(a1)", "F(l*zz)[&(a1)"))
    assert error is not None and ex.error is error  # the last good plant stays, the error is shown
    ex.undo()
    assert ex.error is None and ex.document_text() == good
