"""Faces addressed by label: find a volume's face O, E, C1..Cn (and a sub-label) from per-dart columns.

Every dart carries its face label code (``face``: O = 0, E = 1, Ck = k + 1,
I = -1) and ``sublabel``; operations keep them (an edge split or a sewn
knot turns a quad ``C4`` into a 7-gon, the darts still say ``C4``).  So a
face is found by label, never by template offsets, which break as soon as
old volumes change topology (wood spec, decision 4).

The *anchor* of a face is the dart an operation starts from: among the
face's darts, the forward dart with the smallest stored corner index
(``fcorner``; darts made later have none and come after), ties to the
smaller dart id.  For a fresh prism it is :meth:`GMap3.prism_face` ``(.., 0)``.
When a face label covers several ``<a0,a1>`` orbits (a face split in two
keeps its label in both halves), the anchor is in the half holding the
original corner 0 and :func:`face_darts` returns the darts of all halves.

Queries are batched: one O(n log n) index (cached until the map changes)
answers any number of (volume, label) queries in O(q log n).

>>> from ramure.gmap import GMap3
>>> gm = GMap3(); first = gm.add_prisms(4, 2)
>>> face_of(gm, [0, 1], "C2").tolist() == gm.prism_face(first, 4, "C2").tolist()
True
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel import prism as _prism
from ramure.gmap.kernel.errors import GMapError

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3

_FACE_BITS = 17


def label_code(label: str | int) -> int:
    """Face label code of a name (``'O'``, ``'E'``, ``'C3'``, ``'I'``) or of an int code."""
    if isinstance(label, (int, np.integer)):
        return int(label)
    try:
        return _prism.face_label_code(label)
    except ValueError as exc:
        raise GMapError(str(exc)) from None


def _index(gm):
    """Darts sorted by (volume, face, sublabel, rank, dart), cached on the map."""
    cached = gm.cache.get("face_index")
    if cached is not None:
        return cached
    data = gm.dart_data
    vol = data["volume"].astype(np.int64)
    face = data["face"].astype(np.int64)
    sub = data["sublabel"].astype(np.int64)
    fc = data["fcorner"].astype(np.int64)
    fw = data["forward"]
    key = (vol << _FACE_BITS) | (face + 2)
    # rank: forward darts by face corner, then split darts, then backward darts (17 bits)
    rank = np.where(fw, np.where(fc >= 0, fc, 1 << 15), (1 << 15) + 1)
    kb, sb = int(key.max(initial=0)).bit_length(), int(sub.max(initial=0)).bit_length()
    if kb + sb + 17 <= 63 and sub.min(initial=0) >= 0:  # one stable sort of a packed key
        order = np.argsort((key << (sb + 17)) | (sub << 17) | rank, kind="stable")
    else:
        order = np.lexsort((np.arange(gm.n_darts), rank, sub, key))
    out = (order, key[order], sub[order])
    gm.cache["face_index"] = out
    return out


def _codes(volumes: ArrayLike, label: str | int | Sequence[str | int] | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    volumes = np.atleast_1d(np.asarray(volumes, np.int64))
    if isinstance(label, (str, int, np.integer)):
        codes = np.full(len(volumes), label_code(label), np.int64)
    else:
        codes = np.array([label_code(x) for x in label], np.int64)
        codes = np.broadcast_to(codes, volumes.shape)
    return volumes, codes


def _ranges(gm, volumes, codes, sublabel):
    """``[lo, hi)`` of each query in the sorted index."""
    order, key, sub = _index(gm)
    q = (volumes << _FACE_BITS) | (codes + 2)
    lo = np.searchsorted(key, q, "left")
    hi = np.searchsorted(key, q, "right")
    if sublabel is None:
        return order, lo, hi
    qs = np.broadcast_to(np.asarray(sublabel, np.int64), q.shape)
    a, b = lo.copy(), hi.copy()  # first position with sub >= qs
    while np.any(a < b):
        mid = (a + b) // 2
        less = (a < b) & (sub[np.minimum(mid, len(sub) - 1)] < qs)
        a = np.where(less, mid + 1, a)
        b = np.where(less | (a >= b), b, mid)
    lo2 = a
    a, b = lo2.copy(), hi.copy()  # first position with sub > qs
    while np.any(a < b):
        mid = (a + b) // 2
        le = (a < b) & (sub[np.minimum(mid, len(sub) - 1)] <= qs)
        a = np.where(le, mid + 1, a)
        b = np.where(le | (a >= b), b, mid)
    return order, lo2, a


def face_of(
    gm: GMap3,
    volumes: ArrayLike,
    label: str | int | Sequence[str | int] | np.ndarray,
    sublabel: ArrayLike | None = None,
    missing: str = "raise",
) -> np.ndarray:
    """Anchor dart of face ``label`` of each volume (see the module docstring).

    ``label`` is one name or code for all volumes, or one per volume;
    ``sublabel`` (a code, see :func:`ramure.gmap.sublabel_name`) restricts
    to one child face of a subdivided face.  A volume without that face
    raises :class:`GMapError` naming it, or gives -1 with ``missing="ignore"``.

    >>> from ramure.gmap import GMap3
    >>> gm = GMap3(); _ = gm.add_prisms(4)
    >>> int(face_of(gm, 0, "E")[0]), int(face_of(gm, 0, "C9", missing="ignore")[0])
    (8, -1)
    """
    volumes, codes = _codes(volumes, label)
    if volumes.size and (volumes.min() < 0 or volumes.max() >= gm.n_volumes):
        raise GMapError(f"volume ids must be in 0..{gm.n_volumes - 1}")
    order, lo, hi = _ranges(gm, volumes, codes, sublabel)
    found = lo < hi
    out = np.where(found, order[np.minimum(lo, len(order) - 1)] if len(order) else -1, -1)
    if missing == "raise" and not found.all():
        i = int(np.flatnonzero(~found)[0])
        v = int(volumes[i])
        vd = gm.volume_data
        what = _prism.face_label_name(codes[i]) + ("" if sublabel is None else f" sub-label {sublabel}")
        raise GMapError(f"volume {v} (label {vd['label'][v]}, prism order {int(vd['degree'][v])}) has no face {what}")
    return out.astype(np.int64)


def face_darts(
    gm: GMap3, volumes: ArrayLike, label: str | int | Sequence[str | int], sublabel: ArrayLike | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """All darts of face ``label`` of each volume: ``(darts, which)`` (which = query index).

    Includes every half of a split face.

    >>> from ramure.gmap import GMap3
    >>> gm = GMap3(); _ = gm.add_prisms(4, 2)
    >>> darts, which = face_darts(gm, [0, 1], "O")
    >>> len(darts), which.tolist()[:3]
    (16, [0, 0, 0])
    """
    volumes, codes = _codes(volumes, label)
    order, lo, hi = _ranges(gm, volumes, codes, sublabel)
    n = hi - lo
    which = np.repeat(np.arange(len(volumes)), n)
    pos = np.repeat(lo, n) + (np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n))
    return order[pos].astype(np.int64), which


def face_labels(gm: GMap3, volume: int) -> list[str]:
    """Sorted label names of the faces of one volume, e.g. ``['C1', 'C2', ..., 'E', 'O']``."""
    order, key, _ = _index(gm)
    v = np.int64(volume) << _FACE_BITS
    lo, hi = np.searchsorted(key, [v, v + (1 << _FACE_BITS)])
    codes = np.unique(key[lo:hi] - v - 2)
    return sorted(_prism.face_label_name(c) for c in codes)


def is_free_face(gm: GMap3, darts: ArrayLike) -> np.ndarray:
    """True for each dart whose whole face ``<a0,a1>`` is alpha3-free (orbit-proportional)."""
    walk, _ = gm.face_walk(darts)
    a3 = gm.alpha[3]
    w = np.maximum(walk, 0)
    return np.all((walk < 0) | (a3[w] == w), axis=1)
