"""Min-cut selection over the derivation tree (issue 8's required tests)."""

import networkx as nx
import numpy as np
import pytest
from networkx.algorithms import flow

from ramure.lsys import LSystem, ValueRefused
from ramure.lsys.regeneration.mincut import bonus_table, initial_capacities, kinship, select_roots


def ternary(n=3):
    return LSystem.from_text(f"n: {n}\nw: A\np:\n A -> AAA\n").derive()


def leaves_of(tree, node):
    return tree.leaves_under(node).tolist()


def test_bonus_table_n10():
    assert bonus_table(10, rho=0.5, bonus0=1024, kmax=5).tolist() == [1024, 1022, 1018, 1010, 994, 962]


@pytest.mark.parametrize("rho", [0, -0.1, 1.01, "x"])
def test_rho_out_of_range_refused(rho):
    with pytest.raises(ValueRefused, match="rho"):
        bonus_table(3, rho=rho)


def test_initial_capacities_double_up():
    t = ternary(2).tree
    cap = initial_capacities(t)
    assert cap[t.leaves].tolist() == [1.0] * 9
    assert cap[1] == 6 and cap[0] == 36  # 2*(1+1+1), 2*(6+6+6)


def test_no_selection_effect_keeps_leaves():
    d = ternary(3)
    one = d.tree.leaves[:1]
    cut = select_roots(d.tree, one, n=3, min_ascend=0)
    assert cut.cut_roots.size == 0 and cut.roots.size == 0


def test_more_than_rho_of_siblings_makes_parent_a_root():
    d = ternary(3)
    t = d.tree
    parent = int(t.parent[t.leaves[0]])
    cut = select_roots(t, t.leaves[:2], n=3, min_ascend=0)  # 2 of 3 > 0.5
    assert cut.cut_roots.tolist() == [parent]
    cut = select_roots(t, t.leaves[:1], n=3, min_ascend=0)  # 1 of 3 < 0.5
    assert cut.cut_roots.tolist() == []


def test_isolated_leaf_stays_while_cluster_climbs():
    d = ternary(3)
    t = d.tree
    cluster_root = int(t.ancestor(t.leaves[:1], 2)[0])  # depth-1 node holding 9 leaves
    cluster = leaves_of(t, cluster_root)
    lonely = int(t.leaves[-1])
    cut = select_roots(t, cluster + [lonely], n=3, min_ascend=0)
    assert cluster_root in cut.cut_roots.tolist()
    assert int(t.parent[lonely]) not in cut.cut_roots.tolist()
    assert lonely in cut.cut_nodes.tolist()  # the cut stays on the lonely leaf


def test_lower_rho_climbs_sooner():
    d = ternary(3)
    t = d.tree
    sel = t.leaves[:1]
    assert select_roots(t, sel, rho=0.5, n=3, min_ascend=0).cut_roots.size == 0
    assert select_roots(t, sel, rho=0.3, n=3, min_ascend=0).cut_roots.tolist() == [int(t.parent[sel[0]])]


def test_half_selected_tie_goes_to_lower_cut():
    d = LSystem.from_text("n: 2\nw: A\np:\n A -> AA\n").derive()  # balanced binary, 4 leaves
    t = d.tree
    cut = select_roots(t, t.leaves[:1], n=2, min_ascend=0)  # 1 of 2: a tie at the parent
    assert cut.cut_roots.size == 0


def test_min_ascend_regrows_from_parent():
    d = ternary(3)
    t = d.tree
    leaf = int(t.leaves[4])
    cut = select_roots(t, [leaf], n=3)  # min_ascend=1 by default
    assert cut.cut_roots.size == 0
    assert cut.min_roots.tolist() == [int(t.parent[leaf])] == cut.roots.tolist()


@pytest.mark.parametrize("flow_func", [flow.boykov_kolmogorov, flow.preflow_push, flow.edmonds_karp])
def test_cut_value_equals_sum_of_cut_capacities(flow_func):
    d = LSystem.from_file("grammars/honda_sympodial.lsys").derive(n=6)
    t = d.tree
    rng = np.random.default_rng(0)
    sel = rng.choice(t.leaves, 25, replace=False)
    cut = select_roots(t, sel, n=6, flow_func=flow_func)
    assert cut.cut_value == pytest.approx(sum(cut.cut_edges.values()))
    # cross-check against networkx's own minimum_cut on the unreduced graph
    full = select_roots(t, sel, n=6, flow_func=flow_func, reduce=False)
    value, _ = nx.minimum_cut(full.graph, "s", "t")
    assert cut.cut_value == pytest.approx(value) == pytest.approx(full.cut_value)


