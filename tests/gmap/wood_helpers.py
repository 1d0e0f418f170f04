"""Shared helpers of the wood tests (a uniquely named module: the test folders have no package)."""

from __future__ import annotations

import numpy as np


def contacts(wood) -> tuple[np.ndarray, np.ndarray]:
    """Volume pairs ``(a, b)`` of a wood's map sewn face to face by alpha3 (both directions)."""
    gm = wood.gm
    d = np.arange(gm.n_darts)
    a3 = gm.alpha[3][: gm.n_darts]
    sewn = a3 != d
    return gm.dart_volume[d[sewn]].astype(np.int64), gm.dart_volume[a3[sewn]].astype(np.int64)
