"""Which subtrees to regrow: the minimum cut over the derivation tree (Salomon 2017, §2.4).

Each tree node ``v`` becomes two vertices ``(v, "in") -> (v, "out")`` joined by
an edge of finite capacity; tree edges ``(parent, "out") -> (child, "in")`` and
the source/sink edges are infinite.  A cut through a node edge keeps the node
and regrows everything below it.

Capacities: a leaf 1, an internal node twice the sum of its children, so with
no selection the cut sits on the leaves.  A selected leaf adds
``bonus_k = bonus_0 - (2**k - 1) / rho`` to its k-th ancestor (k = 0 is the
leaf), ``bonus_0 = 2**n`` by default; a capacity that would go negative is
clamped at 0 (spec §4.5).  One level above the leaves this makes the parent a
root exactly when more than ``rho`` of its leaf children are selected.  Higher
up it weighs leaves, not children: against cutting all its children a node is
cut when more than ``rho`` of its leaves (weighted by ``2**depth`` below it)
are selected, so the cut can stay below the spec's child-count rule
(docs/cut.md; tests/lsys/test_lsys_cut_threshold.py).  A selected leaf the cut
keeps regrows from its parent when that parent carries no branch grown later,
or when at least ``rho`` of its leaves of the selected kinds are selected
(:func:`minimum_ascension`).

Only what the cut can touch is built: the selected leaves and their ancestors.
The children of those nodes that hold no selection are merged into one edge
``(v, "out") -> sink`` whose capacity is their number of leaves — exactly the
cheapest cut inside an unselected subtree (with doubling capacities that is
always its leaves) — so the graph has ~2 vertices per ancestor, whatever the
size of the plant.

Ties go to the **lower** cut (the spec's prudent behaviour): the source side
is every vertex that cannot reach the sink in the residual graph.

>>> from ramure.lsys import LSystem
>>> d = LSystem.from_text("n: 1\\nw: A\\np: A -> BBBB").derive()
>>> select_roots(d.tree, [1, 2, 3], n=1).cut_roots.tolist()  # 3 of 4 > rho = 0.5
[0]
>>> select_roots(d.tree, [1], n=1).cut_roots.tolist()        # 1 of 4 stays a leaf
[]
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from fractions import Fraction
from functools import partial
from types import SimpleNamespace

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

if TYPE_CHECKING:
    import networkx as nx  # loaded on the first cut (about 20 MB and a second to import)

    from ..history.tree import DerivationTree

from ..errors import ValueRefused
from ..history.tree import concat_ranges, sorted_unique

SOURCE, SINK = "s", "t"


def check_rho(rho: float) -> float:
    """Refuse rho outside (0, 1] with a message in the user's words (the UI shows 0-100)."""
    try:
        rho = float(rho)
    except (TypeError, ValueError):
        raise ValueRefused(f"rho must be a number in (0, 1], got {rho!r}") from None
    if not 0 < rho <= 1:
        raise ValueRefused(f"rho must be in (0, 1] (0-100 in the UI), got {rho:g}")
    return rho


def bonus_table(n: int, rho: float = 0.5, bonus0: float | None = None, kmax: int | None = None) -> np.ndarray:
    """``bonus_k`` for k = 0..kmax (default n): the selection bonus k levels above a leaf.

    >>> bonus_table(10, rho=0.5, kmax=5).tolist()
    [1024.0, 1022.0, 1018.0, 1010.0, 994.0, 962.0]
    """
    rho = check_rho(rho)
    bonus0 = float(2**n if bonus0 is None else bonus0)
    k = np.arange((n if kmax is None else kmax) + 1, dtype=float)
    return bonus0 - (2.0**k - 1.0) / rho


def initial_capacities(tree: DerivationTree) -> np.ndarray:
    """Capacity of every node with no selection: leaf 1, internal 2 x sum of children.

    Returned as floats for display; the cut itself uses :func:`exact_capacities`
    (floats lose whole units above 2**53, reached on deep histories).
    """

    def make():
        cap = np.zeros(tree.size)
        child_sum = np.zeros(tree.size)
        is_leaf = tree.child_count == 0
        for nodes in reversed(tree.nodes_by_step()):
            cap[nodes] = np.where(is_leaf[nodes], 1.0, 2.0 * child_sum[nodes])
            has_parent = tree.parent[nodes] >= 0
            np.add.at(child_sum, tree.parent[nodes[has_parent]], cap[nodes[has_parent]])
        in_string = np.zeros(tree.size, bool)
        in_string[tree.leaves] = True
        cap[is_leaf & ~in_string] = 0.0  # modules deleted by an empty successor
        return cap

    return tree.cached("cut_capacity", make)


