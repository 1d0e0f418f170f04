"""One id parser and one set of messages for the desktop and the notebook (ramure.app.ids);
the id field's example is made from the plant on screen, so typing it selects."""

from __future__ import annotations

import pytest

from ramure.app.ids import format_ids, id_example, parse_ids, resolve_ids
from ramure.app.jupyter import NotebookExplorer
from ramure.app.model import Explorer as Model
from ramure.errors import ValueRefused


@pytest.mark.parametrize("grammar, n", [("honda_sympodial", 6), ("fruit_tree", None), ("algae", 5), ("plant_1_24a", 3)])
def test_the_placeholder_example_selects_on_the_loaded_plant(grammar, n):
    ex = NotebookExplorer(grammar, n=n, view="static", size=(80, 80))
    panel = ex.selection_panel
    example = panel.ids.placeholder.split("e.g. ", 1)[1]
    panel.ids.value = example
    panel.select_ids()
    assert ex.message.kind == "info", ex.message.text
    single, ranged = example.split(", ")
    first, last = map(int, ranged.split("-"))
    assert int(single) in ex.selection and first in ex.selection and last in ex.selection
    assert all(first <= leaf <= last for leaf in ex.selection if leaf != int(single))


def test_the_example_follows_the_plant():
    ex = NotebookExplorer("honda_sympodial", n=4, view="static", size=(80, 80))
    before = ex.selection_panel.ids.placeholder
    ex.set_derivation(n=6)
    after = ex.selection_panel.ids.placeholder
    assert before != after
    leaves = set(ex.model.derivation.tree.leaves.tolist())
    assert int(after.split("e.g. ")[1].split(",")[0]) in leaves


def test_ranges_mean_the_leaves_inside_them():
    leaves = [2, 5, 13, 17, 40]
    assert resolve_ids("2, 10-20", leaves) == [2, 13, 17]
    assert resolve_ids("13 5;2", leaves) == [2, 5, 13]
    with pytest.raises(ValueRefused, match="^12 is not a leaf of the current plant$"):
        resolve_ids("12, 10-20", leaves)
    with pytest.raises(ValueRefused, match="the range 18-30 holds no leaf"):
        resolve_ids("18-30", leaves)
    with pytest.raises(ValueRefused, match="goes backwards: write 7-9"):
        resolve_ids("9-7", leaves)
    with pytest.raises(ValueRefused, match="more than 100,000 ids"):
        parse_ids("0-99999999999")
    assert format_ids([9, 3, 4, 5]) == "3-5, 9" and parse_ids(format_ids([9, 3, 4, 5])) == [3, 4, 5, 9]
    assert id_example([]) == "" and id_example([4]) == "4" and id_example([4, 6, 9]) == "4-9"


def test_the_model_refuses_with_the_shared_message():
    import ramure.grammars

    model = Model(ramure.grammars.path("honda_sympodial"), n=3)
    with pytest.raises(ValueRefused) as refused:
        model.select([10**9])
    from ramure.app.ids import not_a_leaf

    assert str(refused.value) == not_a_leaf(10**9)
