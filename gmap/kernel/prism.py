"""The labelled prism of order n: its dart template and its default corners.

A prism of order ``n`` (an n-gon extruded along the volume's heading H) has
``12 n`` darts: the base face ``O`` (2n darts), the opposite face ``E``
(2n darts) and ``n`` lateral quads ``C1..Cn`` (8 darts each).

Local dart numbering (``k`` = 0..n-1, ``k1 = (k + 1) % n``):

* ``O``: darts ``2k`` (at base corner k) and ``2k+1`` (at base corner k1), one edge;
* ``E``: darts ``2n + 2k`` and ``2n + 2k + 1``, the same on the top corners;
* ``C(k+1)``: darts ``4n + 8k + j``, ``j`` = 0..7, around the quad
  base k -> base k1 -> top k1 -> top k (bottom, right, top, left edges).

Corners ``0..n-1`` are the base, ``n..2n-1`` the top (corner ``n + k`` above
``k``).  Base corner k sits at angle ``2 pi (k - 1/2) / n`` counter-clockwise
about H in the (L, U) plane, so lateral face ``C(k+1)`` faces the direction at
angle ``2 pi k / n``: ``C1`` faces L.  The polygon's inscribed ellipse has
semi-axes ``L/2`` and ``W/2``; for n = 4 the prism is an exact H x L x W box
(``A(4, ..., N, N, N)`` is a cube of side N, as in the thesis).

>>> t = template(4)
>>> t.alpha.shape, int(t.corner.max())
((3, 48), 7)
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike

#: face label codes: O = 0, E = 1, Ck = k + 1 (k >= 1); I = -1 marks interior
#: faces created by volume subdivision, X = -2 the faces a map cut creates.
FACE_O, FACE_E, FACE_I, FACE_CUT = 0, 1, -1, -2


def face_label_name(code: int) -> str:
    """Name of a face label code: ``0 -> 'O'``, ``1 -> 'E'``, ``3 -> 'C2'``, ``-1 -> 'I'``.

    >>> [face_label_name(c) for c in (0, 1, 2, 5, -1)]
    ['O', 'E', 'C1', 'C4', 'I']
    """
    code = int(code)
    if code == FACE_O:
        return "O"
    if code == FACE_E:
        return "E"
    if code == FACE_I:
        return "I"
    if code == FACE_CUT:
        return "X"
    return f"C{code - 1}"


def face_label_code(name: str) -> int:
    """Inverse of :func:`face_label_name`.

    >>> face_label_code("C3"), face_label_code("E")
    (4, 1)
    """
    name = str(name).strip().upper()
    if name == "O":
        return FACE_O
    if name == "E":
        return FACE_E
    if name == "I":
        return FACE_I
    if name == "X":
        return FACE_CUT
    if name.startswith("C") and name[1:].isdigit() and int(name[1:]) >= 1:
        return int(name[1:]) + 1
    raise ValueError(f"unknown face label {name!r}: expected O, E, I, X or C1, C2, ...")


@dataclass(frozen=True)
class PrismTemplate:
    """Local arrays of one prism of order ``n`` (indices are local dart numbers)."""

    n: int
    alpha: np.ndarray  # (3, 12n) int32: alpha0..alpha2 (alpha3 is free)
    corner: np.ndarray  # (12n,) corner index 0..2n-1 of each dart
    face: np.ndarray  # (12n,) face label code
    fcorner: np.ndarray  # (12n,) index of the dart's corner within its face
    forward: np.ndarray  # (12n,) True when alpha0 leads to the next corner of the face

    @property
    def size(self) -> int:
        return 12 * self.n


@lru_cache(maxsize=64)
def template(n: int) -> PrismTemplate:
    """Dart template of a prism of order ``n`` (cached; arrays are read-only)."""
    n = int(n)
    k = np.arange(n)
    k1 = (k + 1) % n
    size = 12 * n
    a0 = np.empty(size, np.int32)
    a1 = np.empty(size, np.int32)
    a2 = np.empty(size, np.int32)
    corner = np.empty(size, np.int32)
    face = np.empty(size, np.int16)
    fcorner = np.empty(size, np.int16)
    forward = np.zeros(size, bool)
    for off, ring, code in ((0, 0, FACE_O), (2 * n, n, FACE_E)):
        d0, d1 = off + 2 * k, off + 2 * k + 1
        a0[d0], a0[d1] = d1, d0
        a1[d1], a1[off + 2 * k1] = off + 2 * k1, d1
        corner[d0], corner[d1] = ring + k, ring + k1
        face[d0] = face[d1] = code
        fcorner[d0], fcorner[d1] = k, k1
        forward[d0] = True
    side = 4 * n + 8 * k[:, None] + np.arange(8)[None, :]  # (n, 8)
    for j0, j1 in ((0, 1), (2, 3), (4, 5), (6, 7)):
        a0[side[:, j0]], a0[side[:, j1]] = side[:, j1], side[:, j0]
    for j0, j1 in ((1, 2), (3, 4), (5, 6), (7, 0)):
        a1[side[:, j0]], a1[side[:, j1]] = side[:, j1], side[:, j0]
    pairs = [
        (side[:, 0], 2 * k),
        (side[:, 1], 2 * k + 1),  # bottom edge with O
        (side[:, 5], 2 * n + 2 * k),
        (side[:, 4], 2 * n + 2 * k + 1),  # top edge with E
        (side[:, 2], side[k1, 7]),
        (side[:, 3], side[k1, 6]),  # right edge with next side
    ]
    for x, y in pairs:
        a2[x], a2[y] = y, x
    side_corner = np.stack([k, k1, k1, n + k1, n + k1, n + k, n + k, k], axis=1)
    corner[side] = side_corner
    face[side] = (k + 2)[:, None]
    fcorner[side] = np.array([0, 1, 1, 2, 2, 3, 3, 0])[None, :]
    forward[side[:, [0, 2, 4, 6]]] = True
    arrays: list[np.ndarray] = [np.stack([a0, a1, a2]), corner, face, fcorner, forward]
    for arr in arrays:
        arr.setflags(write=False)
    return PrismTemplate(n, *arrays)


def corners(n: int, origins: ArrayLike, frames: ArrayLike, sizes: ArrayLike) -> np.ndarray:
    """Default corners of prisms of order ``n``, ignoring neighbours.

    ``origins`` (k, 3) is the centre of each base face, ``frames`` (k, 3, 3)
    holds the rows H (heading, the prism axis), L and U, and ``sizes`` (k, 3)
    is (H, L, W): height along H and the base's extents along L and U.
    Returns (k, 2n, 3): base corners then top corners.

    >>> import numpy as np
    >>> c = corners(4, np.zeros((1, 3)), np.eye(3)[None], np.array([[2.0, 1.0, 1.0]]))
    >>> np.round(c[0, [0, 4]], 3).tolist()
    [[0.0, 0.5, -0.5], [2.0, 0.5, -0.5]]
    """
    origins = np.asarray(origins, float).reshape(-1, 3)
    frames = np.asarray(frames, float).reshape(-1, 3, 3)
    sizes = np.asarray(sizes, float).reshape(-1, 3)
    theta = 2 * np.pi * (np.arange(n) - 0.5) / n
    scale = 0.5 / np.cos(np.pi / n)
    local = np.zeros((len(sizes), 2 * n, 3))
    local[:, :n, 1] = sizes[:, 1:2] * (scale * np.cos(theta))[None, :]
    local[:, :n, 2] = sizes[:, 2:3] * (scale * np.sin(theta))[None, :]
    local[:, n:, 1:] = local[:, :n, 1:]
    local[:, n:, 0] = sizes[:, 0:1]
    return origins[:, None, :] + np.einsum("kci,kij->kcj", local, frames)


@lru_cache(maxsize=64)
def unit_corners(n: int) -> np.ndarray:
    """:func:`corners` of one unit prism of order ``n`` at the origin (read-only, kept per order).

    Every prism made without origin, frame or size has these corners (the
    products with the identity frame are exact, so they equal a batch's).
    """
    out = corners(n, np.zeros((1, 3)), np.eye(3)[None], np.ones((1, 3)))[0]
    out.setflags(write=False)
    return out