def _leaf_weight_prefix(tree):
    """Prefix sums of ``2**depth`` over the current string (int64 when exact, else Python ints)."""

    def make():
        whole = tree.depth
        top = int(whole.max()) if whole.size else 0
        if top + int(np.ceil(np.log2(len(tree.leaves) + 1))) < 62 and tree.size >= 50_000:
            from ..history.tree import leaf_weight_prefix

            return leaf_weight_prefix(whole, tree.leaves)  # one pass, no gathered copy
        depth = whole[tree.leaves].astype(np.int64)
        top = int(depth.max()) if depth.size else 0
        if top + int(np.ceil(np.log2(depth.size + 1))) < 62:
            prefix = np.zeros(depth.size + 1, np.int64)
            np.cumsum(np.left_shift(np.int64(1), depth), out=prefix[1:])
            return prefix
        exact, total = [0], 0  # Python ints: exact past 2**62
        for d in depth.tolist():
            total += 1 << d
            exact.append(total)
        return np.array(exact, dtype=object)

    return tree.cached("cut_leaf_prefix", make)


def exact_capacities(tree: DerivationTree, nodes: ArrayLike) -> list[int]:
    """Initial capacities of ``nodes`` as exact Python integers.

    A node's capacity is ``sum(2**(depth(leaf) - depth(node)))`` over the leaves
    of the current string below it (leaf 1, internal twice the sum of its
    children, modules deleted by an empty successor 0); leaves below a node are
    contiguous in the string, so one prefix sum serves every node.
    """
    nodes = np.asarray(nodes, np.int64)
    _, weights = tree.subtree_weights(nodes)  # kept by the tree across edits: no whole-tree pass
    if weights is not None:
        return [int(w) for w in weights.tolist()]
    first, last = tree.leaf_spans()
    prefix = _leaf_weight_prefix(tree)
    depth = tree.depth
    out = []
    for v, a, b, d in zip(nodes.tolist(), first[nodes].tolist(), last[nodes].tolist(), depth[nodes].tolist()):
        out.append(0 if b < 0 else int(prefix[b + 1] - prefix[a]) >> d)
    return out


def _as_fraction(value, what):
    """An exact rational for a user number: decimal floats as written (0.9 is 9/10)."""
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        return Fraction(int(value))
    value = float(value)
    if not np.isfinite(value):
        raise ValueRefused(f"{what} must be a finite number, got {value}")
    return Fraction(repr(value))


@dataclass
class CutResult:
    """What the min-cut decided.

    ``roots``: the nodes to regrow from (nested roots collapsed to the highest);
    ``cut_roots``: those the cut chose; ``min_roots``: those added by the
    minimum ascension for selected leaves the cut left in place;
    ``cut_nodes``: every node whose node edge is cut (kept leaves included);
    ``cut_value``: the minimum cut's value, exactly ``sum(cut_edges.values())``
    computed in rationals (so on every axiom module, selected or not);
    ``from_axiom``: a root is an axiom module, so the regrowth restarts from
    the axiom (:data:`FROM_AXIOM_MESSAGE` is what front ends say);
    ``graph_size``: the tree nodes in ``graph`` (each two vertices), known without making it.

    ``cut_edges`` (edge -> capacity), ``graph`` (the networkx graph of
    :func:`build_graph`) and ``source_side`` (its vertices on the source side)
    are made when first read: a quarter of a million-module plant cuts through
    tens of thousands of edges, and only the cut-graph view reads them.
    """

    roots: np.ndarray
    cut_roots: np.ndarray
    min_roots: np.ndarray
    cut_nodes: np.ndarray
    cut_value: float
    make_details: Callable[[], tuple[dict, nx.DiGraph, set]] = field(repr=False)
    selected: np.ndarray | None = field(repr=False, default=None)
    from_axiom: bool = False
    graph_size: int = 0

    def _details(self):
        if "_made" not in self.__dict__:
            self.__dict__["_made"] = self.make_details()
        return self.__dict__["_made"]

    @property
    def cut_edges(self) -> dict:
        return self._details()[0]

    @property
    def graph(self) -> nx.DiGraph:
        return self._details()[1]

    @property
    def source_side(self) -> set:
        return self._details()[2]


#: What front ends and the CLI say when a selection's regrowth starts at an axiom module.
FROM_AXIOM_MESSAGE = "this selection regrows from the axiom: the whole plant"


def stranded_words(count: int) -> str:
    """Why selected leaves regrow nothing (a segment carrying branches grown after it).

    >>> stranded_words(1)[:46]
    'the selected leaf carries branches grown after'
    """
    leaf, it = ("leaf carries", "it") if count == 1 else ("leaves carry", "them")
    return (
        f"the selected {leaf} branches grown after {it}, which the cut keeps (no more than ρ of them is "
        f"selected); select those branches too to regrow {it}"
    )


