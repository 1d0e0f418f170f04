"""Compiled inner loop of the fruit defects (see :mod:`ramure.gmap.organs.defects`): cell volumes.

numba because a cell volume is a short sum over each face's fan of triangles; numpy needs
(faces x degree x 3) temporaries for it, ten times the memory traffic of one pass.
"""

from __future__ import annotations

import numpy as np

from ramure.jit import njit


@njit(cache=True)
def face_fan_volumes(pos, ring, deg, fvol, flip, faces, n_volumes):
    """Signed volume per cell from the face sides ``faces``.

    Each face side ``f`` is the polygon ``pos[ring[f, :deg[f]]]``, fanned from
    its centroid; its tetrahedra against a reference point (the first face's
    first corner) add to cell ``fvol[f]`` with sign ``flip[fvol[f]]``.
    """
    out = np.zeros(n_volumes)
    if faces.size == 0:
        return out
    r0 = pos[ring[faces[0], 0]]
    for i in range(faces.size):
        f = faces[i]
        k = deg[f]
        cx = 0.0
        cy = 0.0
        cz = 0.0
        for j in range(k):
            p = pos[ring[f, j]]
            cx += p[0]
            cy += p[1]
            cz += p[2]
        cx = cx / k - r0[0]
        cy = cy / k - r0[1]
        cz = cz / k - r0[2]
        total = 0.0
        for j in range(k):
            p = pos[ring[f, j]]
            q = pos[ring[f, (j + 1) % k]]
            px, py, pz = p[0] - r0[0], p[1] - r0[1], p[2] - r0[2]
            qx, qy, qz = q[0] - r0[0], q[1] - r0[1], q[2] - r0[2]
            total += (py * qz - pz * qy) * cx + (pz * qx - px * qz) * cy + (px * qy - py * qx) * cz
        c = fvol[f]
        out[c] += flip[c] * total / 6.0
    return out
