"""The "Regrow fruit" control: enabled on fruit, new volumetric fruit for the selected ones only."""

from __future__ import annotations

import numpy as np
import pytest

from ramure.app.jupyter import NotebookExplorer
from jupyter_helpers import HONDA, ROOT

pytest.importorskip("gmap")
FRUIT_TREE = str(ROOT / "grammars" / "fruit_tree.lsys")


@pytest.fixture(scope="module")
def tree():
    return NotebookExplorer(FRUIT_TREE, view="static", size=(120, 120), cache=False)


def fruit_bounds(ex, leaf):

    surface = ex.model.fruit_surface()
    return np.asarray(surface.extract_cells(surface.cell_data["leaf_id"] == leaf).bounds)


def test_regrow_fruit_button_turns_one_fruit_into_a_pear(tree):
    ex = tree
    assert ex.edits.regrow_fruit.disabled  # nothing selected
    fruit = ex.model.fruit_ids()
    ex.select(ex.model.leaves_where(min_order=1)[:3])
    assert ex.edits.regrow_fruit.disabled  # branches only
    ex.select([fruit[3]])
    assert not ex.edits.regrow_fruit.disabled
    target, other = fruit_bounds(ex, fruit[3]), fruit_bounds(ex, fruit[0])
    ex.edits.fruit_preset.value = "pear"
    ex.edits.regrow_fruit.click()
    assert ex.history[-1]["op"] == "fruit" and ex.history[-1]["leaves"] == [fruit[3]]
    assert ex.history[-1]["settings"]["preset"] == "pear"
    assert ex.message.kind == "info" and ex.message.text.startswith("regrew 1 fruit as pear (seed ")
    assert not np.allclose(fruit_bounds(ex, fruit[3]), target)  # that fruit's volume changed
    assert np.allclose(fruit_bounds(ex, fruit[0]), other)  # the others did not
    assert ex.edits.regrow_fruit.disabled  # the edit cleared the selection
    assert ex.fruit_png(size=(120, 120), focus=fruit[3])[:4] == b"\x89PNG"
    assert ex.fruit_cut_png(fruit[3], size=(120, 120))[:4] == b"\x89PNG"
    assert ex.fruit_cut_png(10**9) is None  # not a fruit
    ex.undo()
    assert np.allclose(fruit_bounds(ex, fruit[3]), target)


@pytest.mark.parametrize(
    "settings, expected",
    [
        ({"size": "big"}, "'big' is not a number"),
        ({"size": -1}, "positive"),
        ({"preset": "kiwi"}, "unknown fruit preset 'kiwi'"),
    ],
)
def test_bad_fruit_settings_are_refused(tree, settings, expected):
    ex = tree
    ex.select([ex.model.fruit_ids()[0]])
    edits = list(ex.history)
    ex.regrow_fruit(**settings)
    assert ex.message.kind == "error" and expected in ex.error
    assert ex.history == edits and ex.selection == [ex.model.fruit_ids()[0]]


def test_a_plant_without_fruit_has_no_fruit_picture():
    ex = NotebookExplorer(HONDA, n=3, view="static", size=(80, 80))
    assert ex.fruit_png() is None and ex.edits.regrow_fruit.disabled
