"""The min-cut decided exactly on deep histories, checked against a brute-force solver (issue 11).

Capacities double at every level, so from depth ~28 a float tolerance erases real
differences.  The brute force below enumerates every cut of the derivation tree
(an antichain covering every leaf of the string) with capacities in ``Fraction``
straight from the spec's definition, and takes the lowest of the minimum cuts.
"""

import json
import subprocess
import sys
from fractions import Fraction

import numpy as np
import pytest

from ramure.lsys import LSystem, ValueRefused
from ramure.lsys.regeneration.mincut import FROM_AXIOM_MESSAGE, exact_capacities, initial_capacities, select_roots
from ramure.lsys.regeneration.regen import Session
from ramure.lsys.history.tree import DerivationTree


# -- a tree builder and the brute force -------------------------------------------------------
def build_tree(children_of):
    """A DerivationTree from ``{node: n_children}``, ids given breadth first from the root 0."""
    tree = DerivationTree(max_params=1)
    tree.append([0], 0, 0.0, -1, 0, -1, [0])
    level, step = [0], 0
    while level:
        step += 1
        nxt = []
        for v in level:
            k = children_of.get(v, 0)
            if k:
                ids = tree.append([0] * k, 0, 0.0, v, step, 0, range(k))
                tree.set_children(v, int(ids[0]), k)
                nxt.extend(ids.tolist())
        level = nxt
    return finish(tree, [0])


def random_deep_tree(rng, depth, spines=2):
    """Depth ``depth``, at most ``spines`` growing nodes per level, 1-3 children each."""
    tree = DerivationTree(max_params=1)
    growing = tree.append([0], 0, 0.0, -1, 0, -1, [0]).tolist()
    for step in range(1, depth + 1):
        nxt = []
        for v in growing:
            k = int(rng.integers(1, 4))
            ids = tree.append([0] * k, 0, 0.0, v, step, 0, range(k))
            tree.set_children(v, int(ids[0]), k)
            keep = 1 if not nxt else int(rng.integers(0, 2))
            nxt.extend(rng.permutation(ids)[: min(keep, spines - len(nxt))].tolist())
        growing = nxt or growing[:0]
    return finish(tree, [0])


def finish(tree, roots):
    """Set the string (leaves in depth-first order) of a hand-built tree."""
    order, stack = [], list(roots)[::-1]
    while stack:
        v = stack.pop()
        kids = tree.children(v).tolist()
        if kids:
            stack.extend(kids[::-1])
        else:
            order.append(v)
    tree.leaves = np.array(order, np.int64)
    tree.changed()
    return tree


def spec_capacities(tree, selected, rho, n):
    """Capacities from the spec, in Fractions: leaf 1, internal 2 x children, + bonus_k, clamp 0."""
    rho = Fraction(repr(float(rho)))
    cap = {}
    in_string = set(tree.leaves.tolist())
    for v in range(tree.size - 1, -1, -1):
        kids = tree.children(v).tolist()
        cap[v] = 2 * sum(cap[c] for c in kids) if kids else Fraction(int(v in in_string))
    for leaf in selected:
        v, k = int(leaf), 0
        while v >= 0:
            cap[v] += Fraction(2) ** n - (Fraction(2) ** k - 1) / rho
            v, k = int(tree.parent[v]), k + 1
    return {v: max(c, Fraction(0)) for v, c in cap.items()}


def brute_force_cut(tree, selected, rho, n):
    """Every cut (antichain meeting each root-leaf path once), the lowest of the cheapest."""
    cap = spec_capacities(tree, selected, rho, n)

    def cuts(v):
        kids = tree.children(v).tolist()
        options = [(cap[v], frozenset([v]))]
        if kids:
            combos = [(Fraction(0), frozenset())]
            for c in kids:
                below = cuts(c)
                combos = [(a + b, s | t) for a, s in combos for b, t in below]
            options += combos
        return options

    roots = np.flatnonzero(tree.parent == -1).tolist()
    everything = [(Fraction(0), frozenset())]
    for r in roots:
        below = cuts(r)
        everything = [(a + b, s | t) for a, s in everything for b, t in below]
    best = min(value for value, _ in everything)
    ties = [s for value, s in everything if value == best]

    def source_size(cut):  # nodes at or above the cut: the lower cut has the most
        above = set()
        for v in cut:
            while v >= 0 and v not in above:
                above.add(v)
                v = int(tree.parent[v])
        return len(above)

    lowest = max(ties, key=source_size)
    assert len({s for s in ties if source_size(s) == source_size(lowest)}) == 1  # lattice: unique
    return best, lowest


