"""Growable structure-of-arrays storage used for darts and volumes.

A :class:`Columns` holds named numpy arrays that share their first axis (one
row per dart, or per volume).  Rows are appended in blocks; capacity doubles so
that appending is amortised O(1) per row and no per-row Python work happens.

>>> import numpy as np
>>> c = Columns({"tissue": (np.int8, (), 0), "origin": (np.float64, (3,), 0.0)})
>>> rows = c.extend(3)
>>> c["tissue"][rows] = [1, 2, 3]
>>> len(c), c["origin"].shape
(3, (3, 3))
"""

from __future__ import annotations

import numpy as np


class Columns:
    """Named arrays sharing one growable first axis.

    ``spec`` maps a name to ``(dtype, trailing_shape, fill)``; new rows are set
    to ``fill``.  ``columns[name]`` is a view of the used rows only.
    """

    def __init__(self, spec, capacity=0) -> None:
        self._spec = dict(spec)
        self._n = 0
        self._data = {name: np.full((capacity, *shape), fill, dtype=dtype) for name, (dtype, shape, fill) in self._spec.items()}

    def __len__(self) -> int:
        return self._n

    def __getitem__(self, name):
        return self._data[name][: self._n]

    def __contains__(self, name) -> bool:
        return name in self._data

    def names(self):
        return list(self._data)

    def add(self, name, dtype, shape=(), fill=0) -> None:
        """Add a column (filled with ``fill`` for existing rows); no-op if present."""
        if name in self._data:
            return
        self._spec[name] = (dtype, tuple(shape), fill)
        cap = self.capacity
        self._data[name] = np.full((cap, *shape), fill, dtype=dtype)

    def fill(self, name: str) -> object:
        """The value new rows of column ``name`` start with."""
        return self._spec[name][2]

    def drop(self, name: str) -> None:
        """Remove column ``name`` (used to undo :meth:`add`)."""
        del self._data[name]
        del self._spec[name]

    def put(self, name: str, rows: np.ndarray) -> None:
        """Replace column ``name`` by ``rows`` (one row per used row; stored as given)."""
        if len(rows) != self._n:
            raise ValueError(f"column {name!r} needs {self._n} rows, got {len(rows)}")
        self._data[name] = rows

    def truncate(self, n: int) -> None:
        """Set the number of used rows to ``n`` (at most the capacity): rows from ``n`` on are dropped.

        Used by undo, which may also restore a length that a failed operation shortened.
        """
        if not 0 <= int(n) <= self.capacity:
            raise ValueError(f"cannot truncate to {n} rows (capacity {self.capacity})")
        self._n = int(n)

    @property
    def capacity(self):
        return next(iter(self._data.values())).shape[0] if self._data else 0

    def reserve(self, capacity) -> None:
        """Make room for ``capacity`` rows without changing the length."""
        if capacity <= self.capacity:
            return
        for name, arr in self._data.items():
            dtype, shape, fill = self._spec[name]
            grown = np.empty((capacity, *shape), dtype=arr.dtype)  # extend() fills rows it hands out
            grown[: self._n] = arr[: self._n]
            self._data[name] = grown

    def extend(self, count, skip=()):
        """Append ``count`` rows filled with defaults; return their ``slice``.

        Columns named in ``skip`` are left unfilled: the caller writes every new row.
        """
        start = self._n
        need = start + int(count)
        if need > self.capacity:
            self.reserve(max(need, 2 * self.capacity, 16))
        for name, arr in self._data.items():
            if name not in skip:
                arr[start:need] = self._spec[name][2]
        self._n = need
        return slice(start, need)

    def keep(self, rows) -> None:
        """Keep only ``rows`` (an index array), in that order."""
        for name, arr in self._data.items():
            kept = arr[: self._n][rows]
            arr[: len(kept)] = kept
        self._n = len(rows)

    def copy(self):
        other = Columns(self._spec, capacity=0)
        other._n = self._n
        other._data = {name: arr[: self._n].copy() for name, arr in self._data.items()}  # no fill pass
        return other

    @classmethod
    def from_arrays(cls, spec, arrays):
        """Wrap full-length ``arrays`` (dict name -> array); missing columns get fills."""
        n = len(next(iter(arrays.values())))
        cols = cls(spec, capacity=0)
        cols._n = n
        for name, (dtype, shape, fill) in cols._spec.items():
            if name in arrays:
                cols._data[name] = np.ascontiguousarray(arrays[name], dtype=dtype).reshape(n, *shape)
            else:
                cols._data[name] = np.full((n, *shape), fill, dtype=dtype)
        return cols