def validate_selection(tree: DerivationTree, selected: Iterable[int]) -> np.ndarray:
    """``selected`` as sorted unique leaf ids of ``tree``; :class:`ValueRefused` for an empty
    selection, an id that is not a node, or a node that is not a leaf of the current string."""
    try:
        selected = sorted_unique(np.asarray(list(selected), np.int64))
    except (OverflowError, TypeError, ValueError):
        raise ValueRefused("the selection must be a list of leaf ids (whole numbers)") from None
    if selected.size == 0:
        raise ValueRefused("the selection is empty: select at least one branch or organ")
    bad = (selected < 0) | (selected >= tree.size)
    if bad.any():
        raise ValueRefused(f"node {int(selected[bad][0])} does not exist in this plant")
    in_string = tree.in_string(selected)
    if not in_string.all():
        raise ValueRefused(
            f"node {int(selected[~in_string][0])} is not a leaf of the current plant (only leaves can be selected)"
        )
    return selected


#: From this many selected leaves on, :func:`path_nodes` marks the ancestors in a tree-sized mask
#: (a few ms on a million-node tree) instead of sorting each level's ids.
MASK_FROM = 2_000


def path_nodes(tree: DerivationTree, selected: np.ndarray) -> np.ndarray:
    """The selected leaves and all their ancestors, sorted."""
    if selected.size < MASK_FROM:
        nodes, frontier = [selected], selected
        while frontier.size:
            frontier = sorted_unique(tree.parent[frontier])
            frontier = frontier[frontier >= 0]
            nodes.append(frontier)
        return sorted_unique(np.concatenate(nodes))
    seen = np.zeros(tree.size, bool)
    seen[selected] = True
    frontier = selected
    while frontier.size:  # each level: the parents not seen yet (a repeat is dropped one level up)
        frontier = tree.parent[frontier]
        frontier = frontier[frontier >= 0]
        frontier = frontier[~seen[frontier]]
        seen[frontier] = True
    return np.flatnonzero(seen)


def _scale(rho, bonus0, n):
    """``(S, bonus0 * S, q / p * S)``: every capacity times ``S`` is a whole number.

    Capacities are whole numbers plus ``bonus_k = bonus0 - (2**k - 1) / rho``;
    with ``rho = p / q`` and ``bonus0 = a / b`` (as written in decimal),
    ``S = p * b`` makes every ``bonus_k * S`` an integer, so the cut is decided
    in exact integer arithmetic however deep the history (floats lose whole
    units above 2**53, i.e. from n of about 28 on a branching plant).
    """
    r = _as_fraction(rho, "rho")
    a0 = Fraction(2) ** int(n) if bonus0 is None else _as_fraction(bonus0, "bonus0")
    scale = r.numerator * a0.denominator
    return scale, int(a0 * scale), int(scale / r)


def _cut_arrays(tree, selected, rho, bonus0, n):
    """The capacities of the graph's path nodes (see :func:`build_graph`), as arrays.

    ``cap``: each node edge's capacity; ``off_path``: the merged sink edge of the
    node's children that hold no selection; both exact integers (object arrays)
    times ``scale``.  ``parent_idx``: the parent's index in ``nodes`` (-1 at the top).
    """
    rho = check_rho(rho)
    selected = validate_selection(tree, selected)
    n = int(tree.depth.max()) if n is None else int(n)
    scale, bonus_s, step_s = _scale(rho, bonus0, n)
    nodes = path_nodes(tree, selected)
    depth = tree.depth_of(nodes)
    cap = np.array([c * scale for c in exact_capacities(tree, nodes)] or [0], dtype=object)[: len(nodes)]
    current, k = selected.copy(), 0
    while current.size:
        np.add.at(cap, np.searchsorted(nodes, current), bonus_s - ((1 << k) - 1) * step_s)
        current = tree.parent[current]
        current = current[current >= 0]
        k += 1
    cap = np.maximum(cap, 0) if len(nodes) else np.zeros(0, object)
    counts = _LeafCounts(tree)
    node_counts = counts[nodes]
    parent = tree.parent[nodes]
    has_parent = parent >= 0
    parent_idx = np.where(has_parent, np.searchsorted(nodes, parent), -1)
    on_path_children = np.zeros(len(nodes), np.int64)
    np.add.at(on_path_children, parent_idx[has_parent], node_counts[has_parent])
    is_selected = np.isin(nodes, selected, assume_unique=True)
    off_path = np.where(is_selected, 0, node_counts - on_path_children).astype(object) * scale
    return SimpleNamespace(
        tree=tree,
        selected=selected,
        scale=scale,
        nodes=nodes,
        depth=depth,
        cap=cap,
        off_path=off_path,
        parent=parent,
        parent_idx=parent_idx,
        is_selected=is_selected,
        counts=counts,
    )


