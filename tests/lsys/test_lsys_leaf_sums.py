"""The tree's leaf sums (the min-cut's capacities, leaf counts, string spans) kept across edits
equal a computation from scratch after any sequence of regrows, prunes, undos and redos."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ramure.errors import RamureError
from ramure.lsys import LSystem
from ramure.lsys.regeneration.regen import Session
from ramure.lsys.history.tree import DerivationTree

GRAMMARS = {
    "honda": ("honda_sympodial", 8),
    "empty successors": ("n: 6\nw: A\np:\n A -> F[+A]BA : 1\n A -> F[-A]B : 1\n B -> F[-F] : 1\n B -> : 1\n", 6),
    "cut %": ("n: 5\nw: A\np:\n A -> F[+A][-B]A\n B -> F%FF[+F]\n", 5),
    "decomposition": (
        "n: 5\nw: A\np:\n  A -> F[+A]B : 1\n  A -> F[-A]A : 1\n  C(x) -> C(x+1)\n"
        "decomposition:\n  B -> C(0)[-D]\n  D -> FE\n#decomposition_depth 2\n",
        5,
    ),
    "two axiom modules": ("n: 5\nw: A[+B]A\np:\n A -> F[+A]A : 1\n A -> F : 1\n B -> F[-B]B\n", 5),
}


def reference(tree):
    """Counts and weights of every node from the whole-tree leaf spans (dead nodes 0)."""
    first, last = tree.leaf_spans()
    depth = tree.depth.astype(np.int64)
    prefix = np.zeros(len(tree.leaves) + 1, object)
    prefix[1:] = np.cumsum(np.array([1 << int(d) for d in depth[tree.leaves]], object))
    counts = np.where(last >= 0, last - first + 1, 0)
    weights = [0 if b < 0 else (prefix[b + 1] - prefix[a]) >> int(d) for a, b, d in zip(first, last, depth)]
    return counts, weights


def check(tree, rng):
    nodes = np.arange(tree.size)
    sample = np.unique(np.r_[rng.choice(tree.size, min(tree.size, 60), replace=False), tree.leaves[:5]])
    spans = tree.string_spans(sample)  # before leaf_spans fills the cache they would read
    depth = tree.depth_of(sample)
    counts, weights = tree.subtree_weights(nodes)
    positions = tree.leaf_positions(sample)  # a few nodes: from the sums, no whole-tree table
    in_string = tree.in_string(nodes)
    ref_counts, ref_weights = reference(tree)
    np.testing.assert_array_equal(counts, ref_counts)
    assert weights is not None and weights.tolist() == ref_weights
    first, last = tree.leaf_spans()
    np.testing.assert_array_equal(spans[0], first[sample])
    np.testing.assert_array_equal(spans[1], last[sample])
    np.testing.assert_array_equal(depth, tree.depth[sample])
    mask = np.zeros(tree.size, bool)
    mask[tree.leaves] = True
    np.testing.assert_array_equal(in_string, mask)
    where = np.full(tree.size, -1)
    where[tree.leaves] = np.arange(len(tree.leaves))
    np.testing.assert_array_equal(positions, where[sample])
    np.testing.assert_array_equal(tree.leaf_positions(nodes), where)  # many nodes: the table
    np.testing.assert_array_equal(tree.axiom_modules(), np.flatnonzero((tree.parent == -1) & tree.alive))


def edit(session, rng, op):
    tree = session.tree
    leaves = tree.leaves
    if op in ("undo", "redo"):
        getattr(session, op)()
        return
    k = int(rng.integers(1, 6))
    selection = rng.choice(leaves, min(k, len(leaves)), replace=False).tolist() if len(leaves) else []
    rho = float(rng.choice([0.25, 0.5, 0.9]))
    try:
        if op == "prune" and selection:
            session.prune(selection, rho=rho)
        elif op == "whole":
            session.regrow([], seed=int(rng.integers(1000)))
        elif op == "leaf":  # a leaf as its own root
            session.regrow(selection[:1], seed=int(rng.integers(1000)), ascend_levels=0)
        else:
            session.regrow(selection, rho=rho, seed=int(rng.integers(1000)))
    except RamureError:
        pass  # e.g. a prune that would leave nothing: refused, nothing changed


OPS = st.lists(st.sampled_from(["regrow", "regrow", "prune", "undo", "undo", "redo", "whole", "leaf"]), min_size=1, max_size=12)


@pytest.mark.parametrize("name", list(GRAMMARS))
@pytest.mark.parametrize("compiled", [True, False])
@settings(max_examples=8, deadline=None)
@given(ops=OPS, seed=st.integers(0, 2**16))
def test_kept_sums_equal_a_fresh_computation(name, compiled, ops, seed):
    source, n = GRAMMARS[name]
    ls = LSystem.from_file(source) if "\n" not in source else LSystem.from_text(source)
    session = Session(ls, n=n, seed=seed % 7)
    rng = np.random.default_rng(seed)
    session.tree.use_kernels = compiled
    check(session.tree, rng)
    for op in ops:
        edit(session, rng, op)
        session.tree.use_kernels = compiled
        check(session.tree, rng)


def test_a_regrow_its_undo_and_redo_keep_the_sums_they_update():
    session = Session(LSystem.from_file("honda_sympodial"), n=9)
    tree = session.tree
    tree.subtree_weights([0])  # made once, from the whole tree
    kept = tree.detach_sums()
    assert kept is not None
    tree.attach_sums(kept, [])
    rng = np.random.default_rng(3)
    for op in ("regrow", "undo", "redo", "regrow", "prune", "undo", "undo"):
        edit(session, rng, op)
        held = tree.detach_sums()
        assert held is kept  # updated in place under the roots, not made again
        tree.attach_sums(held, [])
    check(tree, rng)


def test_the_sums_take_the_trees_headroom_so_a_regrow_copies_nothing():
    # the flags are made as long as the tree's arrays, the inner entries twice as many as the
    # inner nodes (zeroed pages cost nothing until used): a first regrow on Honda n = 17
    # otherwise copied them into 2x arrays
    session = Session(LSystem.from_file("honda_sympodial"), n=9)
    tree = session.tree
    tree.subtree_weights([0])
    kept = tree.detach_sums()
    assert kept is not None
    tree.attach_sums(kept, [])
    arrays = (kept.flag, kept.inner, kept.count, kept.weight)
    assert len(kept.flag) == len(tree._parent) > tree.size  # the tree's capacity
    inner = int((tree.child_count > 0).sum())
    assert kept.n_inner == inner and len(kept.inner) == len(kept.count) == len(kept.weight) == max(2 * inner, 1024)
    rng = np.random.default_rng(5)
    for op in ("regrow", "regrow", "undo", "redo"):
        edit(session, rng, op)
        tree.attach_sums(tree.detach_sums(), [])
    if tree.size <= len(arrays[0]):
        assert kept.flag is arrays[0]
    assert all(a is b for a, b in zip((kept.inner, kept.count, kept.weight), arrays[1:]))
    check(tree, rng)


def test_the_sums_keep_entries_for_inner_nodes_only():
    # Honda n = 17 holds 1.57 M nodes, one in twelve with children: 3 MB of sums instead of 19
    session = Session(LSystem.from_file("honda_sympodial"), n=12)
    tree = session.tree
    tree.subtree_weights([0])
    sums = tree.detach_sums()
    tree.attach_sums(sums, [])
    np.testing.assert_array_equal(sums.inner[: sums.n_inner], np.flatnonzero(tree.child_count > 0))
    assert sums.n_inner < tree.size / 5
    rng = np.random.default_rng(4)
    for op in ("regrow", "prune", "undo", "regrow"):
        edit(session, rng, op)
        held = sums.inner[: sums.n_inner]
        assert tree._sums is sums and (np.diff(held) > 0).all()
        assert np.isin(np.flatnonzero(tree.child_count > 0), held).all()  # every inner node has its entry
    check(tree, rng)


@pytest.mark.parametrize("compiled", [True, False])
def test_sums_that_miss_an_inner_node_are_dropped_not_read_wrong(compiled):
    # an inner node without its entry (a tree edited behind the sums' back) would read another
    # node's sums: attach_sums drops them instead, and they are made again when asked
    session = Session(LSystem.from_file("honda_sympodial"), n=9)
    tree = session.tree
    tree.use_kernels = compiled
    tree.subtree_weights([0])
    sums = tree.detach_sums()
    inner = sums.inner[: sums.n_inner]
    victim = int(inner[len(inner) // 2])
    keep = inner != victim
    n = int(keep.sum())
    sums.inner[:n], sums.count[:n], sums.weight[:n] = (
        inner[keep],
        sums.count[: sums.n_inner][keep],
        sums.weight[: sums.n_inner][keep],
    )
    sums.n_inner = n
    tree.attach_sums(sums, [int(tree.parent[victim])])
    assert tree.detach_sums() is None
    check(tree, np.random.default_rng(3))


def test_an_entry_for_a_node_that_gains_children_is_inserted_in_order():
    from ramure.lsys.history.tree import _LeafSums

    sums = _LeafSums(100, np.array([3, 8, 20], np.int32))
    sums.count[:3], sums.weight[:3] = [1, 2, 3], [10, 20, 30]
    inner = sums.inner
    sums.add_inner(np.array([8, 30, 31], np.int32))  # 8 held already, the others appended: no copy
    assert sums.inner is inner and sums.n_inner == 5
    sums.add_inner(np.array([0, 10], np.int32))  # inserted before held ids
    assert sums.n_inner == 7
    assert sums.inner[:7].tolist() == [0, 3, 8, 10, 20, 30, 31]
    assert sums.count[:7].tolist() == [0, 1, 2, 0, 3, 0, 0] and sums.weight[:7].tolist() == [0, 10, 20, 0, 30, 0, 0]
    sums.add_inner(np.arange(40, 40 + 1100, dtype=np.int32))  # past the capacity: grown, kept in order
    assert sums.n_inner == 1107 and len(sums.inner) >= 1107 and sums.count[1] == 1 and sums.inner[1106] == 1139
    child_count = np.zeros(2000, np.int32)
    child_count[[3, 8]] = 1
    sums.flag[[5, 3]] = 1
    count, weight = sums.of(np.array([5, 3, 8, 6]), child_count)
    assert count.tolist() == [1, 1, 2, 0] and weight.tolist() == [1, 10, 20, 0]  # childless: the flag


def test_other_edits_drop_the_sums_and_reviving_unknown_nodes_does_too():
    session = Session(LSystem.from_file("honda_sympodial"), n=7)
    tree = session.tree
    f = session.leaves_with_symbol("F")
    session.regrow(f[tree.step[f] == session.n][-3:].tolist(), seed=1)  # three tips: they regrow
    tree.changed()  # an edit the sums do not follow: dropped
    assert tree.detach_sums() is None
    tree.subtree_weights([0])  # made again now: the nodes the regrow removed are dead, their sums unknown
    session.undo()  # revives them: the sums are dropped and made again when asked
    assert tree.detach_sums() is None
    check(tree, np.random.default_rng(0))
    tree.subtree_weights([0])
    tree.set_children([0], tree.child_start[[0]], tree.child_count[[0]])  # any other edit
    assert tree.detach_sums() is None


def test_weights_are_none_where_int64_could_overflow():
    tree = DerivationTree(max_params=1)
    tree.append([0], [0], [[0.0]], parent=[-1], step=0, rule=-1, index=[0])
    kids = tree.append([0, 0], [0, 0], [[0.0], [0.0]], parent=[0, 0], step=61, rule=0, index=[0, 1])
    tree.set_children([0], kids[:1], 2)
    tree.leaves = kids
    counts, weights = tree.subtree_weights([0, 1])
    assert counts.tolist() == [2, 1] and weights is None


@pytest.mark.parametrize("name", list(GRAMMARS))
@settings(max_examples=10, deadline=None)
@given(ops=OPS, seed=st.integers(0, 2**16))
def test_an_edits_own_spans_are_what_comparing_the_strings_finds(name, ops, seed):
    from ramure.lsys.interpretation.turtle import changed_spans

    source, n = GRAMMARS[name]
    ls = LSystem.from_file(source) if "\n" not in source else LSystem.from_text(source)
    session = Session(ls, n=n, seed=seed % 5)
    rng = np.random.default_rng(seed)
    for op in ops:
        before = session.tree.leaves
        edit(session, rng, op)
        after = session.tree.leaves
        spans = session.edit_spans(before, after)
        if after is before:
            continue  # refused, or nothing to undo
        found = changed_spans(before, after, session.tree.size)
        if spans is not None:
            assert found is not None
            np.testing.assert_array_equal(spans[0], found[0])
            np.testing.assert_array_equal(spans[1], found[1])
        assert session.edit_spans(after, before) is None


def test_the_spans_of_a_regrow_its_undo_and_redo():
    session = Session(LSystem.from_file("honda_sympodial"), n=9)
    first = session.tree.leaves
    leaves = session.leaves_with_symbol("F")
    leaves = leaves[session.tree.step[leaves] == session.n]  # tips: each regrows with its siblings
    session.regrow([int(leaves[5]), int(leaves[-7])], seed=3)
    second = session.tree.leaves
    forward = session.edit_spans(first, second)
    assert forward is not None and len(forward[0]) == 2
    assert session.edit_spans(second, first) is None  # not what the last edit did
    session.undo()
    back = session.edit_spans(second, session.tree.leaves)
    np.testing.assert_array_equal(back[0], forward[1])
    np.testing.assert_array_equal(back[1], forward[0])
    session.redo()
    again = session.edit_spans(first, session.tree.leaves)
    np.testing.assert_array_equal(again[0], forward[0])
