"""The notebook's Undo and Redo buttons say what they did (the model's words) and the sliders
follow them (issue 34, section 4)."""

from __future__ import annotations


def test_undo_and_redo_buttons_say_what_they_did(explorer):
    ex = explorer
    ex.select_where(min_order=3)
    selected = len(ex.model.selection)
    assert selected > 1
    ex.edits.prune.click()
    ex.edits.undo.click()
    assert ex.message.text == f"Undid: prune of {selected} leaves"
    ex.edits.redo.click()
    assert ex.message.text == f"Redid: prune of {selected} leaves"
    ex.set_constant("a2", 45.0)
    ex.edits.undo.click()
    assert ex.message.text == "Undid: a2 = 45" and ex.grammar.sliders["a2"].value == 60.0
    ex.edits.redo.click()
    assert ex.message.text == "Redid: a2 = 45" and ex.grammar.sliders["a2"].value == 45.0