def build_graph(
    tree: DerivationTree,
    selected: Iterable[int],
    rho: float = 0.5,
    bonus0: float | None = None,
    n: int | None = None,
    reduce: bool = True,
) -> tuple[nx.DiGraph, np.ndarray, dict]:
    """The directed graph of the spec, restricted to what the cut can touch.

    Returns ``(G, selected, merged_edges)``.  Each finite edge carries its
    capacity twice: ``capacity`` (a float, for display) and ``exact`` (the
    capacity times ``G.graph["scale"]``, a Python integer: what the solver
    uses).  With ``reduce`` (the default), nodes that no minimum cut can pass
    through (capacity at least the cheapest cut below them, found by the
    tree's own bottom-up recursion) and whose ancestors are all such nodes are
    merged into the source; the sink edges they carried become
    ``merged_edges`` (always cut; ``edge -> exact scaled capacity``), as do the
    leaves of axiom modules that hold no selected leaf.
    """
    a = _cut_arrays(tree, selected, rho, bonus0, n)
    merged = _never_cut_from_source(a) if reduce else np.zeros(len(a.nodes), bool)
    return _graph(a, merged), a.selected, _merged_edges(a, merged)


def _graph(a, merged):
    """The networkx graph of the path nodes that are not ``merged`` into the source."""
    import networkx as nx

    nodes, cap, scale, parent_idx = a.nodes, a.cap, a.scale, a.parent_idx
    G = nx.DiGraph(scale=scale)
    keep = ~merged
    ids, par = nodes.tolist(), a.parent.tolist()
    from_source = keep & ((parent_idx < 0) | merged[np.maximum(parent_idx, 0)])
    G.add_edges_from(
        ((v, "in"), (v, "out"), {"capacity": c / scale, "exact": c}) for v, c in zip(nodes[keep].tolist(), cap[keep].tolist())
    )
    G.add_edges_from(
        ((p, "out"), (v, "in")) for v, p, ok, src in zip(ids, par, keep.tolist(), from_source.tolist()) if ok and not src
    )
    G.add_edges_from((SOURCE, (v, "in")) for v in nodes[from_source].tolist())
    G.add_edges_from(((v, "out"), SINK) for v in a.selected.tolist())
    G.add_edges_from(
        ((v, "out"), SINK, {"capacity": c / scale, "exact": c})
        for v, c, ok in zip(ids, a.off_path.tolist(), keep.tolist())
        if ok and c > 0
    )
    return G


def _merged_edges(a, merged):
    """The sink edges of the nodes merged into the source and of the unselected axiom modules
    (always cut): edge -> exact scaled capacity."""
    ids, off_path = a.nodes[merged].tolist(), a.off_path[merged].tolist()
    edges = {((v, "out"), SINK): c for v, c in zip(ids, off_path) if c > 0}
    edges.update(_unselected_axiom_modules(a.tree, a.nodes, a.counts, a.scale))
    return edges


class _LeafCounts:
    """``tree.leaf_counts()[nodes]`` for the few nodes a cut reads, without a whole-tree array."""

    def __init__(self, tree) -> None:
        self.tree = tree

    def __getitem__(self, nodes):
        return self.tree.subtree_weights(nodes)[0]


def _unselected_axiom_modules(tree, nodes, counts, scale):
    """Axiom modules holding no selected leaf: their cheapest cut is their leaves, always cut."""
    axiom = tree.axiom_modules()
    axiom = axiom[~np.isin(axiom, nodes, assume_unique=True) & (counts[axiom] > 0)]
    return {((v, "out"), SINK): int(c) * scale for v, c in zip(axiom.tolist(), counts[axiom].tolist())}


def _levels(depth):
    """Indices of the path nodes per derivation depth, top first (one sort, no pass per depth)."""
    order = np.argsort(depth, kind="stable")
    bounds = np.searchsorted(depth[order], np.arange(int(depth.max()) + 2) if depth.size else [0])
    return [order[lo:hi] for lo, hi in zip(bounds[:-1], bounds[1:])]


