"""Per-dart attributes through map rebuilds (subdivision, cuts): the kernel side of the rules.

Operations that edit the map in place (sew, edge / face / volume split)
apply the rules directly (:meth:`GMap3._propagate`).  Operations that
rebuild a new map (surface and volume subdivision, :func:`ramure.gmap.kernel.cut.cut_map`)
describe each new dart by the old dart it comes from and a *kind*:
0 the dart's own corner, 1 its edge's point, 2 its face side's point,
3 its volume's point.  :func:`carried` turns that into the new columns:

* ``copy``: the old dart's value whatever the kind;
* ``interpolate``: kind 0 the old value, 1 the mean of the dart and its
  alpha0 partner (the edge midpoint), 2 the mean over the face side
  ``<a0,a1>``, 3 the mean over the volume's darts;
* ``reset``: kind 0 keeps the old value, other kinds get the fill.

>>> import numpy as np
>>> from ramure.gmap import GMap3
>>> gm = GMap3(); _ = gm.add_prisms(4)
>>> gm.add_dart_data("u", float, rule="interpolate")
>>> gm.dart_data["u"][:] = gm.points[:, 0]          # 0 on O, 1 on E
>>> cols = carried(gm, np.array([0, 0, 8]), np.array([0, 1, 3]))
>>> cols["u"].tolist()
[0.0, 0.0, 0.5]
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel.storage import BUILTIN_RULES

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3

OWN, EDGE, FACE, CELL = 0, 1, 2, 3


def extra_names(gm: GMap3) -> list[str]:
    """Names of the per-dart attributes added with :meth:`GMap3.add_dart_data`."""
    return [n for n in gm.dart_rules() if n not in BUILTIN_RULES]


def _group_mean(keys, values, count):
    flat = values.reshape(len(values), -1).astype(float)
    out: np.ndarray = np.stack([np.bincount(keys, flat[:, j], minlength=count) for j in range(flat.shape[1])], axis=1)
    out /= np.maximum(np.bincount(keys, minlength=count), 1)[:, None]
    return out.reshape((count,) + values.shape[1:])


def carried(gm: GMap3, src: ArrayLike, kind: ArrayLike, names: Sequence[str] | None = None) -> dict[str, np.ndarray]:
    """New columns for darts that come from old darts ``src`` with ``kind`` (see module docstring)."""
    src = np.asarray(src, np.int64)
    kind = np.asarray(kind, np.int64)
    rules = gm.dart_rules()
    names = extra_names(gm) if names is None else names
    out = {}
    side = None
    for name in names:
        col = gm.dart_data[name]
        rule = rules[name]
        if rule == "copy":
            out[name] = col[src].copy()
            continue
        if rule == "reset":
            fill = gm.dart_fill(name)
            vals = col[src].copy()
            vals[kind != OWN] = fill
            out[name] = vals
            continue
        vals = col[src].astype(float)
        e = kind == EDGE
        vals[e] = 0.5 * (col[src[e]] + col[gm.alpha[0][src[e]]])
        f = kind == FACE
        if f.any():
            if side is None:
                side, ns = gm.orbit_ids("01")
            means = _group_mean(side, col, ns)
            vals[f] = means[side[src[f]]]
        c = kind == CELL
        if c.any():
            v = gm.dart_volume.astype(np.int64)
            means = _group_mean(v, col, gm.n_volumes)
            vals[c] = means[v[src[c]]]
        out[name] = vals.astype(col.dtype)
    return out
