"""Regeneration, prune, undo/redo and sessions (issue 8)."""

import json

import numpy as np
import pytest

from ramure.lsys import LSystem, RamureError
from ramure.lsys.regeneration.regen import Session

HONDA = "grammars/honda_sympodial.lsys"


def snapshot(tree):
    return {int(v): (int(tree.symbol[v]), tuple(np.nan_to_num(tree.params[v]).tolist())) for v in tree.leaves.tolist()}


def test_regrow_changes_only_the_roots_subtrees():
    s = Session(HONDA, n=7)
    t = s.tree
    before_leaves = t.leaves.copy()
    before = snapshot(t)
    sel = s.leaves_with_symbol("F")[100:106]
    result = s.regrow(sel, constants={"a2": 25, "r2": 0.5})
    assert result.roots.size >= 1
    under = set(result.change.removed.tolist())
    outside = [v for v in before_leaves.tolist() if v not in under]
    after = snapshot(t)
    for v in outside:  # same node id, same module, same parameters
        assert after[v] == before[v]
    # and in the same order in the new string
    pos = {v: i for i, v in enumerate(t.leaves.tolist())}
    assert all(pos[a] < pos[b] for a, b in zip(outside, outside[1:]))
    assert s.derivation.to_string() != LSystem.from_file(HONDA).derive(n=7).to_string()


def test_regrow_with_new_seed_on_stochastic_grammar():
    s = Session("grammars/stochastic_plant.lsys", n=4, seed=1)
    before = s.derivation.to_string()
    sel = s.leaves_with_symbol("F")[:40]
    changed = False
    for seed in range(5):
        s.regrow(sel[:40], seed=seed + 10)
        changed |= s.derivation.to_string() != before
        s.undo()
    assert changed
    assert s.derivation.to_string() == before


def test_undo_redo_exact():
    s = Session(HONDA, n=7)
    strings = [s.derivation.to_string()]
    s.regrow(s.leaves_with_symbol("F")[10:13], constants={"a1": 40})
    strings.append(s.derivation.to_string())
    s.prune(s.leaves_with_symbol("F")[-5:])
    strings.append(s.derivation.to_string())
    s.set_constants({"r1": 0.8})
    strings.append(s.derivation.to_string())
    assert len(set(strings)) == 4
    for expected in reversed(strings[:-1]):
        s.undo()
        assert s.derivation.to_string() == expected
    assert s.undo() is None
    for expected in strings[1:]:
        s.redo()
        assert s.derivation.to_string() == expected


def test_prune_removes_and_roots_become_leaves():
    s = Session(HONDA, n=7)
    n_before = len(s.derivation.skeleton())
    result = s.prune(s.leaves_with_symbol("F")[-20:])
    assert len(s.derivation.skeleton()) < n_before
    assert np.isin(result.roots, s.tree.leaves).all()


def test_params_combination_for_one_rule():
    s = Session(HONDA, n=6)
    before = s.derivation.skeleton().length.sum()
    s.regrow([], params={"rule": 1, "constants": {"r1": 1.2, "r2": 1.1}})  # whole plant, rule B only
    assert s.derivation.skeleton().length.sum() > before


def test_save_load_same_string(tmp_path):
    s = Session("grammars/stochastic_plant.lsys", n=4, seed=3)
    s.regrow(s.leaves_with_symbol("F")[5:9])
    s.regrow(s.leaves_with_symbol("F")[30:60], rho=0.3)
    s.prune(s.leaves_with_symbol("F")[:3])
    path = s.save(tmp_path / "s.json")
    loaded = Session.load(path)
    assert loaded.derivation.to_string() == s.derivation.to_string()
    assert np.array_equal(loaded.tree.leaves, s.tree.leaves)


@pytest.mark.parametrize("content", ["", "{", '{"format": "other"}', '{"format": "ramure-session", "version": 1}'])
def test_corrupt_session_refused(tmp_path, content):
    good = Session(HONDA, n=5)
    before = good.derivation.to_string()
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(RamureError):
        Session.load(path)
    assert good.derivation.to_string() == before


def test_truncated_session_refused(tmp_path):
    s = Session(HONDA, n=5)
    s.regrow(s.leaves_with_symbol("F")[:3])
    text = json.dumps(s.to_dict())
    path = tmp_path / "t.json"
    path.write_text(text[: len(text) // 2])
    with pytest.raises(RamureError, match="truncated"):
        Session.load(path)


def test_bad_edit_values_refused():
    s = Session(HONDA, n=5)
    with pytest.raises(RamureError):
        s.regrow(s.leaves_with_symbol("F")[:2], rho=0)
    with pytest.raises(RamureError):
        s.regrow([10**9])
    with pytest.raises(RamureError):
        s.set_constants({"zz": 1})
    assert not s.edits  # nothing was recorded


def test_whole_plant_regrow_equals_a_fresh_derivation_even_with_context():
    for path, n in (("grammars/context_plant.lsys", 20), (HONDA, 6)):
        s = Session(path, n=n)
        s.regrow([], seed=0, constants={"a": 30} if "context" in path else {"a2": 30})
        ls = LSystem.from_file(path)
        fresh = ls.derive(n=n, constants={"a": 30} if "context" in path else {"a2": 30})
        assert s.derivation.to_string() == fresh.to_string()


def test_older_edits_keep_only_what_they_replaced_and_undo_redo_stay_exact():
    from ramure.lsys.regeneration.regen import KEEP_STRINGS
    from ramure.lsys.interpretation.turtle import changed_spans

    s = Session(HONDA, n=9)
    rng = np.random.default_rng(5)
    strings = [s.tree.leaves.copy()]
    for k in range(6):
        leaves = s.leaves_with_symbol("F")
        leaves = leaves[s.tree.step[leaves] == s.n]  # tips: each edit regrows something
        if k == 3:
            s.prune(leaves[-3:])
        else:
            s.regrow([int(v) for v in rng.choice(leaves, 3, replace=False)], seed=k)
        strings.append(s.tree.leaves.copy())
    changes = [how[1] for _, how in s._undo]
    whole = [c for c in changes if c.old_leaves is not None]
    assert len(whole) == KEEP_STRINGS and whole[0] is changes[-1]  # the last edit keeps both strings
    for c in changes[:-KEEP_STRINGS]:  # what the edit touched, nothing more
        assert c.new_leaves is None and c.old_pieces is not None and c.new_pieces is not None
        assert sum(map(len, c.old_pieces)) == c.removed_leaves and sum(map(len, c.new_pieces)) == c.added_leaves
    for expected in reversed(strings[:-1]):
        before = s.tree.leaves
        s.undo()
        np.testing.assert_array_equal(s.tree.leaves, expected)
        spans = s.edit_spans(before, s.tree.leaves)  # known without comparing the strings
        assert spans is not None
        found = changed_spans(before, s.tree.leaves, s.tree.size)
        np.testing.assert_array_equal(spans[0], found[0])
        np.testing.assert_array_equal(spans[1], found[1])
    for expected in strings[1:]:
        before = s.tree.leaves
        s.redo()
        np.testing.assert_array_equal(s.tree.leaves, expected)
        assert s.edit_spans(before, s.tree.leaves) is not None
