"""The compiled whole-tree passes (depth, leaf spans) equal the numpy passes by step,
on fresh derivations and on trees edited by regrow, prune, undo and redo (dead nodes)."""

import numpy as np
import pytest

from ramure.lsys import LSystem
from ramure.lsys.regeneration.regen import Session


def _both(tree):
    out = []
    for compiled in (False, True):
        tree.use_kernels = compiled
        tree.changed()
        first, last = tree.leaf_spans()
        out.append((tree.depth.copy(), first.copy(), last.copy(), tree.leaf_counts().copy()))
    tree.use_kernels = None
    return out


def assert_same(tree):
    (d0, f0, l0, c0), (d1, f1, l1, c1) = _both(tree)
    np.testing.assert_array_equal(d0, d1)
    np.testing.assert_array_equal(f0, f1)
    np.testing.assert_array_equal(l0, l1)
    np.testing.assert_array_equal(c0, c1)
    return d0, f0, l0


@pytest.mark.parametrize("name, n", [("honda_sympodial", 9), ("context_plant", 20), ("fruit_tree", 5)])
def test_compiled_tree_passes_equal_the_numpy_passes_through_edits(name, n):
    session = Session(LSystem.from_file(name), n=n)
    rng = np.random.default_rng(2)
    depth, first, last = assert_same(session.tree)
    assert depth.max() > 3 and (last >= 0).sum() > 10
    leaves = session.tree.leaves
    assert (first[leaves] == np.arange(len(leaves))).all()
    for step in range(6):
        tree = session.tree
        pick = rng.choice(tree.leaves, size=3, replace=False)
        if step % 3 == 0:
            session.regrow(pick, rho=0.5, seed=step)
        elif step % 3 == 1:
            session.prune(pick, rho=0.5)
        else:
            session.undo()
        _, _, last = assert_same(session.tree)
        dead = ~session.tree.alive
        assert step == 0 or dead.any()
        assert (last[dead] == -1).all()
    session.redo()
    assert_same(session.tree)


def test_cut_leaf_weights_and_counts_from_the_compiled_passes():
    from ramure.lsys.regeneration.mincut import _leaf_weight_prefix, _LeafCounts

    session = Session(LSystem.from_file("honda_sympodial"), n=13)
    session.regrow(session.tree.leaves[[5, 500, 5000]], rho=0.5, seed=3)
    tree = session.tree
    assert tree.size >= 50_000  # the compiled prefix
    depth = tree.depth[tree.leaves].astype(np.int64)
    expected = np.r_[0, np.cumsum(np.left_shift(np.int64(1), depth))]
    np.testing.assert_array_equal(_leaf_weight_prefix(tree), expected)
    nodes = np.arange(tree.size)
    np.testing.assert_array_equal(_LeafCounts(tree)[nodes], tree.leaf_counts())
