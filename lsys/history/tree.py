"""The derivation-history tree, stored as numpy arrays (one row per module ever made).

Every module of every derivation step is a node.  A module rewritten by a rule
gets the successor modules as children (always a contiguous block of ids); a
module that no rule matched keeps its node, it is not copied.  The current
string is therefore exactly the ordered sequence of leaves, held in
:attr:`DerivationTree.leaves`.

Node ids never change: regeneration marks removed nodes dead (``alive`` is
False) and appends new ones, so every id outside a regenerated subtree keeps
meaning the same module.  A child's id is always larger than its parent's and
its ``step`` strictly larger, which lets the bottom-up passes below run one
vectorised pass per derivation step.

>>> t = DerivationTree(max_params=1)
>>> root = t.append([0], [1], [[1.0]], parent=[-1], step=0, rule=-1, index=[0])
>>> kids = t.append([0, 1], [1, 1], [[2.0], [2.0]], parent=[0, 0], step=1, rule=0, index=[0, 1])
>>> t.set_children(root, kids[:1], 2)
>>> t.children(0).tolist(), t.parent[kids].tolist()
([1, 2], [0, 0])
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike

from ..errors import DerivationError


def sorted_unique(values: ArrayLike) -> np.ndarray:
    """``np.unique(values)`` (sorted, flattened), by one sort: numpy 2's ``np.unique`` imports
    ``numpy.ma`` on its first call, about 9 ms of a new process's first edit.

    Values already sorted and unique (a regrow's 650,000 regrown leaves) are only checked, not
    sorted again.

    >>> sorted_unique([3, 1, 3, 2]).tolist()
    [1, 2, 3]
    """
    values = np.asarray(values).ravel()
    if values.size < 2 or bool((values[1:] > values[:-1]).all()):
        return values
    values = np.sort(values)
    keep = np.empty(values.size, bool)
    keep[0] = True
    np.not_equal(values[1:], values[:-1], out=keep[1:])
    return values[keep]


T = TypeVar("T")

# Node ids in ``parent`` and ``child_start`` are int32: a tree holds at most
# LSystem.max_history (60 M) nodes, and int32 saves 8 bytes per node (12 MB at 1.5 M
# nodes, issue 14).  So is the string, ``leaves`` (5.8 MB less at 1.44 M modules, and an
# edit keeps the string before it for undo); the small arrays of ids the tree hands out
# (children, subtree, ancestors) are int64.
_MAX_NODES = int(np.iinfo(np.int32).max)
_FIELDS = {
    "symbol": np.int16,
    "nparams": np.int8,
    "parent": np.int32,
    "step": np.int16,
    "rule": np.int16,
    "index_in_rule": np.int16,
    "child_start": np.int32,
    "child_count": np.int16,
    "alive": np.bool_,
}
# Symbols, rules, slots in a successor and child counts start as int16 (issue 14: 8 bytes per
# node less than int32, 12 MB at 1.57 M nodes): grammars have far fewer than 32,767 symbols and
# rules, and successors that much shorter.  A tree widens one of these fields to int32 the first
# time it is asked to hold a value that does not fit (:meth:`DerivationTree.widen`: a long axiom,
# successor or decomposition, a huge generated grammar), so every grammar derives as before.
WIDENABLE = ("symbol", "rule", "index_in_rule", "child_count")


class DerivationTree:
    """Arrays ``symbol, nparams, params, parent, step, rule, index_in_rule,
    child_start, child_count, alive`` of length :attr:`size`, plus the current
    string :attr:`leaves` (node ids in order)."""

    def __init__(self, max_params: int, capacity: int = 1024) -> None:
        self.max_params = max(int(max_params), 1)
        self.size = 0
        self._cap = 0
        self._dtypes = dict(_FIELDS)  # per tree: a field widens on its own (see WIDENABLE)
        # parameters after the first (see ParamTable): every node's while the tree grows (None
        # once compact, or without any), then only for the nodes that have any
        self._rest: np.ndarray | None = np.zeros((0, self.max_params - 1)) if self.max_params > 1 else None
        self._more_ids = np.zeros(0, np.int32)  # compact: their node ids, ascending
        self._more = np.zeros((0, self.max_params - 1))  # compact: their values (NaN beyond a node's count)
        self._n_more = 0
        self._leaves = np.zeros(0, np.int32)
        self._cache: dict[str, Any] = {}
        self._sums: _LeafSums | None = None  # kept across edits made through detach/attach_sums
        self._reserve(capacity)

    # -- storage -----------------------------------------------------------
    def _reserve(self, need) -> None:
        if need <= self._cap:
            return
        if need > _MAX_NODES:
            raise DerivationError(
                f"a derivation history of {need:,} modules is more than the {_MAX_NODES:,} a tree holds (its node ids are int32)"
            )
        cap = max(need, 2 * self._cap, 1024)
        for name, dtype in self._dtypes.items():
            old = getattr(self, "_" + name, None)
            arr = np.empty(cap, dtype)
            if old is not None:
                arr[: self.size] = old[: self.size]
            setattr(self, "_" + name, arr)
        old = getattr(self, "_param0", None)
        first = np.empty(cap)
        if old is not None:
            first[: self.size] = old[: self.size]
        self._param0 = first
        if self._rest is not None:
            rest = np.empty((cap, self.max_params - 1))
            rest[: self.size] = self._rest[: self.size]
            self._rest = rest
        self._cap = cap

    def compact_params(self) -> None:
        """Keep the parameters after the first only for the nodes that have any (see
        :class:`ParamTable`); a derivation does this once its steps are done.  Nodes appended
        later are kept so too."""
        if self._rest is None:
            return
        rest, self._rest = self._rest, None
        self._n_more = 0
        self._keep_rest(0, rest[: self.size])

    def _write_params(self, start: int, block: ArrayLike) -> None:
        """The parameters of nodes ``start`` to the end (``block``: (size - start, max_params),
        NaN where a node has fewer)."""
        rows = self.size - start
        values = np.broadcast_to(np.asarray(block, float), (rows, self.max_params))
        self._param0[start : self.size] = values[:, 0]
        if self._rest is not None:  # still dense
            self._rest[start : self.size] = values[:, 1:]
        elif self.max_params > 1:
            self._keep_rest(start, values[:, 1:])

    def _more_before(self, node: int) -> int:
        """How many of the kept later parameters belong to nodes below ``node``."""
        n = self._n_more
        if n == 0 or self._more_ids[n - 1] < node:  # the usual case: nodes appended at the end
            return n
        return int(np.searchsorted(self._more_ids[:n], np.int32(node)))  # int32: no copy of the ids

    def _keep_rest(self, start: int, rest: np.ndarray) -> None:
        """Keep ``rest``, the later parameters of the nodes from ``start`` to the end, for the
        rows that have any; what was kept for those nodes before is dropped."""
        n = self._more_before(start)
        if rest.shape[1] == 1:  # the usual two-parameter table: one pass over the column
            second = rest[:, 0]
            have = np.flatnonzero(second == second)  # not NaN
        else:
            have = np.flatnonzero(~np.isnan(rest).all(axis=1))
        need = n + len(have)
        if need > len(self._more_ids):
            cap = max(need, 2 * len(self._more_ids), 1024)
            ids, more = np.empty(cap, np.int32), np.empty((cap, self.max_params - 1))
            ids[:n], more[:n] = self._more_ids[:n], self._more[:n]
            self._more_ids, self._more = ids, more
        self._more_ids[n:need] = have + start
        self._more[n:need] = rest[have]
        self._n_more = need

    def widen(self, name: str, low: int, high: int) -> None:
        """Make the field ``name`` (one of :data:`WIDENABLE`) able to hold every value from ``low``
        to ``high``: an int16 field that cannot becomes int32 (one copy of its used part); past
        int32 a :class:`DerivationError` says which field and value.  Whoever writes a field
        through its public view calls this first: numpy would wrap a value that does not fit."""
        if name not in WIDENABLE:
            raise ValueError(f"{name!r} is not a field a tree widens (one of {', '.join(WIDENABLE)})")
        low, high = int(low), int(high)
        if _fits(self._dtypes[name], low, high):
            return
        if not _fits(np.int32, low, high):
            value = high if high > np.iinfo(np.int32).max else low
            raise DerivationError(f"the history tree cannot store {value:,} as a node's {name} (int32 at most)")
        old = self.__dict__["_" + name]
        wide = np.empty(self._cap, np.int32)  # the headroom stays untouched (no resident pages)
        wide[: self.size] = old[: self.size]
        setattr(self, "_" + name, wide)
        self._dtypes[name] = np.int32

    def _widen_for(self, name, values) -> None:
        """:meth:`widen` ``name`` for the values about to be written (an array or a scalar)."""
        values = np.asarray(values)
        if values.size and values.dtype.kind in "iu" and not np.can_cast(values.dtype, self._dtypes[name]):
            self.widen(name, values.min(), values.max())

    @property
    def leaves(self) -> np.ndarray:
        """The current string: node ids in order, int32 (node ids stay below 2^31)."""
        return self._leaves

    @leaves.setter
    def leaves(self, ids: ArrayLike) -> None:
        # the very array when it is int32 already (an undo swaps back the one it kept)
        self._leaves = np.asarray(ids).astype(np.int32, copy=False)

    def __getattr__(self, name):
        # Public views trimmed to the used size: tree.parent, tree.symbol, ...
        if name in _FIELDS:
            return self.__dict__["_" + name][: self.__dict__["size"]]
        raise AttributeError(name)

    @property
    def params(self) -> ParamTable:
        """The nodes' parameters, read as a (size, max_params) float array (see :class:`ParamTable`)."""
        return ParamTable(self)

    def __len__(self) -> int:
        return self.size

    def append(
        self,
        symbol: Sequence[int] | np.ndarray,
        nparams: ArrayLike,
        params: ArrayLike,
        parent: ArrayLike,
        step: ArrayLike,
        rule: ArrayLike,
        index: ArrayLike,
    ) -> np.ndarray:
        """Append nodes (arrays of equal length, scalars broadcast); return their ids."""
        count = len(symbol)
        start = self.size
        for name, values in (("symbol", symbol), ("rule", rule), ("index_in_rule", index)):
            self._widen_for(name, values)
        self._reserve(start + count)
        ids = np.arange(start, start + count, dtype=np.int64)
        sl = slice(start, start + count)
        self._symbol[sl] = symbol
        self._nparams[sl] = nparams
        self._parent[sl] = parent
        self._step[sl] = step
        self._rule[sl] = rule
        self._index_in_rule[sl] = index
        self._child_start[sl] = -1
        self._child_count[sl] = 0
        self._alive[sl] = True
        self.size = start + count
        self._write_params(start, params)
        self._dropped()
        return ids

    def extend(self, count: int, step: int) -> int:
        """Make room for ``count`` new nodes of ``step``; returns the first new id.

        The new nodes are alive, childless and of ``step``; the caller writes
        their ``symbol, nparams, params, parent, rule, index_in_rule`` through the
        public views (``tree.symbol[start:] = ...``), which now include them.
        """
        start = self.size
        self._reserve(start + count)
        sl = slice(start, start + count)
        self._step[sl] = step
        self._child_start[sl] = -1
        self._child_count[sl] = 0
        self._alive[sl] = True
        self.size = start + count
        self._dropped()
        return start

    def set_children(self, nodes: ArrayLike, first_child: ArrayLike, count: ArrayLike) -> None:
        """Record that ``nodes`` were rewritten into blocks starting at ``first_child``."""
        self._widen_for("child_count", count)
        self._child_start[nodes] = first_child
        self._child_count[nodes] = count
        self._dropped()

    def changed(self) -> None:
        """Forget cached spans/depths after an in-place edit."""
        self._dropped()

    def _dropped(self) -> None:
        self._cache.clear()
        self._sums = None

    def set_alive(self, nodes: ArrayLike, alive: bool = True) -> None:
        """Mark ``nodes`` alive (or dead, removed by a regeneration); caches are dropped."""
        self._alive[np.asarray(nodes, np.int64)] = bool(alive)
        self._dropped()

    def truncate(self, size: int) -> None:
        """Forget every node appended at or after id ``size`` (a regeneration that failed)."""
        if not 0 <= int(size) <= self.size:
            raise ValueError(f"cannot truncate a tree of {self.size} nodes to {size}")
        self.size = int(size)
        if self._rest is None:
            self._n_more = self._more_before(self.size)
        self._dropped()

    def cached(self, key: str, make: Callable[[], T]) -> T:
        """``make()`` computed once per tree state: the cache is dropped by every edit.

        For per-tree results other modules derive from the public arrays (e.g. the
        min-cut's leaf weights), so they never reach into the tree's private state.
        """
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    #: Trees at least this large use the compiled whole-tree passes (:mod:`._tree_kernel`);
    #: smaller ones too once numba is loaded, but a small tree never loads it.
    kernel_min_nodes = 50_000
    #: True / False force the compiled / numpy passes (tests compare them); None chooses.
    use_kernels = None

    def _compiled(self):
        if self.use_kernels is not None:
            return self.use_kernels
        return self.size >= self.kernel_min_nodes or ("numba" in sys.modules and self.size >= 2_000)

    # -- navigation --------------------------------------------------------
    def children(self, node: int) -> np.ndarray:
        """Ids of a node's children (empty for a leaf)."""
        count = int(self._child_count[node])
        start = int(self._child_start[node])
        return np.arange(start, start + count, dtype=np.int64)

    def is_leaf(self, node: int) -> bool:
        return self._child_count[node] == 0

    def ancestors(self, node: int, k: int | None = None) -> np.ndarray:
        """The parent, grandparent, ... of ``node`` (at most ``k`` of them)."""
        out: list[int] = []
        p = int(self._parent[node])
        while p >= 0 and (k is None or len(out) < k):
            out.append(p)
            p = int(self._parent[p])
        return np.array(out, dtype=np.int64)

    def ancestor(self, nodes: ArrayLike, k: int) -> np.ndarray:
        """The ``k``-th ancestor of each node (vectorised; -1 above a root).

        ``k`` may be huge (a session's ``min_ascend``): the walk stops once every
        node has gone above its root, so it costs at most the tree's depth.
        """
        nodes = np.asarray(nodes, np.int64).copy()
        for _ in range(max(int(k), 0)):
            ok = nodes >= 0
            if not ok.any():
                break
            nodes[ok] = self._parent[nodes[ok]]
        return nodes

    @property
    def depth(self) -> np.ndarray:
        """Depth of every node (roots 0), one vectorised pass per step."""
        if "depth" not in self._cache and self._compiled():
            from ._tree_kernel import depth as kernel_depth

            self._cache["depth"] = kernel_depth(self.parent, self.alive)
        if "depth" not in self._cache:
            depth = np.zeros(self.size, np.int32)
            for nodes in self.nodes_by_step()[1:]:
                depth[nodes] = depth[self.parent[nodes]] + 1
            self._cache["depth"] = depth
        return self._cache["depth"]

    def nodes_by_step(self) -> list:
        """Alive node ids grouped by creation step: list index = step (cached)."""
        if "by_step" not in self._cache:
            alive = np.flatnonzero(self.alive)
            steps = self.step[alive]
            order = np.argsort(steps, kind="stable")
            alive, steps = alive[order], steps[order]
            top = int(steps[-1]) if len(steps) else 0
            cuts = np.searchsorted(steps, np.arange(top + 2))
            self._cache["by_step"] = [alive[cuts[s] : cuts[s + 1]] for s in range(top + 1)]
        return self._cache["by_step"]

    def leaf_spans(self) -> tuple[np.ndarray, np.ndarray]:
        """``(first, last)`` leaf positions under every node (-1 for dead nodes).

        Leaves under a node are contiguous in the string, so a node's leaves are
        ``tree.leaves[first[v]:last[v] + 1]``.
        """
        if "spans" not in self._cache and self._compiled():
            from ._tree_kernel import leaf_spans

            self._cache["spans"] = leaf_spans(self.parent, self.alive, self.leaves)
        if "spans" not in self._cache:
            first = np.full(self.size, np.iinfo(np.int64).max, np.int64)
            last = np.full(self.size, -1, np.int64)
            pos = np.arange(len(self.leaves), dtype=np.int64)
            first[self.leaves] = pos
            last[self.leaves] = pos
            for nodes in reversed(self.nodes_by_step()[1:]):
                np.minimum.at(first, self.parent[nodes], first[nodes])
                np.maximum.at(last, self.parent[nodes], last[nodes])
            first[last < 0] = -1
            self._cache["spans"] = (first, last)
        return self._cache["spans"]

    def leaf_counts(self) -> np.ndarray:
        """Number of current leaves under every node (1 for a leaf, 0 if dead); cached, read-only."""
        if "counts" not in self._cache:
            first, last = self.leaf_spans()
            counts = np.where(last >= 0, last - first + 1, 0)
            counts.flags.writeable = False
            self._cache["counts"] = counts
        return self._cache["counts"]

    # -- leaf sums, kept across edits (issue 14: a regrow costs what it touches) ----------
    def subtree_weights(self, nodes: ArrayLike) -> tuple[np.ndarray, np.ndarray | None]:
        """``(counts, weights)`` of ``nodes``: the current string's leaves below each node, and
        ``sum(2**(depth(leaf) - depth(node)))`` over them (the min-cut's capacity without a
        selection: a leaf 1, an internal node twice the sum of its children); 0 for dead nodes.

        ``weights`` is None when int64 could overflow (``2**step`` times the tree's size reaches
        2**62); the caller then sums exact integers itself.  Both come from per-node sums that an
        edit through :meth:`detach_sums` / :meth:`attach_sums` (a regrow, its undo and redo)
        updates under the regrown roots only; any other edit drops them.
        """
        nodes = np.asarray(nodes, np.int64)
        sums = self._leaf_sums()
        alive = self._alive[nodes]
        count, weight = sums.of(nodes, self._child_count)
        counts = np.where(alive, count, 0)
        weights = np.where(alive, weight, 0) if sums.exact else None
        return counts, weights

    def string_spans(self, nodes: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """``leaf_spans()`` at ``nodes`` only: ``(first, last)`` string positions of their leaves
        (-1, -1 without leaves), from the leaf counts of their ancestors' earlier siblings,
        without a pass over the whole tree."""
        nodes = np.asarray(nodes, np.int64)
        if "spans" in self._cache:
            first, last = self._cache["spans"]
            return first[nodes].copy(), last[nodes].copy()
        sums, alive, child_count = self._leaf_sums(), self._alive, self._child_count
        axiom = self.axiom_modules()
        before = np.zeros(len(axiom) + 1, np.int64)
        np.cumsum(sums.of(axiom, child_count)[0], out=before[1:])
        # the earlier siblings of each node and of its ancestors: one block of ids per step up
        owner, starts, stops = [], [], []
        tops = np.zeros(len(nodes), np.int64)
        for i, v in enumerate(nodes.tolist()):
            node, parent = v, int(self._parent[v])
            while parent >= 0:
                owner.append(i)
                starts.append(int(self._child_start[parent]))
                stops.append(node)
                node, parent = parent, int(self._parent[parent])
            tops[i] = node
        sizes = np.maximum(np.array(stops, np.int64) - np.array(starts, np.int64), 0)  # a dead child: none
        siblings = concat_ranges(np.array(starts, np.int64), sizes)
        whose = np.repeat(np.array(owner, np.int64), sizes)
        held = alive[siblings]
        first = np.zeros(len(nodes), np.int64)
        np.add.at(first, whose[held], sums.of(siblings[held], child_count)[0])  # all in one lookup
        first += before[np.searchsorted(axiom, tops)]
        n = np.where(alive[nodes], sums.of(nodes, child_count)[0], 0)
        return np.where(n > 0, first, -1), np.where(n > 0, first + n - 1, -1)

    def in_string(self, nodes: ArrayLike) -> np.ndarray:
        """Whether each node is a module of the current string (ids must be nodes of the tree)."""
        nodes = np.asarray(nodes, np.int64)
        sums = self._sums
        if sums is not None and sums.size == self.size:
            return self._alive[nodes] & (self._child_count[nodes] == 0) & (sums.flag[nodes] == 1)

        def make():
            mask = np.zeros(self.size, bool)
            mask[self.leaves] = True
            mask.flags.writeable = False
            return mask

        return self.cached("in_string", make)[nodes]

    def axiom_modules(self) -> np.ndarray:
        """Alive nodes without a parent (the axiom's modules), in id (string) order."""
        sums = self._leaf_sums()
        return sums.axiom[self._alive[sums.axiom]]

    def depth_of(self, nodes: ArrayLike) -> np.ndarray:
        """``depth[nodes]`` by walking up from these nodes only (the whole array when cached)."""
        nodes = np.asarray(nodes, np.int64)
        if "depth" in self._cache:
            return self._cache["depth"][nodes]
        out = np.zeros(len(nodes), np.int32)
        up = self._parent[nodes].astype(np.int64)
        while (up >= 0).any():
            more = up >= 0
            out += more
            up[more] = self._parent[up[more]]
        return np.where(self._alive[nodes], out, 0).astype(np.int32)

    def detach_sums(self) -> Any:
        """Take the leaf sums out of the tree before an in-place edit (None if none were made);
        give them back with :meth:`attach_sums` once the edit is done, or drop them."""
        sums, self._sums = self._sums, None
        return sums

    def attach_sums(
        self, sums: Any, roots: ArrayLike, revived: ArrayLike = (), new_leaves: Sequence[np.ndarray] | None = None
    ) -> None:
        """Put back sums taken by :meth:`detach_sums` after an edit that gave ``roots`` new
        children and set :attr:`leaves`: the nodes appended since (all alive) are summed with
        ``new_leaves`` (the arrays of new string modules the edit made, or None to find them in
        the string), then the roots and their ancestors.  ``revived`` (nodes marked alive again)
        keep the sums they had when they were alive; sums of nodes that were already dead when
        the sums were first made are not known, so reviving one drops the sums instead."""
        if sums is None:
            return
        revived = np.asarray(revived, np.int64)
        if revived.size and np.isin(revived, sums.dead_at_start).any():
            return
        roots = np.asarray(roots, np.int64)
        given = None if new_leaves is None else np.concatenate([np.asarray(p, np.int64) for p in new_leaves] or [roots[:0]])
        lo = sums.size
        if self.size > lo:
            fresh = self.leaves[self.leaves >= lo] if given is None else given[given >= lo]
            sums.grow(self.size)
            sums.flag[lo : self.size] = 0
            sums.flag[fresh] = 1
            if not self._sum_range(sums, lo, self.size):
                return  # an inner node without its entry: dropped, made again when asked
            sums.axiom = np.concatenate([sums.axiom, lo + np.flatnonzero(self.parent[lo:] < 0)])
            sums.max_step = max(sums.max_step, int(self.step[lo:].max()))
        sums.size = self.size
        sums.exact = _weights_fit(sums.max_step, self.size)
        leaf_roots = roots[(self._child_count[roots] == 0) & self._alive[roots]]
        if leaf_roots.size:  # a pruned root: 1 when the string holds it
            sums.flag[leaf_roots] = np.isin(leaf_roots, self.leaves if given is None else given)
        sums.add_inner(sorted_unique(roots[self._child_count[roots] > 0]))  # a leaf regrown: inner now
        if self._resum(sums, roots):
            self._sums = sums

    def _leaf_sums(self) -> _LeafSums:
        if self._sums is None or self._sums.size != self.size:
            inner = np.flatnonzero(self._child_count[: self.size] > 0).astype(np.int32)
            sums = _LeafSums(max(self.size, self._cap), inner)  # the tree's headroom: zeroed pages cost nothing until used
            sums.flag[self.leaves] = 1
            made = self._sum_range(sums, 0, self.size, inner_known=True)
            assert made, "every node with children has an entry"  # by construction
            sums.size = self.size
            sums.axiom = np.flatnonzero(self.parent < 0)
            sums.max_step = int(self.step.max()) if self.size else 0
            sums.exact = _weights_fit(sums.max_step, self.size)
            sums.dead_at_start = np.flatnonzero(~self.alive)  # ids (few, often none), not a mask of every node
            self._sums = sums
        return self._sums

    def _sum_range(self, sums, lo, hi, inner_known=False) -> bool:
        """Sums of nodes ``lo .. hi - 1`` from their children (all at larger ids; childless nodes
        hold their flags already).  Those with children get entries, after every id held
        (``inner_known``: they have them).  False when a node with children has no entry (an
        edit the sums did not follow)."""
        if not inner_known:
            sums.add_inner((lo + np.flatnonzero(self._child_count[lo:hi] > 0)).astype(np.int32))
        if self._compiled():
            from ._tree_kernel import leaf_sums

            n = sums.n_inner
            return bool(
                leaf_sums(
                    self._child_start, self._child_count, self._alive, lo, hi, sums.flag, sums.inner[:n], sums.count, sums.weight
                )
            )
        # numpy: dense sums of the range, by step from the deepest, then kept for its inner nodes
        ids = np.arange(lo, hi)
        flag = sums.flag[lo:hi].astype(np.int64)
        count, weight = flag.copy(), flag.copy()
        inner = self._child_count[lo:hi] > 0
        count[inner] = weight[inner] = 0
        parent = self._parent[lo:hi].astype(np.int64)
        alive = self._alive
        up = (parent >= lo) & (alive[lo:hi] | ~alive[np.maximum(parent, 0)])
        steps = self._step[lo:hi]
        for s in sorted_unique(steps[up])[::-1]:
            kids = ids[up & (steps == s)]
            np.add.at(count, parent[kids - lo] - lo, count[kids - lo])
            np.add.at(weight, parent[kids - lo] - lo, 2 * weight[kids - lo])
        pos = sums.position(ids[inner])
        sums.count[pos], sums.weight[pos] = count[inner], weight[inner]
        return True

    def _resum(self, sums, roots) -> bool:
        """Sums of ``roots`` and all their ancestors again, from their children (deepest first);
        False when one of them, or a child of one, has children but no entry."""
        chain = set()
        for v in roots.tolist():
            while v >= 0 and v not in chain:
                chain.add(v)
                v = int(self._parent[v])
        order = np.array(sorted(chain, reverse=True), np.int64)
        order = order[self._child_count[order] > 0]  # childless roots keep their flags
        if self._compiled():
            from ._tree_kernel import resum

            n = sums.n_inner
            return bool(
                resum(
                    order, self._child_start, self._child_count, self._alive, sums.flag, sums.inner[:n], sums.count, sums.weight
                )
            )
        alive = self._alive
        for v, i in zip(order.tolist(), sums.position(order).tolist()):
            block = np.arange(int(self._child_start[v]), int(self._child_start[v]) + int(self._child_count[v]))
            block = block[alive[block] | (not alive[v])]
            if not sums.held(np.r_[v, block[self._child_count[block] > 0]]).all():
                return False
            count, weight = sums.of(block, self._child_count)
            sums.count[i], sums.weight[i] = int(count.sum()), 2 * int(weight.sum())
        return True

    def leaves_under(self, node: int) -> np.ndarray:
        """Leaf node ids under ``node`` in string order."""
        first, last = self.leaf_spans()
        if last[node] < 0:
            return np.zeros(0, np.int64)
        return self.leaves[first[node] : last[node] + 1]

    def leaf_positions(self, nodes: ArrayLike) -> np.ndarray:
        """Position of each node in the current string, -1 for a node that is not in it; raises
        for ids out of range.  A few nodes (at most 256: a click, a regrow's picks) are found
        from the leaf sums (:meth:`string_spans`), without a table over the whole tree."""
        nodes = np.asarray(nodes, np.int64)
        if nodes.size and (nodes.min() < 0 or nodes.max() >= self.size):
            raise IndexError("node id out of range")
        if nodes.size <= 256 and self._sums is not None and self._sums.size == self.size:
            first, _ = self.string_spans(nodes)
            return np.where(self.in_string(nodes), first, -1)
        pos = np.full(self.size, -1, np.int64)
        pos[self.leaves] = np.arange(len(self.leaves))
        if nodes.size and (nodes.min() < 0 or nodes.max() >= self.size):
            raise IndexError("node id out of range")
        return pos[nodes]

    def subtree(self, node: int) -> np.ndarray:
        """All alive descendants of ``node`` (not the node itself), breadth first."""
        out, frontier = [], np.array([node], np.int64)
        while frontier.size:
            counts = self._child_count[frontier]
            starts = self._child_start[frontier]
            frontier = concat_ranges(starts[counts > 0], counts[counts > 0])
            out.append(frontier)
        return np.concatenate(out) if out else np.zeros(0, np.int64)


class ParamTable:
    """A tree's parameters as a ``(size, max_params)`` float array, NaN where a node has fewer:
    ``params[rows]``, ``params[rows, j]``, ``params[rows, :k]``, ``params[:, 0]`` (the first
    parameter of every node, a view), ``np.asarray(params)`` (the whole table, a copy); written
    for the nodes at the end only, ``params[start:] = rows``.

    Stored by column: every node's first parameter; the others of every node while the tree
    grows (a derivation reads and writes them at full speed), and once it is done
    (:meth:`DerivationTree.compact_params`, which :meth:`ramure.lsys.LSystem.derive` calls)
    only for the nodes that have any: their ids, ascending, and values.  Honda sympodial
    n = 17 has 1.57 M nodes, of which 786k have no parameter and 262k have two: 3 MB for the
    second parameters instead of 12.6 MB.  A compact table reads a later column for a few rows
    by looking them up among those ids (a binary search; an edit reads a few hundred), and for
    many rows (more than an eighth of the nodes: a whole string) through the column made dense
    for that read."""

    def __init__(self, tree: DerivationTree) -> None:
        self.tree = tree

    @property
    def shape(self) -> tuple[int, int]:
        return (self.tree.size, self.tree.max_params)

    @property
    def ndim(self) -> int:
        return 2

    @property
    def dtype(self) -> np.dtype:
        return np.dtype(float)

    def __len__(self) -> int:
        return self.tree.size

    @property
    def nbytes(self) -> int:
        """Bytes the table's used rows take (the first column, the later ones kept)."""
        tree = self.tree
        if tree._rest is not None:
            return 8 * tree.size * tree.max_params
        return 8 * tree.size + (4 + 8 * (tree.max_params - 1)) * tree._n_more

    def __array__(self, dtype: Any = None, copy: Any = None) -> np.ndarray:
        table = self[:]
        return table if dtype is None else table.astype(dtype)

    def __getitem__(self, key: Any) -> Any:
        rows, cols = key if isinstance(key, tuple) else (key, slice(None))
        if isinstance(rows, tuple) or (isinstance(key, tuple) and len(key) != 2):
            raise IndexError("a parameter table is indexed by rows, or by rows and columns")
        if isinstance(cols, (int, np.integer)):
            return self.column(int(cols), rows)
        if not isinstance(cols, slice):
            raise IndexError("a parameter table's columns are one index or a slice")
        columns = [self.column(j, rows) for j in range(*cols.indices(self.tree.max_params))]
        if not columns:
            return np.zeros((*np.shape(self.column(0, rows)), 0))
        return np.stack(columns, axis=-1)

    def __setitem__(self, key: Any, value: ArrayLike) -> None:
        tree = self.tree
        if not isinstance(key, slice) or key.step not in (None, 1) or key.indices(tree.size)[1] != tree.size:
            raise TypeError("a tree's parameters are written for the nodes at the end: params[start:] = rows")
        tree._write_params(key.indices(tree.size)[0], np.asarray(value, float))

    def column(self, j: int, rows: Any = slice(None)) -> Any:
        """Parameter ``j`` (from 0) of ``rows`` (an index, a slice, ids or a mask), NaN where
        a node has fewer; ``column(0)`` is a view of the tree's own column."""
        tree = self.tree
        if not -tree.max_params <= j < tree.max_params:
            raise IndexError(f"parameter {j} of a tree of {tree.max_params}")
        j %= tree.max_params
        if j == 0:
            return tree._param0[: tree.size][rows]
        if tree._rest is not None:
            return tree._rest[: tree.size, j - 1][rows]
        ids = _row_ids(rows, tree.size)
        n = tree._n_more
        known = tree._more_ids[:n]
        if n == 0:
            out = np.full(np.shape(ids), np.nan)
        elif np.size(ids) > tree.size // 8:  # many rows (a whole string): the column made dense, once
            column = np.full(tree.size, np.nan)
            column[known] = tree._more[:n, j - 1]
            out = column[ids]
        else:
            pos = np.minimum(np.searchsorted(known, ids.astype(np.int32)), n - 1)  # int32: no copy of the ids kept
            out = np.where(known[pos] == ids, tree._more[pos, j - 1], np.nan)
        return out[()] if np.ndim(ids) == 0 else out


def _row_ids(rows: Any, size: int) -> np.ndarray:
    """``rows`` of a table of ``size`` rows as ids (negative ones counted from the end, as numpy
    does; out of range: IndexError)."""
    if isinstance(rows, slice):
        return np.arange(*rows.indices(size))
    ids = np.asarray(rows)
    if ids.dtype == bool:
        if ids.shape != (size,):
            raise IndexError(f"a mask of {ids.shape} for {size} rows")
        return np.flatnonzero(ids)
    if ids.size:
        low, high = int(ids.min()), int(ids.max())
        if low < -size or high >= size:
            raise IndexError(f"row {high if high >= size else low} of {size}")
        if low < 0:
            return np.where(ids < 0, ids + size, ids)
    return ids


class _LeafSums:
    """Per-node leaf counts and weights (see :meth:`DerivationTree.subtree_weights`), valid for
    nodes below ``size``; dead nodes keep what they had when alive (an undo revives them).

    A childless node's count and weight are both its in-string ``flag`` (int8, one per node).
    Only the *inner* nodes (those that had children when summed: about one node in twelve on
    Honda sympodial) keep a count and a weight of their own, in ``count`` and ``weight`` at the
    position of their id in ``inner`` (ascending int32).  An inner node that an edit leaves
    childless keeps its entry, unused while childless.  At 1.57 M nodes this is 3 MB instead
    of 19 MB of dense int32 counts and int64 weights."""

    def __init__(self, size: int, inner: np.ndarray) -> None:
        self.flag = np.zeros(max(int(size), 1024), np.int8)  # zeroed pages cost nothing until used
        cap = max(2 * len(inner), 1024)  # headroom: a regrow appends without a copy
        self.inner = np.zeros(cap, np.int32)
        self.count = np.zeros(cap, np.int32)
        self.weight = np.zeros(cap, np.int64)
        self.n_inner = len(inner)
        self.inner[: len(inner)] = inner
        self.size = 0
        self.axiom = np.zeros(0, np.int64)
        self.max_step = 0
        self.exact = True
        self.dead_at_start = np.zeros(0, np.int64)  # ids of the nodes already dead when the sums were made

    def grow(self, size: int) -> None:
        """Room for ``size`` nodes' flags."""
        if size > len(self.flag):
            flag = np.zeros(max(size, 2 * len(self.flag)), np.int8)
            flag[: len(self.flag)] = self.flag
            self.flag = flag

    def add_inner(self, nodes: np.ndarray) -> None:
        """Give ``nodes`` (ascending) an entry each, where they have none yet (zeros)."""
        fresh = ~self.held(nodes)
        nodes, pos = nodes[fresh], self.position(nodes[fresh])
        if not nodes.size:
            return
        need = self.n_inner + len(nodes)
        if need > len(self.inner) or pos[0] < self.n_inner:  # an insertion: one copy of the used part
            cap = max(need, 2 * len(self.inner)) if need > len(self.inner) else len(self.inner)
            for name in ("inner", "count", "weight"):
                old = getattr(self, name)[: self.n_inner]
                new = np.zeros(cap, old.dtype)
                new[:need] = np.insert(old, pos, nodes if name == "inner" else 0)
                setattr(self, name, new)
        else:  # the usual case: nodes appended after every id held
            self.inner[self.n_inner : need] = nodes
            self.count[self.n_inner : need] = self.weight[self.n_inner : need] = 0
        self.n_inner = need

    def held(self, nodes: np.ndarray) -> np.ndarray:
        """Whether each of ``nodes`` has an entry."""
        if not self.n_inner:
            return np.zeros(len(nodes), bool)
        return self.inner[np.minimum(self.position(nodes), self.n_inner - 1)] == nodes

    def position(self, nodes: np.ndarray) -> np.ndarray:
        """Where each of ``nodes`` (inner ones) is kept."""
        return np.searchsorted(self.inner[: self.n_inner], nodes.astype(np.int32))  # int32: no copy of the ids

    def of(self, nodes: np.ndarray, child_count: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(count, weight)`` of ``nodes`` as last summed (int64 both)."""
        leaf = child_count[nodes] == 0
        flag = self.flag[nodes].astype(np.int64)
        if not self.n_inner:
            return flag, flag.copy()
        pos = np.minimum(self.position(nodes), self.n_inner - 1)
        return np.where(leaf, flag, self.count[pos]), np.where(leaf, flag, self.weight[pos])


def _fits(dtype, low: int, high: int) -> bool:
    info = np.iinfo(dtype)
    return info.min <= low and high <= info.max


def _weights_fit(max_step: int, size: int) -> bool:
    """Whether ``2**depth``-weighted leaf sums stay below 2**62 (depth <= step)."""
    return max_step + int(size).bit_length() < 62


def concat_ranges(starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Concatenate ``arange(s, s + c)`` for every pair, vectorised."""
    if not len(starts):
        return np.zeros(0, np.int64)
    total = int(counts.sum())
    offsets = np.repeat(starts - np.cumsum(counts) + counts, counts)
    return offsets + np.arange(total, dtype=np.int64)


def leaf_weight_prefix(depth: np.ndarray, leaves: np.ndarray) -> np.ndarray:
    """Prefix sums of ``2**depth[leaves]`` in int64, one compiled pass without a gathered copy
    (numba loads on the first call); the caller checks the sums cannot overflow."""
    from ._tree_kernel import leaf_weight_prefix as compiled

    return compiled(depth, leaves)
