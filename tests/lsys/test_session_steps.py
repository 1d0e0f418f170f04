"""Session.set_steps: a qualifier's n +- 1 is one undoable edit that a saved session replays (issue 35)."""

import pathlib

import pytest

from ramure.errors import RamureError, ValueRefused
from ramure.lsys.regen import Session

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
