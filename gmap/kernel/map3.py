"""The 3-G-map: :class:`GMap3`, its storage with the operations on top.

A :class:`GMap3` is ``(B, alpha0, alpha1, alpha2, alpha3)`` (Lienhardt).  What it stores and
reads (darts, involutions, attributes, orbits, cells, validity, embedding) is
:class:`~ramure.gmap.kernel.storage.MapStorage`, whose module describes the layout; the
operations that edit it (prisms, i-sewing, splits, removal) are
:class:`~ramure.gmap.kernel.operations.Operations`, built on that storage.  Each layer is a
real base class of the next, so no layer re-declares what another one defines.

>>> gm = GMap3()
>>> first = gm.add_prisms(4)          # one cube
>>> gm.n_darts, gm.is_valid()
(48, True)
>>> c = gm.counts()
>>> c["vertices"], c["edges"], c["faces"], c["volumes"], gm.euler_characteristic()
(8, 12, 6, 1, 1)
"""

from __future__ import annotations

from ramure.gmap.kernel.operations import Operations

__all__ = ["GMap3"]


class GMap3(Operations):
    """A 3-G-map with numpy storage (see :mod:`ramure.gmap.kernel.storage` for the layout)."""
