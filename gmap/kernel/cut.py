"""Plane cuts that show the inside of a volumetric model.

:func:`plane_cut` keeps what lies behind a plane (the side opposite its
normal).  ``mode="clip"`` cuts cells exactly (VTK clip), giving a flat face
like a knife; ``mode="cells"`` drops whole cells whose centre is in front, so
the cut face shows the cells themselves.  Cell data (``tissue``, ``label``,
``leaf_id``...) is kept either way.

>>> from ramure.gmap.organs.fruit import build_fruit
>>> grid = plane_cut(build_fruit("round_tomato"), normal="z", origin=(0, 0, 0), mode="cells")
>>> 0 < grid.n_cells < 110
True
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel.errors import ValueRefused
from ramure.gmap.kernel.mapcut import AXES, cut_map, unit_normal

if TYPE_CHECKING:
    import pyvista as pv

    from ramure.gmap.kernel.map3 import GMap3

__all__ = ["cut_map", "parse_plane", "plane_cut", "unit_normal"]


def parse_plane(text: str) -> tuple[tuple[float, float, float], tuple[float, ...]]:
    """``"z=0"`` or ``"x=1.5"`` -> (normal, origin); the normal points along the axis.

    >>> parse_plane("z=2")
    ((0.0, 0.0, 1.0), (0.0, 0.0, 2.0))
    """
    axis, sep, value = str(text).partition("=")
    axis = axis.strip().lower()
    if not sep or axis not in AXES:
        raise ValueRefused(f"cut plane must look like x=VALUE, y=VALUE or z=VALUE, got {text!r}")
    try:
        v = float(value)
    except ValueError:
        raise ValueRefused(f"cut plane value must be a number, got {value.strip()!r}") from None
    if not np.isfinite(v):
        raise ValueRefused(f"cut plane value must be a finite number, got {value.strip()!r}")
    normal = AXES[axis]
    return normal, tuple(v * c for c in normal)


def plane_cut(
    model: GMap3 | pv.UnstructuredGrid, normal: str | ArrayLike = "z", origin: ArrayLike | None = None, mode: str = "clip"
) -> pv.UnstructuredGrid:
    """Keep the part of ``model`` (a GMap3 or an UnstructuredGrid) behind the plane.

    ``origin`` defaults to the centre of the model's bounds.
    """
    from ramure.gmap.kernel.map3 import GMap3
    from ramure.gmap.kernel.pyvista import to_unstructured_grid

    grid = to_unstructured_grid(model) if isinstance(model, GMap3) else model
    n = unit_normal(normal)
    o = np.asarray(grid.center if origin is None else origin, float).reshape(3)
    if mode == "cells":
        centres = grid.cell_centers().points
        keep = (centres - o) @ n <= 0
        return grid.extract_cells(np.flatnonzero(keep))  # type: ignore[arg-type]  # pyvista stubs want int64
    if mode == "clip":
        return grid.clip(normal=tuple(n), origin=tuple(o), invert=True)
    raise ValueRefused(f"cut mode must be 'clip' or 'cells', got {mode!r}")
