"""Leaf ids typed by a user: one parser and one set of messages for every front end.

The desktop window and the notebook both select through
:meth:`ramure.app.model.Explorer.select`; what a user types (``"12, 40-45"``) is read here
(:func:`resolve_ids`), the refusals are worded here (the model's own "not a leaf" too), and the
example a front end shows in its id field is made here from the plant on screen
(:func:`id_example`), so typing the example always selects.

>>> parse_ids("3, 7-9 12;4")
[3, 7, 8, 9, 12, 4]
>>> format_ids([3, 4, 5, 9, 11, 12])
'3-5, 9, 11-12'
>>> id_example([2, 5, 13, 17, 21, 26, 30, 41])
'13, 21-41'
>>> parse_ids("12, x")
Traceback (most recent call last):
...
ramure.errors.ValueRefused: 'x' is not a leaf id or a range like 40-45
"""

from __future__ import annotations

import re
from collections.abc import Iterable

import numpy as np

from ramure.errors import ValueRefused
from ramure.lsys.history.tree import sorted_unique

#: Most ids one typed range may name (a typo such as 0-99999999999 must not exhaust memory).
MAX_RANGE = 100_000


def not_a_leaf(leaf: int) -> str:
    """The refusal for an id that is not a leaf of the plant on screen."""
    return f"{int(leaf)} is not a leaf of the current plant"


def parse_ids(text: str) -> list[int]:
    """Leaf ids typed as ``"12, 40-45 51"``: commas, semicolons or spaces between items,
    ``a-b`` every id from a to b; the order typed is kept.  :func:`resolve_ids` reads the same
    text against a plant (what the front ends use)."""
    return [i for a, b in parse_items(text) for i in range(a, b + 1)]


def runs(ids: Iterable[int]) -> list[tuple[int, int]]:
    """Sorted unique ``ids`` as ``(first, last)`` runs of consecutive numbers."""
    values = np.unique(np.asarray(list(ids), np.int64))
    if not values.size:
        return []
    breaks = np.flatnonzero(np.diff(values) != 1)
    starts = np.r_[values[0], values[breaks + 1]]
    ends = np.r_[values[breaks], values[-1]]
    return list(zip(starts.tolist(), ends.tolist()))


def format_ids(ids: Iterable[int]) -> str:
    """``[3, 4, 5, 9]`` -> ``"3-5, 9"`` (what :func:`parse_ids` reads back)."""
    return ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in runs(ids))


def parse_items(text: str) -> list[tuple[int, int]]:
    """The items typed, each as ``(first, last)`` (``first == last`` for a single id)."""
    items: list[tuple[int, int]] = []
    for token in re.split(r"[\s,;]+", str(text).strip()):
        if not token:
            continue
        m = re.fullmatch(r"(\d+)(?:-(\d+))?", token)
        if m is None:
            raise ValueRefused(f"'{token}' is not a leaf id or a range like 40-45")
        a = int(m.group(1))
        b = int(m.group(2)) if m.group(2) else a
        if b < a:
            raise ValueRefused(f"the range '{token}' goes backwards: write {b}-{a}")
        if b - a >= MAX_RANGE:
            raise ValueRefused(f"the range '{token}' names more than {MAX_RANGE:,} ids")
        items.append((a, b))
    return items


def resolve_ids(text: str, leaves: Iterable[int]) -> list[int]:
    """The leaves a user means by ``text``, given the plant's ``leaves``: a single id must be a
    leaf (else :func:`not_a_leaf`); a range ``a-b`` means the leaves numbered a to b (history
    ids interleave leaves and inner nodes) and is refused only when it holds none.

    >>> resolve_ids("2, 10-20", [2, 5, 13, 17, 40])
    [2, 13, 17]
    >>> resolve_ids("5, 18-30", [2, 5, 13, 17, 40])
    Traceback (most recent call last):
    ...
    ramure.errors.ValueRefused: the range 18-30 holds no leaf of the current plant
    """
    known = sorted_unique(np.asarray(leaves if isinstance(leaves, np.ndarray) else list(leaves), np.int64))
    chosen: list[int] = []
    for a, b in parse_items(text):
        if a == b:
            if not _contains(known, a):
                raise ValueRefused(not_a_leaf(a))
            chosen.append(a)
            continue
        inside = known[np.searchsorted(known, a) : np.searchsorted(known, b, side="right")]
        if not inside.size:
            raise ValueRefused(f"the range {a}-{b} holds no leaf of the current plant")
        chosen.extend(inside.tolist())
    return sorted(set(chosen))


def _contains(sorted_ids, value) -> bool:
    i = int(np.searchsorted(sorted_ids, value))
    return i < sorted_ids.size and int(sorted_ids[i]) == value


def id_example(leaves: Iterable[int], span: int = 4) -> str:
    """An example for an id field made of the plant's own ``leaves`` (e.g. those that draw):
    one leaf and a range from a leaf to the ``span``-th leaf after it (``"17, 40-52"``), so that
    typing the example selects ``span + 1`` leaves."""
    known = sorted_unique(np.asarray(list(leaves), np.int64))
    if not known.size:
        return ""
    if known.size <= span + 1:
        return format_ids(known.tolist()) if known.size < 3 else f"{known[0]}-{known[-1]}"
    single = int(known[known.size // 4])
    start = known.size // 2
    return f"{single}, {int(known[start])}-{int(known[min(start + span, known.size - 1)])}"


__all__ = ["MAX_RANGE", "format_ids", "id_example", "not_a_leaf", "parse_ids", "parse_items", "resolve_ids", "runs"]
