"""A selection changes only what the user is shown will change (issue 34, section 2): the cut
preview, the message after a regrow, a click that once replaced half the plant, and "Regrow with
constants" on a part made in the last step."""

import json

import numpy as np
import pytest

from ramure.app.model import Explorer, percent
from ramure.errors import ValueRefused
from ramure.lsys.regeneration.regen import Session

HONDA = "grammars/honda_sympodial.lsys"


def _tips(ex, count=3):
    tree = ex.derivation.tree
    f = ex.session.leaves_with_symbol("F")
    tips = f[tree.step[f] == ex.session.n]
    return tips[len(tips) // 2 : len(tips) // 2 + count].tolist()


def test_preview_is_the_cut_its_leaves_and_their_share():
    ex = Explorer(HONDA, n=6)
    assert ex.preview() is None  # nothing selected: a regrow is the whole plant
    ex.select(_tips(ex))
    p = ex.preview()
    tree = ex.derivation.tree
    under = np.concatenate([tree.leaves_under(int(r)) for r in p.roots])
    assert p.roots.tolist() == ex.plan().roots.tolist() and len(p.roots) == 3
    assert sorted(p.leaves.tolist()) == sorted(under.tolist()) and p.changed == 36 == len(under)
    assert p.total == 693 and p.climb == (1, 1) and not len(p.stranded) and not p.from_axiom
    assert p.message == "36 of 693 modules (5.2 %) will change, the cut climbs 1 level above the selected leaves"
    result = ex.regrow(seed=4)
    assert result.removed == p.changed and result.roots.tolist() == p.roots.tolist()  # what was shown changed


def test_preview_of_a_large_selection_is_array_code_and_exact():
    ex = Explorer(HONDA, n=11)
    leaves = ex.derivation.tree.leaves
    ex.select(leaves[: len(leaves) // 4])
    p = ex.preview()
    tree = ex.derivation.tree
    expected = np.concatenate([tree.leaves_under(int(r)) for r in p.roots])
    assert np.array_equal(np.sort(p.leaves), np.sort(expected)) and p.changed == len(expected)
    assert p.climb[1] >= 2 and f"({percent(p.changed / p.total)})" in p.message


def test_after_a_regrow_the_status_says_the_share_and_the_climb():
    ex = Explorer(HONDA, n=6)
    tree = ex.derivation.tree
    twig = np.flatnonzero((tree.depth == 2) & tree.alive & (tree.child_count > 0))[-1]
    ex.select(tree.leaves_under(int(twig)).tolist())
    shown = ex.preview()
    deepest = int(tree.depth_of(shown.leaves).max())  # the selected leaves are all the twig's
    result = ex.regrow(seed=3)
    assert shown.climb == (1, deepest - 2)
    status = ex.status()
    assert f"regrew {result.removed} of 693 modules ({percent(result.removed / 693)}) as {result.added}" in status
    assert f"the cut climbed 1-{deepest - 2} levels above the selected leaves" in status


def test_whole_plant_from_the_axiom_is_said():
    ex = Explorer(HONDA, n=4)
    ex.select(ex.derivation.tree.leaves.tolist())
    assert "the whole plant" in ex.preview().message and ex.preview().from_axiom
    ex.regrow(seed=1)
    assert "regrew" in ex.status() and "the whole plant" in ex.status()


def test_one_clicked_segment_never_regrows_the_branches_it_carries():
    """The notebook: one click on a segment of Honda n = 6 replaced 342 of its 693 modules. The
    click path is the notebook's (mesh cell -> leaf_of_cell -> select, as app/jupyter/view.py
    and selection.py do); every click now changes at most the modules made with the clicked one."""
    ex = Explorer(HONDA, n=6)
    tree = ex.derivation.tree
    cells = np.unique(ex.mesh.cell_data["leaf_id"], return_index=True)[1]
    changed = {}
    for cell in cells.tolist():
        leaf = ex.leaf_of_cell(cell)
        ex.select([leaf], "replace")
        changed[leaf] = ex.preview().changed
    assert max(changed.values()) == 12 and min(changed.values()) == 0  # a tip and its 11 siblings at most
    ex.select([13])  # F(0.9) made at step 2: it carries a main branch (342 modules)
    assert ex.lsystem.module_text(tree, 13) == "F(0.9)"
    assert ex.preview().message.startswith("nothing will change: the selected leaf carries branches grown after it")
    before = ex.derivation.to_string()
    with pytest.raises(ValueRefused, match="nothing regrows"):
        ex.regrow(seed=1)
    assert ex.derivation.to_string() == before and not ex.session.can_undo and ex.selection == [13]
    ex.select([13, _tips(ex, 1)[0]])  # with a tip: the tip regrows, the segment stays and is named
    p = ex.preview()
    assert p.changed == 12 and p.stranded.tolist() == [13] and "1 selected leaf stays: the selected leaf carries" in p.message


def test_a_session_saved_before_keeps_replaying_the_old_ascension(tmp_path):
    s = Session(HONDA, n=6)
    s.regrow([13], seed=2)
    assert s.edits[-1]["whole_branches"] is False and not len(s.last_result.roots)
    data = json.loads(json.dumps(s.to_dict()))
    del data["edits"][0]["whole_branches"]  # as written before issue 34
    old = Session.from_dict(data)
    assert old.last_result.roots.tolist() == [5] and old.last_result.removed == 342
    data["edits"][0]["whole_branches"] = "yes"
    with pytest.raises(Exception, match="whole_branches"):
        Session.from_dict(data)


def test_an_edit_that_regrew_nothing_keeps_no_whole_string():
    s = Session(HONDA, n=6)
    original = s.tree.leaves.copy()
    s.regrow([13], seed=2)  # every selected leaf stayed: an empty edit (the explorer refuses it)
    s.regrow(_tips(Explorer(HONDA, n=6)), seed=3)
    after = s.tree.leaves.copy()
    empty = s._undo[0][1][1]
    assert empty.old_leaves is None and empty.new_leaves is None and empty.spans() is None
    s.undo()
    s.undo()
    assert np.array_equal(s.tree.leaves, original)
    s.redo()
    s.redo()
    assert np.array_equal(s.tree.leaves, after)


def test_regrow_with_constants_on_a_part_made_in_the_last_step_says_so():
    ex = Explorer(HONDA, n=6)
    ex.select(_tips(ex))
    ex.regrow(constants={"a2": 30})
    status = ex.status()
    assert "this part was made in the last derivation step" in status
    assert "nothing is left to regrow with new constants" in status and "a2" in status
    assert "Regrow with constants" not in status and "press" not in status  # not what the user just did
    ex.undo()
    tree = ex.derivation.tree
    twig = np.flatnonzero((tree.depth == 3) & tree.alive & (tree.child_count > 0))[-1]
    ex.select(tree.leaves_under(int(twig)).tolist())  # three steps left: a2 reaches drawn branches
    ex.regrow(constants={"a2": 30})
    assert "last derivation step" not in ex.status() and ex.note is None


def test_regrow_with_constants_read_by_no_regrowing_rule_says_which():
    text = "#define k 30\n#define g 2\nn: 4\nw: A\np:\n  A -> F[+(k)B]A\n  B -> F(g)C\n  C -> F(1)D\n  D -> F\n"
    ex = Explorer(text)
    tree = ex.derivation.tree
    c = np.flatnonzero((ex.derivation.tree.symbol == ex.lsystem.symbols.index("C")) & tree.alive)
    node = int(c[np.argmax(ex.derivation.tree.child_count[c] > 0)])
    ex.select(tree.leaves_under(node).tolist())
    ex.regrow(constants={"k": 40})
    assert ex.note.startswith("the 3 steps that regrew this part apply the rules for B (line 7), C (line 8), D (line 9)")
    assert "which read none of k: nothing is left to regrow with these constants" in ex.note