def _cheapest_below(a):
    """``(best, below, levels)``: the cheapest cut of each path node's subtree (``best[v] =
    min(cap[v], below[v])``, a selected leaf's own capacity), the cheapest cut under its node
    edge (``below[v] = off_path[v] + sum(best[children])``), and the node indices per depth.
    Capacities are exact integers (object arrays), so a tie is a tie."""
    cap, parent_idx, is_selected = a.cap, a.parent_idx, a.is_selected
    below = a.off_path.copy()
    best = np.where(is_selected, cap, 0).astype(object)
    levels = _levels(a.depth)
    for idx in reversed(levels):
        inner = idx[~is_selected[idx]]
        best[inner] = np.minimum(cap[inner], below[inner])
        up = idx[parent_idx[idx] >= 0]
        np.add.at(below, parent_idx[up], best[up])
    return best, below, levels


def _never_cut_from_source(a, cheapest=None):
    """Path nodes that no (lower) minimum cut crosses, reachable from the source through such nodes.

    Bottom-up (:func:`_cheapest_below`): a node whose capacity is at least the
    cheapest cut below it is never cut (ties go to the lower cut).  Top-down:
    merge it only if its parent is merged too.
    """
    _, below, levels = cheapest or _cheapest_below(a)
    parent_idx = a.parent_idx
    never = ~a.is_selected & (a.cap >= below).astype(bool)
    merged = np.zeros(len(a.nodes), bool)
    for idx in levels:
        top = parent_idx[idx] < 0
        merged[idx] = never[idx] & (top | merged[np.maximum(parent_idx[idx], 0)])
    return merged


def _tree_cut(a):
    """The lower minimum cut by the tree's own recursion (no flow solver): the graph is a tree
    whose every subtree is cut independently, so the cheapest cut below each node decides.

    The nodes :func:`_never_cut_from_source` merges into the source are passed.  The source
    side of the lower cut (the largest of the minimum cuts') holds ``(v, "in")`` when v's parent
    is passed (or v is an axiom module), and also when v's subtree can be cut for nothing
    (``best == 0``: capacities clamped at 0 by a low rho), as a flow solver's residual graph
    finds; it holds ``(v, "out")`` too when v is never cut.  Returns ``(cut, passed, source)``:
    masks over ``a.nodes`` of the nodes whose node edge is cut, of the passed ones, and of
    those whose ``(v, "in")`` is on the source side.
    """
    cheapest = _cheapest_below(a)
    passed = _never_cut_from_source(a, cheapest)
    never = ~a.is_selected & (a.cap >= cheapest[1]).astype(bool)
    reached = (a.parent_idx < 0) | passed[np.maximum(a.parent_idx, 0)]
    source = reached | (cheapest[0] == 0).astype(bool)
    return source & ~never, passed, source & ~passed


def _tree_details(a, cut, passed, source):
    """``(cut_edges, graph, source_side)`` of a :func:`_tree_cut` (the graph is the reduced one)."""
    G = _graph(a, passed)
    ids = a.nodes[cut].tolist()
    exact = {((v, "in"), (v, "out")): c for v, c in zip(ids, a.cap[cut].tolist())}
    exact.update(_merged_edges(a, passed))
    outs = a.nodes[source & ~cut].tolist()
    source_side = {SOURCE, *((v, "in") for v in a.nodes[source].tolist()), *((v, "out") for v in outs)}
    return {e: float(Fraction(c, a.scale)) for e, c in exact.items()}, G, source_side


def _lower_cut(R):
    """Vertices that cannot reach the sink in the residual graph R (the lower cut).

    Capacities are exact integers, so an edge is saturated exactly when its
    residual is zero: no tolerance, however large the capacities grow.
    """
    sink_side = {SINK}
    stack = [SINK]
    pred = R.pred
    while stack:
        v = stack.pop()
        for u, attrs in pred[v].items():
            if u not in sink_side and attrs["capacity"] - attrs["flow"] > 0:
                sink_side.add(u)
                stack.append(u)
    return set(R) - sink_side


def solve(G: nx.DiGraph, flow_func: Callable | None = None) -> tuple[int, set]:
    """Max flow / min cut on ``G``; returns ``(scaled cut value, source_side)`` with the lower cut.

    The solver runs on the ``exact`` (scaled integer) capacities.  The default
    is preflow-push: on the graphs built here it measured about 3x faster than
    Boykov-Kolmogorov (``benchmarks/bench_regen.py``).
    """
    if G.number_of_edges() == 0 or SOURCE not in G or SINK not in G:
        return 0, set(G) | {SOURCE}
    if flow_func is None:
        from networkx.algorithms import flow

        flow_func = flow.preflow_push
    R = flow_func(G, SOURCE, SINK, capacity="exact")
    return R.graph["flow_value"], _lower_cut(R)