def dp_cut(tree, selected, rho, n):
    """The same lowest minimum cut by the tree recursion (for trees too wide to enumerate).

    ``best(v) = min(cap(v), sum(best(children)))``; the cut stays below ``v`` on a tie.
    """
    cap = spec_capacities(tree, selected, rho, n)
    best, choice = {}, {}
    for v in range(tree.size - 1, -1, -1):
        kids = tree.children(v).tolist()
        below = sum((best[c] for c in kids), Fraction(0))
        take = not kids or cap[v] < below
        best[v], choice[v] = (cap[v] if take else below), take
    cut, stack = set(), np.flatnonzero(tree.parent == -1).tolist()
    while stack:
        v = stack.pop()
        if choice[v]:
            cut.add(v)
        else:
            stack.extend(tree.children(v).tolist())
    return sum((best[r] for r in np.flatnonzero(tree.parent == -1).tolist()), Fraction(0)), cut


# -- the tests -----------------------------------------------------------------------------------
def test_exact_capacities_match_the_doubling_rule():
    children = {0: 3, 1: 2, 2: 1, 3: 2, 6: 2}
    t = build_tree(children)
    exact = exact_capacities(t, np.arange(t.size))
    spec = spec_capacities(t, [], 1.0, 0)
    assert exact == [int(spec[v]) for v in range(t.size)]
    assert initial_capacities(t).tolist() == [float(c) for c in exact]


def test_exact_capacities_stay_whole_on_a_depth_70_chain():
    t = build_tree({2 * i: 2 for i in range(70)})  # a comb 70 deep
    top = exact_capacities(t, [0])[0]
    spec = spec_capacities(t, [], 1.0, 0)[0]
    assert top == spec and top > 2**60  # beyond float precision, still exact


@pytest.mark.parametrize("n", [20, 28, 31, 45, 60])
def test_selected_pair_climbs_to_the_cheapest_ancestor_at_any_depth(n):
    # Every leaf at depth n; the two selected leaves share a parent.  Capacities
    # are ~2**(n + 1) and the parent and grandparent differ by exactly 1:
    # the grandparent wins (a float tolerance calls it a tie from n ~ 28 on).
    t = LSystem.from_text(f"n: {n}\nw: A\np:\n A -> BA\n B -> B\n").derive().tree
    last = t.leaves[-2:]
    parent = int(t.parent[last[0]])
    assert int(t.parent[last[1]]) == parent and t.children(parent).tolist() == last.tolist()
    cut = select_roots(t, last, rho=0.5, n=n, min_ascend=0)
    value, lowest = dp_cut(t, last.tolist(), 0.5, n)
    assert sorted(v for v in lowest if t.child_count[v] > 0) == [int(t.parent[parent])]
    assert cut.cut_roots.tolist() == [int(t.parent[parent])]
    assert value == 2 ** (n + 1) + n - 2 and cut.cut_value == float(value)


@pytest.mark.parametrize("seed", range(24))
def test_deep_random_trees_agree_with_brute_force(seed):
    rng = np.random.default_rng(seed)
    depth = int(rng.integers(20, 61))
    t = random_deep_tree(rng, depth, spines=int(rng.integers(1, 3)))
    n = int(t.depth.max())
    leaves = t.leaves
    # a cluster (most leaves under one node) plus a few strays
    hub = int(rng.choice(np.flatnonzero(t.child_count > 0)))
    under = t.leaves_under(hub)
    take = under[rng.random(under.size) < rng.uniform(0.4, 1.0)]
    strays = rng.choice(leaves, int(rng.integers(0, 4)), replace=False)
    selected = np.unique(np.concatenate([take, strays, leaves[:1]]))
    rho = float(rng.choice([0.3, 0.5, 0.75, 0.9, 1.0, 1 / 3]))
    value, lowest = brute_force_cut(t, selected.tolist(), rho, n)
    assert (value, lowest) == dp_cut(t, selected.tolist(), rho, n)
    for reduce in (True, False):
        cut = select_roots(t, selected, rho=rho, n=n, min_ascend=0, reduce=reduce)
        internal = sorted(v for v in lowest if t.child_count[v] > 0)
        assert cut.cut_roots.tolist() == internal, (seed, reduce)
        kept = sorted(set(lowest) & set(selected.tolist()))
        assert sorted(set(cut.cut_nodes.tolist()) & set(selected.tolist())) == kept
        assert cut.cut_value == float(value)


def test_cut_value_counts_every_axiom_module():
    # ABOP fig. 2.8a at n = 4: '!', 'F' and '/' of the axiom hold no selected leaf.
    s = Session(LSystem.from_file("ternary_branching"), n=4)
    cut = select_roots(s.tree, [11], n=4, min_ascend=0)
    assert cut.cut_value == 740.0 == sum(cut.cut_edges.values())
    value, _ = dp_cut(s.tree, [11], 0.5, 4)
    assert cut.cut_value == float(value)


