"""The history tree stores node ids in int32 (issue 14: 8 bytes less per node) and hands out int64."""

from __future__ import annotations

import numpy as np
import pytest

from ramure.errors import DerivationError
from ramure.lsys import LSystem
from ramure.lsys.history.tree import DerivationTree


def test_parent_child_start_and_the_string_are_int32_and_ids_handed_out_are_int64():
    d = LSystem.from_file("honda_sympodial").derive(8)
    t = d.tree
    assert t.parent.dtype == np.int32 and t.child_start.dtype == np.int32
    assert t.leaves.dtype == np.int32
    inner = int(np.flatnonzero(t.child_count > 0)[-1])
    assert t.children(inner).dtype == np.int64 and t.subtree(0).dtype == np.int64
    assert t.ancestor(t.leaves[:5], 2).dtype == np.int64
    # the ids still mean the same nodes: every child's parent is the node that made it
    kids = t.children(inner)
    assert (t.parent[kids] == inner).all() and (kids > inner).all()
    rewritten = np.flatnonzero(t.child_count > 0)
    assert (t.parent[t.child_start[rewritten]] == rewritten).all()


def test_a_tree_past_the_int32_ids_is_refused_and_left_as_it_was():
    t = DerivationTree(max_params=1)
    t.append([0], [0], [[0.0]], parent=[-1], step=0, rule=-1, index=[0])
    with pytest.raises(DerivationError, match="int32"):
        t.extend(2**31, step=1)  # refused before any memory is asked for
    assert len(t) == 1 and t.parent.tolist() == [-1]


def test_symbols_rules_slots_and_child_counts_are_int16_for_a_usual_grammar():
    t = LSystem.from_file("honda_sympodial").derive(8).tree
    assert {t.symbol.dtype, t.rule.dtype, t.index_in_rule.dtype, t.child_count.dtype} == {np.dtype(np.int16)}


@pytest.mark.parametrize("compiled", [False, True])
def test_a_successor_longer_than_int16_widens_the_tree_and_derives_the_same(compiled):
    long = 40_000  # child counts and slots past 32,767
    ls = LSystem.from_text(f"n: 2\nw: A\np:\n A -> {'F' * long}A\n")
    if compiled:
        ls.kernel_min_modules = ls.kernel_loaded_min_modules = 0
    t = ls.derive().tree
    assert t.child_count.dtype == np.int32 and t.index_in_rule.dtype == np.int32
    assert t.symbol.dtype == np.int16  # the fields that fit stay narrow
    assert t.child_count.max() == long + 1 and t.index_in_rule.max() == long
    last_a, first_a = int(t.leaves[-1]), int(t.parent[t.leaves[-1]])
    assert t.index_in_rule[last_a] == long and t.symbol[first_a] == t.symbol[last_a]
    assert t.children(first_a)[-1] == last_a and len(t.children(first_a)) == long + 1
    assert ls.derive().to_string() == "F" * long + "F" * long + "A"


def test_appending_values_past_int16_widens_and_past_int32_is_refused():
    t = DerivationTree(max_params=1)
    t.append([0, 70_000], [0, 0], [[0.0], [0.0]], parent=[-1, -1], step=0, rule=-1, index=[0, 1])
    assert t.symbol.dtype == np.int32 and t.symbol.tolist() == [0, 70_000]
    kids = t.append([1] * 3, [0] * 3, [[0.0]] * 3, parent=[0] * 3, step=1, rule=-40_000, index=[0, 1, 2])
    assert t.rule.dtype == np.int32 and t.rule[kids].tolist() == [-40_000] * 3
    t.set_children([0], [int(kids[0])], [3])
    assert t.child_count.dtype == np.int16 and t.children(0).tolist() == kids.tolist()
    t.set_children([1], [int(kids[0])], np.array([50_000], np.int64))
    assert t.child_count.dtype == np.int32 and t.child_count.tolist()[:2] == [3, 50_000]
    with pytest.raises(DerivationError, match="symbol"):
        t.widen("symbol", 0, 2**31)
    with pytest.raises(ValueError, match="parent"):
        t.widen("parent", 0, 1)


def test_the_string_stays_int32_through_edits_and_undo_swaps_back_the_very_array():
    from ramure.lsys.regeneration.regen import Session

    s = Session(LSystem.from_file("honda_sympodial"), n=9)
    t = s.derivation.tree
    before = t.leaves
    s.regrow(s.leaves_with_symbol("F")[[5, 50, 500]].tolist(), rho=0.5, seed=3)
    after = t.leaves
    assert after.dtype == np.int32 and after is not before
    s.prune(s.leaves_with_symbol("F")[-3:].tolist(), rho=0.5)
    assert t.leaves.dtype == np.int32
    s.undo()
    assert t.leaves is after
    s.undo()  # an older edit keeps only what it replaced (Change.compact): the string is spliced
    assert t.leaves.dtype == np.int32 and np.array_equal(t.leaves, before)
    t.leaves = np.array([0, 1], np.int64)  # given as int64: kept as int32
    assert t.leaves.dtype == np.int32 and t.leaves.tolist() == [0, 1]


def test_every_step_hands_the_compiled_assemble_an_int32_string(monkeypatch):
    """Decomposed strings and regrown roots come as int64 ids: a step takes them as the tree's
    int32 string, so the compiled pass has one signature to load (and the string one dtype)."""
    import ramure.lsys.engine._derive_kernel as kernel

    seen = []
    compiled = kernel.assemble
    monkeypatch.setattr(kernel, "assemble", lambda string, *rest: seen.append(string.dtype) or compiled(string, *rest))
    grammar = (
        "n: 5\nw: A\np:\n  A -> F[+A]B : 1\n  A -> F[-A]A : 1\n  C(x) -> C(x+1)\n"
        "decomposition:\n  B -> C(0)[-D]\n  D -> FE\n#decomposition_depth 2\n"
    )
    ls = LSystem.from_text(grammar)
    ls.kernel_min_modules = ls.kernel_loaded_min_modules = 0
    d = ls.derive()
    assert seen and set(seen) == {np.dtype(np.int32)} and d.tree.leaves.dtype == np.int32