@pytest.mark.parametrize("seed", range(8))
def test_graph_reduction_keeps_the_answer(seed):
    d = LSystem.from_file("grammars/honda_sympodial.lsys").derive(n=7)
    t = d.tree
    rng = np.random.default_rng(seed)
    sel = rng.choice(t.leaves, int(rng.integers(1, 200)), replace=False)
    rho = float(rng.uniform(0.2, 1.0))
    a = select_roots(t, sel, rho=rho, n=7)
    b = select_roots(t, sel, rho=rho, n=7, reduce=False)
    assert a.roots.tolist() == b.roots.tolist()
    assert a.cut_nodes.tolist() == b.cut_nodes.tolist()
    assert a.cut_value == pytest.approx(b.cut_value)
    assert a.graph.number_of_nodes() <= b.graph.number_of_nodes()


def test_roots_do_not_nest():
    d = LSystem.from_file("grammars/honda_sympodial.lsys").derive(n=8)
    t = d.tree
    sel = t.leaves[::7]
    roots = select_roots(t, sel, n=8).roots
    for r in roots.tolist():
        assert not set(t.ancestors(r).tolist()) & set(roots.tolist())


def test_selection_must_be_leaves():
    d = ternary(2)
    with pytest.raises(ValueRefused, match="not a leaf"):
        select_roots(d.tree, [0], n=2)
    with pytest.raises(ValueRefused, match="empty"):
        select_roots(d.tree, [], n=2)


def test_kinship_hues():
    d = ternary(2)
    t = d.tree
    leaf = int(t.leaves[0])
    phi, hue, rgb = kinship(t, leaf, n=2)
    assert phi.tolist() == [0, 1, 1, 2, 2, 2, 2, 2, 2]
    assert hue.tolist() == [0, 120, 120, 240, 240, 240, 240, 240, 240]
    assert np.allclose(rgb[0], [1, 0, 0]) and np.allclose(rgb[-1], [0, 0, 1])