def select_roots(
    tree: DerivationTree,
    selected: Iterable[int],
    rho: float = 0.5,
    bonus0: float | None = None,
    n: int | None = None,
    min_ascend: int = 1,
    flow_func: Callable | None = None,
    reduce: bool = True,
    whole_branches: bool = False,
) -> CutResult:
    """Decide which subtrees a selection regrows.  See the module docstring.

    ``min_ascend``: a selected leaf that the cut leaves in place still regrows
    from its ``min_ascend``-th ancestor, so a selection always changes
    something (0 turns this off; values above the tree's depth mean the axiom
    module).  By default the cut comes from the tree's own bottom-up recursion
    (:func:`_tree_cut`: arrays, no graph; 32,000 selected leaves of a 1.4 M-module
    plant in a fraction of a second, where preflow-push took 17 s).  ``flow_func``
    (any networkx max-flow function) or ``reduce=False`` (the unreduced graph)
    solve the graph with networkx instead: same answer, slower; kept for checking.
    ``whole_branches``: see :func:`minimum_ascension`.
    """
    min_ascend = _check_min_ascend(min_ascend, tree)
    if flow_func is None and reduce:
        a = _cut_arrays(tree, selected, rho, bonus0, n)
        cut, passed, source = _tree_cut(a)
        chosen, cut_nodes = a.selected, a.nodes[cut]
        value = sum(a.cap[cut].tolist()) + sum(a.off_path[passed].tolist())
        value += sum(_unselected_axiom_modules(tree, a.nodes, a.counts, a.scale).values())
        value = float(Fraction(value, a.scale))
        details = partial(_tree_details, a, cut, passed, source)
        graph_size = int(len(a.nodes) - passed.sum())
    else:
        cut_nodes, value, details, chosen = _flow_cut(tree, selected, rho, bonus0, n, flow_func, reduce)
        graph_size = len({v[0] for v in details()[1] if isinstance(v, tuple)})
    internal = tree.child_count[cut_nodes] > 0
    cut_roots = cut_nodes[internal]
    kept = np.intersect1d(cut_nodes[~internal], chosen, assume_unique=True)
    min_roots = np.zeros(0, np.int64)
    if min_ascend > 0 and kept.size:
        top = minimum_ascension(tree, kept, min_ascend, whole_branches, chosen, rho)
        min_roots = sorted_unique(top[tree.child_count[top] > 0])
    roots = collapse_nested(tree, np.concatenate([cut_roots, min_roots]))  # it sorts and dedupes
    return CutResult(
        roots,
        np.intersect1d(cut_roots, roots, assume_unique=True),
        np.intersect1d(np.setdiff1d(min_roots, cut_roots, assume_unique=True), roots, assume_unique=True),
        cut_nodes,
        value,
        details,
        chosen,
        from_axiom=bool(roots.size and (tree.parent[roots] < 0).any()),
        graph_size=graph_size,
    )


def _flow_cut(tree, selected, rho, bonus0, n, flow_func, reduce):
    """The cut by a networkx max-flow solver on :func:`build_graph`'s graph (kept for checking
    the tree recursion, and for any solver a caller names): ``(cut_nodes, value, details,
    selected)`` as :func:`select_roots` uses them."""
    G, selected, merged_edges = build_graph(tree, selected, rho, bonus0, n, reduce=reduce)
    scale = G.graph["scale"]
    _, source_side = solve(G, flow_func)
    exact = {(u, v): d.get("exact") for u, v, d in G.edges(data=True) if u in source_side and v not in source_side}
    exact.update(merged_edges)
    finite = [c for c in exact.values() if c is not None]
    value = float(Fraction(sum(finite), scale)) if len(finite) == len(exact) else float("inf")
    cut_edges = {e: float("inf") if c is None else float(Fraction(c, scale)) for e, c in exact.items()}
    cut_nodes = np.array(sorted(u[0] for u, v in cut_edges if isinstance(u, tuple) and u[1] == "in"), np.int64)
    return cut_nodes, value, lambda: (cut_edges, G, source_side), selected


