"""Discrete-event scheduling of bud events (AMAP's *échéancier*, Blaise 1991; spec B.4).

Growth events fall at real-valued dates. The scheduler is a time-ordered list of clock ticks
(``tick = floor(date / dt)``); each tick holds **four lists** — new growth unit, new internode,
branching, organ — handled in that order. Within a list, events ascend by **branching order**
(trunk first), and events of equal order are put in a random order drawn from the seed, so no
axis is favoured and the same seed replays the same history. Every node (a bud at the tip of an
internode) is **active**, **paused** or **dead**: a dead node's events are dropped (death adds
no event of its own), a paused node's events wait for the next tick.

Everything is numpy: all pending events are sorted once by (tick, list, order, tie key), and
each tick is a slice of that order; events a handler adds are merged in.

>>> s = EventScheduler(seed=1)
>>> s.add(dates=[0.5, 0.2, 1.5, 0.7], kinds=["internode", "growth_unit", "branching", "internode"],
...       orders=[2, 1, 1, 1], nodes=[10, 11, 12, 13])
>>> [(tick, kind, nodes.tolist()) for tick, kind, nodes, _ in s.run()]
[(0, 'growth_unit', [11]), (0, 'internode', [13, 10]), (1, 'branching', [12])]
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np

from ramure.errors import ValueRefused
from numpy.typing import ArrayLike

KINDS = ("growth_unit", "internode", "branching", "organ")
ACTIVE, PAUSED, DEAD = 0, 1, 2
STATES = {"active": ACTIVE, "paused": PAUSED, "dead": DEAD}


class EventScheduler:
    """Pending events as arrays; :meth:`run` hands them out tick by tick, list by list.

    ``dt`` is the length of one tick in date units (one trunk growth unit: a year for a
    temperate tree). ``seed`` draws the order among events of equal branching order.
    """

    def __init__(self, seed: int = 0, dt: float = 1.0) -> None:
        if not (np.isfinite(dt) and dt > 0):
            raise ValueRefused(f"the tick length dt must be a positive number, not {dt!r}")
        self.dt = float(dt)
        self.rng = np.random.default_rng(seed)
        self._columns = {
            name: np.zeros(0, dtype)
            for name, dtype in (
                ("tick", np.int64),
                ("kind", np.int8),
                ("order", np.int32),
                ("node", np.int64),
                ("date", np.float64),
                ("tie", np.float64),
            )
        }
        self.state = np.zeros(0, np.int8)  # per node id
        self.handled = 0
        self._unsorted = False

    def __len__(self) -> int:
        return len(self._columns["tick"])

    def add(self, dates: ArrayLike, kinds: ArrayLike, orders: ArrayLike, nodes: ArrayLike) -> None:
        """Schedule events (array-likes of one length); refuses bad dates, kinds and orders."""
        dates = np.asarray(dates, np.float64).ravel()
        kinds = _kind_codes(kinds, len(dates))
        orders = np.asarray(orders, np.int64).ravel()
        nodes = np.asarray(nodes, np.int64).ravel()
        if not (len(orders) == len(nodes) == len(dates)):
            raise ValueRefused("dates, kinds, orders and nodes must have the same length")
        if len(dates) and (not np.all(np.isfinite(dates)) or dates.min() < 0):
            bad = dates[~np.isfinite(dates) | (dates < 0)][0]
            raise ValueRefused(f"event dates must be finite and >= 0, not {bad}")
        if len(orders) and orders.min() < 1:
            raise ValueRefused("branching orders start at 1 (the trunk)")
        if len(nodes) and nodes.min() < 0:
            raise ValueRefused("node ids must be >= 0")
        self._grow_states(int(nodes.max()) + 1 if len(nodes) else 0)
        new = {
            "tick": np.floor(dates / self.dt).astype(np.int64),
            "kind": kinds,
            "order": orders.astype(np.int32),
            "node": nodes,
            "date": dates,
            "tie": self.rng.random(len(dates)),
        }
        self._columns = {k: np.concatenate([self._columns[k], new[k]]) for k in self._columns}
        self._unsorted = True

    def set_state(self, nodes: ArrayLike, state: str) -> None:
        """Mark nodes ``"active"``, ``"paused"`` or ``"dead"``."""
        if state not in STATES:
            raise ValueRefused(f"a node state is one of {', '.join(STATES)}, not {state!r}")
        nodes = np.asarray(nodes, np.int64).ravel()
        self._grow_states(int(nodes.max()) + 1 if len(nodes) else 0)
        self.state[nodes] = STATES[state]

    def _grow_states(self, size) -> None:
        if size > len(self.state):
            self.state = np.concatenate([self.state, np.zeros(size - len(self.state), np.int8)])

    def _sorted(self) -> None:
        """Sort the pending events once after each addition (each tick is then a slice)."""
        if self._unsorted:
            c = self._columns
            order = np.lexsort((c["tie"], c["order"], c["kind"], c["tick"]))
            self._columns = {k: v[order] for k, v in c.items()}
            self._unsorted = False

    def run(self, handler: Callable | None = None, until: float = np.inf) -> Iterator:
        """Yield ``(tick, kind, nodes, dates)`` for each non-empty list, in time order.

        ``handler(kind, nodes, dates)`` (optional) may return new events as a tuple
        ``(dates, kinds, orders, nodes)``; they must fall after the current tick.
        """
        while len(self):
            self._sorted()
            c = self._columns
            tick = int(c["tick"][0])
            if tick * self.dt >= until:
                return
            end = int(np.searchsorted(c["tick"], tick, side="right"))
            now = {k: v[:end] for k, v in c.items()}
            self._columns = {k: v[end:] for k, v in c.items()}
            state = self.state[now["node"]]
            waiting = state == PAUSED
            if waiting.any():  # paused nodes try again next tick
                later = {k: v[waiting] for k, v in now.items()}
                later["tick"] = later["tick"] + 1
                self._columns = {k: np.concatenate([later[k], self._columns[k]]) for k in c}
                self._unsorted = True
            alive = state == ACTIVE
            if not alive.any() and waiting.all() and len(self) == int(waiting.sum()):
                return  # only paused nodes are left and nothing can wake them
            bounds = np.searchsorted(now["kind"][alive], np.arange(len(KINDS) + 1))
            nodes, dates = now["node"][alive], now["date"][alive]
            for code, kind in enumerate(KINDS):
                lo, hi = bounds[code], bounds[code + 1]
                if hi == lo:
                    continue
                self.handled += hi - lo
                yield tick, kind, nodes[lo:hi], dates[lo:hi]
                if handler is not None:
                    self._accept(handler(kind, nodes[lo:hi], dates[lo:hi]), tick)

    def _accept(self, new, tick):
        if new is None:
            return
        dates, kinds, orders, nodes = new
        if len(np.atleast_1d(dates)) and np.min(np.floor(np.asarray(dates, float) / self.dt)) <= tick:
            raise ValueRefused("a handler may only schedule events after the current tick")
        self.add(dates, kinds, orders, nodes)


def _kind_codes(kinds, n):
    if isinstance(kinds, str):
        kinds = [kinds] * n
    kinds = np.asarray(kinds)
    if kinds.dtype.kind in "iu":
        if len(kinds) and (kinds.min() < 0 or kinds.max() >= len(KINDS)):
            raise ValueRefused(f"event kinds are 0..{len(KINDS) - 1} ({', '.join(KINDS)})")
        return kinds.astype(np.int8).ravel()
    names, inverse = np.unique(kinds.ravel(), return_inverse=True)
    lookup = {k: i for i, k in enumerate(KINDS)}
    unknown = [str(k) for k in names if str(k) not in lookup]
    if unknown:
        raise ValueRefused(f"unknown event kind {unknown[0]!r} (known: {', '.join(KINDS)})")
    return np.array([lookup[str(k)] for k in names], np.int8)[inverse]
