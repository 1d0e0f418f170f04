"""Turtle frames: rows H (heading), L (left), U (up), with H x L = U.

A volume's attribute angles ``(atx, aty, atz)`` (degrees) turn its frame the
LOGO way: ``atx`` rolls about H, ``aty`` pitches about L, ``atz`` turns about
U.  The thesis does not fix the order; we apply roll, then pitch, then turn,
each about the axes of the frame as it stands (intrinsic rotations), and a
positive turn carries H towards L, as the turtle's ``+`` does.

>>> import numpy as np
>>> f = rotate(np.eye(3), atz=90.0)
>>> np.round(f, 6).tolist()   # H became the old L, L the old -H
[[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def _axis_rotation(frames, angle_deg, a, b):
    """Rotate rows ``a`` towards ``b`` by ``angle_deg`` in every frame (vectorised)."""
    t = np.radians(np.asarray(angle_deg, float))
    c, s = np.cos(t)[..., None], np.sin(t)[..., None]
    out = frames.copy()
    out[..., a, :] = c * frames[..., a, :] + s * frames[..., b, :]
    out[..., b, :] = -s * frames[..., a, :] + c * frames[..., b, :]
    return out


def rotate(frames: ArrayLike, atx: ArrayLike = 0.0, aty: ArrayLike = 0.0, atz: ArrayLike = 0.0) -> np.ndarray:
    """Return ``frames`` (…, 3, 3) rolled by ``atx``, pitched by ``aty``, turned by ``atz``.

    Roll (about H) carries L towards U; pitch (about L) carries U towards H;
    turn (about U) carries H towards L.

    >>> import numpy as np
    >>> np.allclose(rotate(rotate(np.eye(3), atx=30), atx=-30), np.eye(3))
    True
    """
    frames = np.asarray(frames, float)
    out = _axis_rotation(frames, atx, 1, 2)
    out = _axis_rotation(out, aty, 2, 0)
    return _axis_rotation(out, atz, 0, 1)


def frame_from(heading: ArrayLike, left_hint: ArrayLike) -> np.ndarray:
    """Orthonormal frames whose H is ``heading`` and L is ``left_hint`` made orthogonal.

    >>> import numpy as np
    >>> np.round(frame_from([0, 0, 2], [1, 0, 1]), 6).tolist()
    [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    """
    h = np.asarray(heading, float)
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    left = np.asarray(left_hint, float)
    left = left - np.sum(left * h, axis=-1, keepdims=True) * h
    left = left / np.linalg.norm(left, axis=-1, keepdims=True)
    return np.stack([h, left, np.cross(h, left)], axis=-2)