@pytest.mark.parametrize("seed", range(4))
def test_cut_value_equals_brute_force_on_multi_module_axioms(seed):
    rng = np.random.default_rng(100 + seed)
    ls = LSystem.from_text("n: 5\nw: XAYA\np:\n A -> F[A]B\n B -> FB\n X -> XX\n")
    t = ls.derive().tree
    sel = rng.choice(t.leaves, int(rng.integers(1, 6)), replace=False)
    cut = select_roots(t, sel, n=5, min_ascend=0)
    value, lowest = dp_cut(t, sel.tolist(), 0.5, 5)
    assert cut.cut_value == float(value) == pytest.approx(sum(cut.cut_edges.values()))
    assert cut.cut_roots.tolist() == sorted(v for v in lowest if t.child_count[v] > 0)


def test_huge_min_ascend_is_clamped_to_the_axiom():
    d = LSystem.from_file("ternary_branching").derive(n=4)
    t = d.tree
    leaf = int(t.leaves[5])
    for k in (10**9, 10**30):
        cut = select_roots(t, [leaf], n=4, min_ascend=k)
        axiom = int(t.ancestor([leaf], int(t.depth[leaf]))[0])
        assert cut.roots.tolist() == [axiom] and cut.from_axiom
    with pytest.raises(ValueRefused, match="min_ascend"):
        select_roots(t, [leaf], n=4, min_ascend=-1)


def test_session_file_with_huge_min_ascend_replays(tmp_path):
    s = Session(LSystem.from_file("ternary_branching"), n=3)
    leaf = next(
        int(x) for x in s.tree.leaves if s.tree.depth[x] == 3 and select_roots(s.tree, [x], n=3, min_ascend=0).roots.size == 0
    )  # the cut keeps it
    data = s.to_dict()
    data["edits"] = [
        {
            "op": "regrow",
            "selection": [leaf],
            "rho": 0.5,
            "seed": 3,
            "constants": {},
            "params": None,
            "min_ascend": 10**30,
            "ascend": None,
        }
    ]
    loaded = Session.from_dict(data)
    assert loaded.last_result.to_dict()["from_axiom"] is True


def test_from_axiom_is_reported_and_plain_selection_is_not():
    s = Session(LSystem.from_file("ternary_branching"), n=4)
    leaf = next(
        int(x) for x in s.tree.leaves if s.tree.depth[x] == 4 and select_roots(s.tree, [x], n=4, min_ascend=0).roots.size == 0
    )
    near = s.regrow([leaf], seed=1)
    assert near.to_dict()["from_axiom"] is False and "warning" not in near.to_dict()
    s.undo()
    everything = s.regrow(s.tree.leaves.tolist(), seed=1)
    record = everything.to_dict()
    assert record["from_axiom"] is True and record["warning"] == FROM_AXIOM_MESSAGE


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "ramure.app.cli", *args], capture_output=True, text=True, timeout=120)


def test_cli_reports_cut_value_clamp_and_axiom():
    out = run_cli("regen", "ternary_branching", "-n", "4", "--select", "11", "--min-ascend", "0", "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["cut_value"] == 740.0
    out = run_cli("regen", "ternary_branching", "-n", "4", "--select", "11", "--min-ascend", "1000000000", "--json")
    record = json.loads(out.stdout)
    assert out.returncode == 0 and record["from_axiom"] is True
    assert record["warning"] == FROM_AXIOM_MESSAGE


def test_status_lines_say_the_selection_regrows_from_the_axiom():
    from ramure.app.desktop.state import status_line
    from ramure.app.model import Explorer
    import ramure.grammars

    ex = Explorer(ramure.grammars.path("ternary_branching"), n=4)
    ex.selection = ex.derivation.tree.leaves.tolist()
    ex.regrow(seed=2)
    assert FROM_AXIOM_MESSAGE in ex.status()
    assert FROM_AXIOM_MESSAGE in status_line(ex)


def _session_text(**edit):
    s = Session(LSystem.from_file("ternary_branching"), n=2)
    data = s.to_dict()
    data["edits"] = [
        {
            "op": "regrow",
            "selection": [int(s.tree.leaves[-1])],
            "rho": 0.5,
            "seed": 1,
            "constants": {},
            "params": None,
            "min_ascend": 1,
            "ascend": None,
            **edit,
        }
    ]
    return json.dumps(data)


@pytest.mark.parametrize(
    "make",
    [
        lambda: "[" * 200000 + "]" * 200000,  # nesting
        lambda: '{"format": "ramure-session", "version": 1, "n": ' + "9" * 5000 + "}",  # huge int
        lambda: _session_text(selection=[2**70]),  # leaf id beyond int64
        lambda: _session_text(seed=2**70),
        lambda: _session_text(selection=[-(2**70)]),
    ],
)
def test_corrupt_session_files_are_refused_in_one_line(tmp_path, make):
    from ramure.errors import RamureError

    path = tmp_path / "s.json"
    path.write_text(make())
    with pytest.raises(RamureError) as info:
        Session.load(path)
    assert "\n" not in str(info.value) and len(str(info.value)) < 300
