"""The history tree's parameter table: read like the dense (size, max_params) array it replaces,
whether its later columns are still dense (while a derivation grows it) or compact (after)."""

from __future__ import annotations

import numpy as np
import pytest

from ramure.app.model import Explorer
from ramure.lsys import LSystem
from ramure.lsys.history.tree import DerivationTree


def random_tree(rng, nodes=3000, width=3):
    """A tree of ``nodes`` roots whose parameters are random, NaN beyond each node's count, and
    the dense table it should read as."""
    tree = DerivationTree(max_params=width, capacity=64)
    counts = rng.integers(0, width + 1, nodes)
    table = np.where(np.arange(width) < counts[:, None], rng.normal(size=(nodes, width)), np.nan)
    done = 0
    for size in np.diff(np.r_[0, np.sort(rng.choice(np.arange(1, nodes), 6, replace=False)), nodes]):
        rows = slice(done, done + size)
        tree.append(np.zeros(size, int), counts[rows], table[rows], -1, 0, -1, np.arange(size))
        done += size
    return tree, table


def assert_reads_like(params, table, rng):
    size = len(table)
    np.testing.assert_array_equal(np.asarray(params), table)
    assert params.shape == table.shape and len(params) == size
    ids = rng.integers(-size, size, 500)
    mask = rng.random(size) < 0.3
    last = table.shape[1] - 1
    keys = (ids, (ids, last), (ids, -1), (ids, slice(None, 2)), mask, (mask, last), slice(10, 900, 7), (slice(None), last))
    for key in (*keys, 17, -3, (5, last), (5, slice(None, 1))):
        np.testing.assert_array_equal(params[key], table[key], err_msg=repr(key))
    for bad in (size, -size - 1):
        with pytest.raises(IndexError):
            params[[0, bad], 1]


@pytest.mark.parametrize("width", [1, 2, 3])
def test_dense_and_compact_tables_read_as_the_dense_array(width):
    rng = np.random.default_rng(width)
    tree, table = random_tree(rng, width=width)
    assert_reads_like(tree.params, table, rng)
    dense_bytes = tree.params.nbytes
    tree.compact_params()
    assert_reads_like(tree.params, table, rng)
    assert tree.params.nbytes < dense_bytes or width == 1
    first = tree.params[:, 0]
    assert np.shares_memory(first, tree._param0) and first.base is not None  # a view, no copy


def test_a_compact_table_takes_appended_nodes_and_a_truncation():
    rng = np.random.default_rng(4)
    tree, table = random_tree(rng, width=2)
    tree.compact_params()
    more = np.where(rng.random((400, 2)) < 0.5, rng.normal(size=(400, 2)), np.nan)
    start = tree.extend(400, 1)
    tree.params[start:] = more
    assert_reads_like(tree.params, np.r_[table, more], rng)
    tree.truncate(len(table) + 150)  # a regeneration that failed
    assert_reads_like(tree.params, np.r_[table, more[:150]], rng)
    again = np.full((250, 2), 7.0)
    start = tree.extend(250, 2)
    tree.params[start:] = again  # the nodes after the truncation are new ones
    assert_reads_like(tree.params, np.r_[table, more[:150], again], rng)
    with pytest.raises(TypeError):
        tree.params[10:20] = 1.0  # only the nodes at the end are written


def test_a_derivation_keeps_its_table_compact_with_the_same_values(monkeypatch):
    source = str(LSystem.from_file("honda_sympodial").grammar.filename)
    compact = Explorer(source, n=12)
    monkeypatch.setattr(DerivationTree, "compact_params", lambda self: None)
    dense = Explorer(source, n=12)
    a, b = compact.derivation.tree, dense.derivation.tree
    assert a._rest is None and b._rest is not None
    np.testing.assert_array_equal(np.asarray(a.params), np.asarray(b.params))
    # Honda's nodes: most have fewer than two parameters, and the table is that much smaller
    assert a.params.nbytes < 0.7 * b.params.nbytes
    for ex in (compact, dense):  # the same edits on both: the same plants, the same tables
        for step in range(4):
            ex.select(np.random.default_rng(step).choice(ex.skeleton.leaf_id, 5, replace=False).tolist())
            ex.regrow(seed=step)
        ex.undo()
    np.testing.assert_array_equal(np.asarray(compact.derivation.tree.params), np.asarray(dense.derivation.tree.params))
    np.testing.assert_array_equal(compact.skeleton.start, dense.skeleton.start)
    assert compact.derivation.to_string() == dense.derivation.to_string()
