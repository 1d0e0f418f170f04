"""Built-in environments answering cpfg's ``?E`` modules (see :mod:`ramure.lsys.language.cpfg_environment`).

**honda81** (vlab ``ENVIRO/honda81/honda81.c``, Honda 1981): every ``?E(vigor[, index])`` of the
string is a query at the turtle's position.  A query is answered 0 (cannot grow) when another
query with the same index (the second parameter, default 0) and a vigor at least its own lies
within ``radius`` of it, else 1; the answer replaces the first parameter.  In 3D the distance is
taken in x, y, z; otherwise, as honda81.c does, in x and z.

>>> import numpy as np
>>> honda81(np.array([[0, 0, 0], [0.5, 0, 0], [3, 0, 0]]), np.array([1, 2, 1]), np.zeros(3), 1.0, True).tolist()
[0.0, 1.0, 1.0]
"""

from __future__ import annotations

import numpy as np


def honda81(positions: np.ndarray, vigor: np.ndarray, index: np.ndarray, radius: float, three_d: bool) -> np.ndarray:
    """The answers (0 or 1) of honda81 to queries at ``positions`` (q, 3) with ``vigor`` and ``index``.

    The pairs within ``radius`` come from a k-d tree (:class:`scipy.spatial.cKDTree`), so many
    queries cost about q log q, not the q^2 of honda81.c's double loop."""
    from scipy.spatial import cKDTree

    points = np.asarray(positions, float)[:, [0, 1, 2] if three_d else [0, 2]]
    vigor, index = np.asarray(vigor, float), np.asarray(index, float)
    answers = np.ones(len(points))
    if len(points) < 2:
        return answers
    pairs = cKDTree(points).query_pairs(radius * (1 + 1e-12), output_type="ndarray")
    if len(pairs):
        a, b = pairs[:, 0], pairs[:, 1]
        near = np.sum((points[a] - points[b]) ** 2, axis=1) <= radius * radius  # honda81.c's test, exactly
        same = near & (index[a] == index[b])
        answers[a[same & (vigor[a] <= vigor[b])]] = 0.0  # a stronger (or equal) query blocks
        answers[b[same & (vigor[b] <= vigor[a])]] = 0.0
    return answers