def minimum_ascension(
    tree: DerivationTree,
    leaves: ArrayLike,
    k: int,
    whole_branches: bool = False,
    selected: ArrayLike | None = None,
    rho: float = 0.5,
) -> np.ndarray:
    """Where each of ``leaves`` (selected leaves the cut left in place) regrows from.

    ``k`` = 1, the default: its parent, when the parent's children are all leaves (a tip and
    the modules its rule made with it) or at least ``rho`` of the parent's leaves *of the
    selected kinds* (the symbols of ``selected``, e.g. the segments ``F`` a click or a
    rectangle picks) are selected; else the leaf itself (nothing regrows).  The cut's
    threshold rule counts every module (brackets and turns too, which no click selects), so
    it keeps a lone picked leaf in place; this minimum ascension still regrows a tip with the
    modules its rule made with it (its parent holds one segment, the tip) and a rubber-banded
    branch with its parents, but never takes branches the user did not pick: one click on a
    segment made at step 2 of Honda n = 6 once replaced the 342 of its 693 modules grown on
    it.  The preview says which leaves stay (:func:`climb_levels` gives them -1).

    ``k`` > 1 is an explicit request (a session's ``min_ascend``, a qualifier told to climb):
    the ``k``-th ancestor, or the axiom module above a shallower leaf.  So is
    ``whole_branches`` (what ``k`` = 1 did before issue 34: sessions saved then replay with it).
    """
    leaves = np.asarray(leaves, np.int64)
    if int(k) > 1 or whole_branches:
        up = tree.ancestor(leaves, k)
        return np.where(up < 0, _axiom_root(tree, leaves), up)
    up = tree.parent[leaves].astype(np.int64)
    ok = up >= 0
    selected = leaves if selected is None else np.asarray(selected, np.int64)
    parents = up[ok]
    climbs = _only_leaves_below(tree, parents)  # a tip: its parent holds leaves only
    if not climbs.all():  # the share of picked leaves only where it decides (two passes over the string)
        climbs[~climbs] = _picked_share(tree, parents[~climbs], selected) >= rho
    ok[ok] = climbs
    return np.where(ok, up, leaves)


def _only_leaves_below(tree, nodes):
    """Whether each node's children are all leaves (a group one rule made, nothing grown on it)."""
    counts = tree.child_count[nodes].astype(np.int64)
    children = concat_ranges(tree.child_start[nodes].astype(np.int64), counts)
    inner = np.zeros(len(nodes), bool)
    np.logical_or.at(inner, np.repeat(np.arange(len(nodes)), counts), tree.child_count[children] > 0)
    return ~inner


def _picked_share(tree, nodes, selected):
    """For each node, the share of its leaves of the selected symbols that are selected.

    Nodes whose leaves make a small part of the string (a tip's parent, a twig) are counted on
    their spans only; larger ones by running sums over the whole string."""
    string = np.asarray(tree.leaves)
    unique, back = _unique_inverse(np.asarray(nodes, np.int64))
    if len(unique) > 256:
        first, last = tree.leaf_spans()
        first, last = first[unique], last[unique]
    else:
        first, last = tree.string_spans(unique)
    has = last >= 0
    a, b = np.where(has, first, 0), np.where(has, last + 1, 0)
    symbols = sorted_unique(tree.symbol[selected])
    picked_at = np.sort(tree.leaf_positions(selected))
    if (b - a).sum() <= len(string) // 16:
        total = _span_kinds(tree, string, a, b, symbols)
    else:
        kind_sum = np.zeros(len(string) + 1, np.int64)
        np.cumsum(np.isin(tree.symbol[string], symbols), out=kind_sum[1:])
        total = kind_sum[b] - kind_sum[a]
    chosen = np.searchsorted(picked_at, b) - np.searchsorted(picked_at, a)
    share = np.where(total > 0, chosen / np.maximum(total, 1), 0.0)
    return share[back]


def _span_kinds(tree, string, a, b, symbols):
    """Leaves of ``symbols`` in each string span ``[a, b)``, counted on the spans only."""
    at = concat_ranges(a, b - a)
    owner = np.repeat(np.arange(len(a)), b - a)
    return np.bincount(owner[np.isin(tree.symbol[string[at]], symbols)], minlength=len(a))


def _unique_inverse(values):
    """``np.unique(values, return_inverse=True)`` by one sort (no numpy.ma import)."""
    order = np.argsort(values, kind="stable")
    ordered = values[order]
    first = np.r_[True, ordered[1:] != ordered[:-1]] if len(ordered) else np.zeros(0, bool)
    back = np.empty(len(values), np.int64)
    back[order] = np.cumsum(first) - 1
    return ordered[first], back


def _axiom_root(tree, nodes):
    """The highest ancestor of each node (its axiom module)."""
    out = np.asarray(nodes, np.int64).copy()
    while True:
        up = tree.parent[out]
        more = up >= 0
        if not more.any():
            return out
        out[more] = up[more]


def climb_levels(tree: DerivationTree, leaves: ArrayLike, roots: ArrayLike) -> np.ndarray:
    """How many levels above each of ``leaves`` its regrown root is (-1: under no root, the
    leaf stays).  Walks up the parent links, which an edit keeps for the nodes it removed, so
    this answers before and after the regrow alike; one pass per level, no whole-tree array.

    >>> from ramure.lsys import LSystem
    >>> t = LSystem.from_text("n: 2\\nw: A\\np:\\n A -> BB\\n B -> CC").derive().tree
    >>> climb_levels(t, t.leaves, [1]).tolist()  # the first B holds the first two leaves
    [1, 1, -1, -1]
    """
    up = np.asarray(leaves, np.int64).copy()
    roots = sorted_unique(np.asarray(roots, np.int64))
    levels = np.full(len(up), -1, np.int64)
    open_ = np.ones(len(up), bool)
    k = 0
    while open_.any():
        hit = open_ & np.isin(up, roots)
        levels[hit] = k
        open_ &= ~hit
        up[open_] = tree.parent[up[open_]]
        open_ &= up >= 0
        k += 1
    return levels