def test_networkx_loads_when_the_network_is_looked_at_not_for_a_cut():
    import subprocess
    import sys

    code = (
        "import sys; from ramure.lsys import LSystem; import ramure.lsys.regeneration.regen; "
        "a = 'networkx' in sys.modules; "
        "from ramure.lsys.regeneration.regen import Session; s = Session(LSystem.from_file('honda_sympodial'), n=4); "
        "cut = s.plan(s.tree.leaves[:2], rho=0.5)[0]; s.regrow(s.tree.leaves[:2], rho=0.5, seed=1); "
        "b = 'networkx' in sys.modules; print(a, b, cut.graph.number_of_nodes() > 2, 'networkx' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.split() == ["False", "False", "True", "True"], out.stderr


def _same_cut(a, b):
    assert a.cut_edges == b.cut_edges  # the same edges with the same capacities, exactly
    assert a.cut_value == b.cut_value
    for name in ("roots", "cut_roots", "min_roots", "cut_nodes", "selected"):
        assert getattr(a, name).tolist() == getattr(b, name).tolist(), name
    assert a.from_axiom == b.from_axiom


@pytest.mark.parametrize(
    ("name", "n"), [("honda_sympodial", 7), ("stochastic_plant", None), ("context_plant", None), ("abop/bush_1_25", 4)]
)
def test_the_trees_own_recursion_finds_the_max_flows_cut(name, n):
    ls = LSystem.from_file(name)
    d = ls.derive(n=n, seed=2)
    t, steps = d.tree, d.n
    rng = np.random.default_rng(len(name))
    sizes = (1, 2, 3, 5, 12, 40, 200, len(t.leaves) // 2, len(t.leaves))
    for size, rho in zip(sizes, (1.0, 0.5, 0.3, 0.5, 0.9, 0.25, 0.5, 0.5, 0.1)):
        sel = rng.choice(t.leaves, min(size, len(t.leaves)), replace=False)
        for bonus0 in (None, 3.5):
            fast = select_roots(t, sel, rho=rho, n=steps, bonus0=bonus0)
            for check in (dict(flow_func=flow.preflow_push), dict(reduce=False)):
                _same_cut(fast, select_roots(t, sel, rho=rho, n=steps, bonus0=bonus0, **check))
            # the network made on first use is the one the solver would have cut
            solved = select_roots(t, sel, rho=rho, n=steps, bonus0=bonus0, flow_func=flow.preflow_push)
            assert fast.source_side == solved.source_side
            assert sorted(fast.graph.edges(data=True), key=repr) == sorted(solved.graph.edges(data=True), key=repr)


def test_the_recursion_after_edits_and_with_ties():
    from ramure.lsys.regeneration.regen import Session

    s = Session(LSystem.from_file("honda_sympodial"), n=6, seed=0)
    leaves = s.tree.leaves
    s.regrow(leaves[10:30], rho=0.5, seed=1)
    s.prune(s.tree.leaves[40:45], rho=0.5)  # dead nodes and deleted modules in the tree
    t = s.tree
    found = set()
    for start in range(0, len(t.leaves), 7):
        sel = t.leaves[start : start + 4]
        for rho in (0.5, 1.0, 0.26):  # 0.5: ties at the parents of pairs
            fast = select_roots(t, sel, rho=rho, n=6, min_ascend=0)
            _same_cut(fast, select_roots(t, sel, rho=rho, n=6, min_ascend=0, reduce=False))
            found.add(fast.cut_roots.size > 0)
    assert found == {True, False}  # both cuts above the selection and cuts on it


@pytest.mark.parametrize("seed", range(12))
def test_tree_recursion_matches_the_flow_solver(seed):
    """The default cut (the tree's bottom-up recursion, no graph) gives networkx preflow-push's
    answer: the same roots, cut nodes, value and cut edges, for any selection and rho."""
    d = LSystem.from_file("grammars/honda_sympodial.lsys").derive(n=8)
    t = d.tree
    rng = np.random.default_rng(seed)
    sel = rng.choice(t.leaves, int(rng.integers(1, 300)), replace=False)
    rho = float(rng.choice([0.05, 0.2, 0.5, 0.75, 1.0]))
    tree_cut = select_roots(t, sel, rho=rho, n=8)
    flow_cut = select_roots(t, sel, rho=rho, n=8, flow_func=flow.preflow_push)
    assert tree_cut.roots.tolist() == flow_cut.roots.tolist()
    assert tree_cut.min_roots.tolist() == flow_cut.min_roots.tolist()
    assert tree_cut.cut_nodes.tolist() == flow_cut.cut_nodes.tolist()
    assert tree_cut.cut_value == flow_cut.cut_value == pytest.approx(sum(tree_cut.cut_edges.values()))
    assert tree_cut.cut_edges == flow_cut.cut_edges
    assert tree_cut.source_side == flow_cut.source_side
    assert set(tree_cut.graph.edges) == set(flow_cut.graph.edges)


@pytest.mark.parametrize("seed", range(3))
def test_graph_size_counts_the_graph_nodes_without_making_the_graph(seed):
    t = LSystem.from_file("grammars/honda_sympodial.lsys").derive(n=8).tree
    sel = np.random.default_rng(seed).choice(t.leaves, 40, replace=False)
    tree_cut = select_roots(t, sel, n=8)
    size = tree_cut.graph_size
    assert "_made" not in tree_cut.__dict__  # the graph, its edges and source side: not made yet
    flow_cut = select_roots(t, sel, n=8, flow_func=flow.preflow_push)
    for cut in (tree_cut, flow_cut):
        assert cut.graph_size == size == len({v[0] for v in cut.graph if isinstance(v, tuple)}) > 0


@pytest.mark.parametrize("seed", range(4))
def test_large_selections_mark_nodes_in_a_mask_with_the_same_answer(seed, monkeypatch):
    """path_nodes marks a tree-sized mask for large selections: the same nodes and roots as
    sorting each level (forced both ways here); collapse_nested (300 roots: its climb of all
    roots at once) keeps exactly the roots with no other root above them."""
    from ramure.lsys.regeneration import mincut as cut_module
    from ramure.lsys.regeneration.mincut import collapse_nested, path_nodes

    t = LSystem.from_file("grammars/honda_sympodial.lsys").derive(n=8).tree
    rng = np.random.default_rng(seed)
    sel = np.unique(rng.choice(t.leaves, int(rng.integers(2, 120)), replace=False))
    some = np.unique(rng.choice(np.arange(t.size), 300, replace=False))
    answers = []
    for mask_from in (10**9, 0):
        monkeypatch.setattr(cut_module, "MASK_FROM", mask_from)
        answers.append((path_nodes(t, sel).tolist(), collapse_nested(t, some).tolist(), select_roots(t, sel, n=8).roots.tolist()))
    assert answers[0] == answers[1]
    nodes = set(answers[0][0])
    assert all(int(t.parent[v]) in nodes for v in nodes if t.parent[v] >= 0) and set(sel.tolist()) <= nodes
    members = set(some.tolist())
    assert answers[0][1] == [r for r in some.tolist() if not members & set(t.ancestors(r).tolist())]


@pytest.mark.parametrize("count, wide", [(3, False), (40, False), (3, True), (300, True)])
def test_picked_share_counts_each_nodes_leaves_of_the_picked_kinds(count, wide):
    """The share a minimum ascension compares with rho, against a count leaf by leaf: small
    spans are counted on the spans, large ones (near the root) by running sums."""
    from ramure.lsys.regeneration.mincut import _picked_share
    from ramure import load

    tree = load("honda_sympodial").derive(n=9).tree
    rng = np.random.default_rng(count)
    string = np.asarray(tree.leaves)
    segments = string[tree.symbol[string] == tree.symbol[string].max()]  # one kind of module
    picked = rng.choice(segments, min(count, len(segments)), replace=False)
    nodes = tree.parent[picked]
    if wide:  # the root and other inner nodes: more than a sixteenth of the string in all
        nodes = np.r_[nodes, 0, rng.choice(np.flatnonzero(tree.child_count > 0), 20)]
    first, last = tree.leaf_spans()
    want = []
    for v in nodes:
        under = string[first[v] : last[v] + 1]
        kinds = np.isin(tree.symbol[under], tree.symbol[picked])
        want.append(np.isin(under, picked).sum() / kinds.sum() if kinds.any() else 0.0)
    np.testing.assert_allclose(_picked_share(tree, nodes, picked), want)
