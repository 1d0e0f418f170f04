"""Session.set_steps: a qualifier's n +- 1 is one undoable edit that a saved session replays (issue 35)."""

import pathlib

import numpy as np
import pytest

from ramure.errors import RamureError, ValueRefused
from ramure.lsys.regeneration.regen import Session

SHRUB = pathlib.Path(__file__).parents[1] / "data" / "grammars" / "shrub.lsys"


def _f(session):
    return len(session.leaves_with_symbol("F"))


def test_steps_edit_undo_redo_and_replay():
    s = Session(SHRUB)
    assert s.n == 6 and _f(s) == 600  # 5 stems: each adds 2^k - 1 laterals per step ...
    s.set_steps(7, {"rule": 0, "constants": {"ls": 0.5}})
    grown = _f(s)
    assert s.n == 7 and grown > 600 and s.edits[-1] == {"op": "steps", "n": 7, "params": {"rule": 0, "constants": {"ls": 0.5}}}
    tips = s.leaves_with_symbol("F")[:3].tolist()
    s.regrow(tips, seed=3)
    again = Session.from_dict(s.to_dict())  # replays from the first n, then the steps edit
    assert again.n == 7 and again.to_dict()["n"] == 6 and again.tree.leaves.tolist() == s.tree.leaves.tolist()
    s.undo()
    s.undo()
    assert s.n == 6 and _f(s) == 600
    s.redo()
    assert s.n == 7 and _f(s) == grown


@pytest.mark.parametrize("n", [-1, 31, 2.5, True])
def test_steps_out_of_range_are_refused(n):
    s = Session(SHRUB)
    with pytest.raises(ValueRefused, match="derivation count"):
        s.set_steps(n)
    assert s.n == 6 and not s.edits


def test_a_saved_steps_edit_is_checked():
    data = Session(SHRUB).to_dict()
    data["edits"] = [{"op": "steps", "n": 99}]
    with pytest.raises(RamureError, match="'n' must be a whole number from 0 to 30"):
        Session.from_dict(data)


def test_a_selection_regrows_one_step_more_or_less_inside_only(tmp_path):
    """Issue 35 section 3: a selection's part regrown with one derivation step more (less) than
    the plant; every leaf outside it stays, the plant's n stays, and a saved session replays it."""
    s = Session("honda_sympodial", n=5)
    tree = s.tree
    f = set(s.leaves_with_symbol("F").tolist())
    branch = np.flatnonzero(tree.alive & (tree.depth == 2) & (tree.child_count > 0))
    leaves = [x for x in tree.leaves_under(int(branch[0])).tolist() if x in f]
    roots = s.plan(leaves)[1]
    first, last = tree.string_spans(roots)
    outside = np.concatenate([tree.leaves[: first.min()], tree.leaves[last.max() + 1 :]])
    inside = int(sum(len(tree.leaves_under(int(r))) for r in roots))
    more = s.regrow(leaves, seed=4, steps=1)
    grown = int(sum(len(tree.leaves_under(int(r))) for r in more.roots))
    assert more.roots.tolist() == roots.tolist() and s.n == 5 and grown > inside
    assert np.isin(outside, tree.leaves).all() and int(tree.step[tree.leaves].max()) == 6
    again = Session.load(s.save(tmp_path / "s.json"))
    assert again.derivation.to_string() == s.derivation.to_string()
    s.undo()
    less = s.regrow(leaves, seed=4, steps=-1)
    assert int(sum(len(tree.leaves_under(int(r))) for r in less.roots)) < inside
    assert np.isin(outside, tree.leaves).all()
    with pytest.raises(ValueRefused, match="-1, 0 or 1"):
        s.regrow(leaves, steps=2)
    tips = [x for x in tree.leaves[tree.step[tree.leaves] == 5].tolist() if x in f][:3]
    edits = len(s.edits)
    with pytest.raises(ValueRefused, match="one step less"):
        s.regrow(tips, steps=-1)
    assert len(s.edits) == edits


@pytest.mark.parametrize("steps", [0, 1])
def test_a_regrow_reports_the_roots_the_plan_showed(steps):
    """Two roots whose string order is not their id order (161 is drawn before 53): a regrow (one
    step more included) or a prune reports the plan's roots in the plan's order, so a qualifier's
    result names the part its preview showed (it reported the string order, order-dependently)."""
    s = Session("plant_1_24d", n=4)
    selection = [505, 517]
    shown = s.plan(selection, 0.5)[1]
    first = s.tree.string_spans(shown)[0]
    assert shown.tolist() == [53, 161] and first[0] > first[1]
    result = s.regrow(selection, seed=2, steps=steps)
    assert result.roots.tolist() == shown.tolist() and result.change.roots.tolist() == [161, 53]
    s.undo()
    assert s.prune(selection).roots.tolist() == [53, 161]