def _check_min_ascend(min_ascend, tree):
    """A whole number >= 0, clamped to the tree's size, more than its depth (a longer climb
    ends at the axiom all the same)."""
    if isinstance(min_ascend, bool) or not isinstance(min_ascend, (int, np.integer)):
        if not (isinstance(min_ascend, float) and min_ascend.is_integer()):
            raise ValueRefused(f"min_ascend must be a whole number >= 0, not {min_ascend!r}")
    if min_ascend < 0:
        raise ValueRefused(f"min_ascend must be a whole number >= 0, not {min_ascend!r}")
    return int(min(int(min_ascend), tree.size + 1))  # > every depth (climbing stops at the axiom anyway)


def collapse_nested(tree: DerivationTree, roots: ArrayLike) -> np.ndarray:
    """Drop every root that lies under another root."""
    roots = sorted_unique(np.asarray(roots, np.int64))
    if roots.size < 2:
        return roots
    if roots.size <= 256:  # a few roots: walk up from each (a set lookup per ancestor, no pass per level)
        members, parent = set(roots.tolist()), tree.parent
        keep = []
        for r in roots.tolist():
            p = int(parent[r])
            while p >= 0 and p not in members:
                p = int(parent[p])
            keep.append(p < 0)
        return roots[np.array(keep, bool)]
    is_root = np.zeros(tree.size, bool)
    is_root[roots] = True
    inside = np.zeros(roots.size, bool)
    which, current = np.arange(roots.size), tree.parent[roots]
    while which.size:  # climb from every root at once until the axiom or another root
        up = current >= 0
        which, current = which[up], current[up]
        hit = is_root[current]
        inside[which[hit]] = True
        which, current = which[~hit], tree.parent[current[~hit]]
    return roots[~inside]


def ascend(tree: DerivationTree, leaf: int, k: int = 1) -> int:
    """Plain ascension: the ``k``-th ancestor of ``leaf`` (stops at the axiom)."""
    node = int(leaf)
    for _ in range(int(k)):
        parent = int(tree.parent[node])
        if parent < 0:
            break
        node = parent
    return node


def kinship(tree: DerivationTree, leaf: int, n: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Derivation kinship of every leaf to one selected leaf (spec §3.3).

    Returns ``(phi, hue, rgb)`` per leaf of the current string: ``phi`` is the
    order of the first ancestor of ``leaf`` that also holds that leaf (0 for
    the leaf itself; leaves of other axiom modules get ``n``); the hue is
    ``240 * phi / n`` degrees (red = selection, blue = most distant), S = V = 1.
    """
    n = int(tree.depth.max()) if n is None else int(n)
    n = max(n, 1)
    pos = tree.leaf_positions([leaf])[0]
    if pos < 0:
        raise ValueRefused(f"node {leaf} is not a leaf of the current plant")
    first, last = tree.leaf_spans()
    phi = np.full(len(tree.leaves), n, np.int64)
    chain = [int(leaf), *tree.ancestors(leaf).tolist()]
    for j in range(len(chain) - 1, -1, -1):  # widest first, narrower spans overwrite
        v = chain[j]
        phi[first[v] : last[v] + 1] = j
    hue = 240.0 * np.minimum(phi, n) / n
    return phi, hue, hsv_to_rgb(hue)


def hsv_to_rgb(hue: ArrayLike, s: float = 1.0, v: float = 1.0) -> np.ndarray:
    """Hue in degrees (S = V = 1 by default) to RGB in [0, 1], vectorised."""
    h = (np.asarray(hue, float) % 360.0) / 60.0
    c = v * s
    x = c * (1 - np.abs(h % 2 - 1))
    z, full = np.zeros_like(h), np.full_like(h, c)
    sector = np.floor(h).astype(int) % 6
    table = [(full, x, z), (x, full, z), (z, full, x), (z, x, full), (x, z, full), (full, z, x)]
    rgb = np.zeros(h.shape + (3,))
    for k, (r, g, b) in enumerate(table):
        m = sector == k
        rgb[m] = np.stack([r[m], g[m], b[m]], axis=-1)
    return rgb + (v - full)[..., None]
