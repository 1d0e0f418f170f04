"""Exact volumes of a 3-G-map's cells, oriented by the darts (no VTK, no centroid heuristics).

Each face side ``<a0,a1>`` is walked from a dart of orientation class 0
(:func:`ramure.gmap.kernel.topology.orientation_parity`), fan-triangulated from
its vertex centroid, and the signed tetrahedra against the origin are
summed per volume (divergence theorem); a volume whose sum is negative was
walked inside out and takes the absolute value.  Non-planar faces are
measured with that fan, which is also how a VTK clip splits a hexahedron's
faces, so the kept volume of :func:`ramure.gmap.kernel.cut.cut_map` can be checked
against the picture cut.

>>> from ramure.gmap import GMap3
>>> gm = GMap3(); _ = gm.add_prisms(4, sizes=[[2.0, 3.0, 4.0]]); _ = gm.embed()
>>> float(round(volumes(gm)[0], 12))
24.0
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ramure.gmap.kernel.topology import orientation_parity

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3


def volumes(gm: GMap3) -> np.ndarray:
    """Volume of every volume (n_volumes,), from the embedded vertex positions."""
    if gm.n_darts == 0:
        return np.zeros(gm.n_volumes)
    vid, pos = gm.vertex_positions()
    side, ns = gm.orbit_ids("01")
    parity = orientation_parity(gm)
    cand = np.flatnonzero(parity == 0)
    first = np.full(ns, -1, np.int64)
    first[side[cand][::-1]] = cand[::-1]
    first = first[first >= 0]
    walk, length = gm.face_walk(first)
    corners = walk[:, 0::2]
    ok = corners >= 0
    deg = length // 2
    p = np.where(ok[:, :, None], pos[vid[np.maximum(corners, 0)]], 0.0)
    c = p.sum(axis=1) / deg[:, None]
    nxt = (np.arange(corners.shape[1])[None, :] + 1) % deg[:, None]
    q = np.take_along_axis(p, nxt[:, :, None], axis=1)
    ref = pos.mean(axis=0)
    tet = np.einsum("fki,fki->fk", np.cross(p - ref, q - ref), (c - ref)[:, None, :]) / 6.0
    signed = np.bincount(gm.dart_volume[first], np.where(ok, tet, 0.0).sum(axis=1), minlength=gm.n_volumes)
    return np.abs(signed)


def total_volume(gm: GMap3) -> float:
    """Sum of :func:`volumes`."""
    return float(volumes(gm).sum())
