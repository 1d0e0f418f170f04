"""What a 3-G-map stores and reads: darts and involutions as numpy arrays, attributes, orbits.

:class:`MapStorage` is the part of :class:`~ramure.gmap.kernel.map3.GMap3` below its
operations (:mod:`ramure.gmap.kernel.operations`, which build on it); use ``GMap3``.

A :class:`GMap3` is ``(B, alpha0, alpha1, alpha2, alpha3)`` (Lienhardt): a dart
is one vertex of one edge of one face of one volume; ``alpha0`` joins the two
darts of an edge, ``alpha1`` the two edges of a face at a vertex, ``alpha2`` two
faces of one volume along an edge, ``alpha3`` two volumes along a face.  A dart
is *free* for ``alpha_i`` when ``alpha_i(d) == d``.

Storage (all numpy, growable):

* ``alpha`` -- int32 array of shape (4, n_darts);
* per-dart data (:attr:`GMap3.dart_data`): ``volume`` id, ``face`` label code
  (O = 0, E = 1, Ck = k + 1, interior I = -1), ``sublabel`` (letters a..z as
  base-32 digits 1..26, see :func:`sublabel_name`), ``fcorner`` / ``forward``
  (corner index in the face, walk direction), ``point`` (the dart's vertex
  position: the volume's default corner before :meth:`GMap3.embed`, the
  vertex's position after) and ``radial``, a vertex scalar that embedding
  averages and subdivision interpolates like positions (the fruit stores its
  radial coordinate there: 0 on the core, 1 on the skin);
* per-volume data (:attr:`GMap3.volume_data`): ``label``, ``tissue``, ``order``,
  ``stage``, ``parent``, ``parent_face``, ``degree`` (prism order),
  ``leaf_id``, ``origin``, ``frame`` (rows H, L, U) and ``size`` (H, L, W).

Cells are orbits: vertex ``<a1,a2,a3>``, edge ``<a0,a2,a3>``, face
``<a0,a1,a3>``, volume ``<a0,a1,a2>``; all cells of one dimension are labelled
at once with scipy's connected components, and after growth (darts added,
free darts linked) the labelling and :meth:`GMap3.orbit_count` are updated
from the new darts only, as is the validity check.

Kernel extension API: modules built on the kernel (``embedding``, ``identify``,
``incidence``, ``mapcut``, ``faces``, ``attributes``...) use these public but
low-level members and never the map's private arrays:
:meth:`GMap3.atomic` (a context manager that restores the map when an
operation inside fails), :meth:`GMap3.check_darts` (validate dart ids),
:meth:`GMap3.orbits_from` (orbits of a few darts, cost proportional to them),
:meth:`GMap3.mark_changed` (call after editing ``alpha`` or dart data in place)
and :attr:`GMap3.cache` (derived data cleared on change),
:meth:`GMap3.dart_fill`, and the unchecked steps :meth:`GMap3.edge_zone`,
:meth:`GMap3.check_sewable`, :meth:`GMap3.sew_walks`,
:meth:`GMap3.split_face_edges`, :meth:`GMap3.split_faces` and
:meth:`GMap3.split_volumes`, which leave validation and atomicity to their caller.

>>> from ramure.gmap import GMap3
>>> gm = GMap3()
>>> first = gm.add_prisms(4)          # one cube
>>> gm.n_darts, gm.is_valid()
(48, True)
>>> c = gm.counts()
>>> c["vertices"], c["edges"], c["faces"], c["volumes"], gm.euler_characteristic()
(8, 12, 6, 1, 1)
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from types import TracebackType
from typing import Literal, Self

import numpy as np
from numpy.typing import ArrayLike, DTypeLike

from ramure.errors import RamureError
from ramure.gmap.kernel._columns import Columns
from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.kernel.graphs import compiled_pays, components, orbit_labels

DART_SPEC = {
    "volume": (np.int32, (), -1),
    "face": (np.int16, (), 0),
    "sublabel": (np.int64, (), 0),
    "fcorner": (np.int16, (), -1),
    "forward": (np.bool_, (), False),
    "point": (np.float64, (3,), 0.0),
    "radial": (np.float64, (), 0.0),
    "corner": (np.float64, (3,), 0.0),
    "vcorner": (np.int16, (), -1),
    "sup": (np.int32, (2,), -1),
    "supt": (np.float64, (), 0.0),
}

#: How each per-dart column reaches the darts an operation creates (see
#: :meth:`GMap3.add_dart_data`): ``copy`` from the dart the new one continues,
#: ``interpolate`` along the split edge (or average over the face / cell for
#: subdivision's face and cell points), ``reset`` to the column's fill value.
BUILTIN_RULES = {
    "volume": "copy",
    "face": "copy",
    "sublabel": "copy",
    "fcorner": "reset",
    "forward": "copy",
    "point": "interpolate",
    "radial": "interpolate",
    "corner": "interpolate",
    "vcorner": "reset",
    "sup": "reset",
    "supt": "reset",
}
PROPAGATION_RULES = ("copy", "interpolate", "reset")

#: ``parent_face`` value of a volume that was not grown on a parent face.
NO_FACE = -2

#: Names of the ``tissue`` volume codes (the biology in :mod:`ramure.gmap.organs.tissue` assigns them).
TISSUES = ("columella", "pericarp", "exocarp", "mesocarp", "endocarp", "septum", "locule", "seed")

VOLUME_SPEC = {
    "label": ("<U8", (), ""),
    "tissue": (np.int8, (), 0),
    "order": (np.int16, (), 0),
    "stage": (np.int16, (), 0),
    "parent": (np.int32, (), -1),
    "parent_face": (np.int16, (), NO_FACE),
    "degree": (np.int16, (), 0),
    "leaf_id": (np.int64, (), -1),
    "origin": (np.float64, (3,), 0.0),
    "frame": (np.float64, (3, 3), 0.0),
    "size": (np.float64, (3,), 0.0),
    "angles": (np.float64, (3,), 0.0),
    "shift": (np.float64, (), 0.0),
    "weight": (np.float64, (), 1.0),
    "exclusive": (np.bool_, (), False),
    "fit": (np.bool_, (), False),
}

SUBLABEL_BASE = 32

#: Ids of alpha snapshots (global, so copies of a map never reuse one).
_SNAPSHOT_IDS = itertools.count(1)

#: Involutions that generate each cell dimension (``i`` -> all but alpha_i).
CELL_INVOLUTIONS = {0: (1, 2, 3), 1: (0, 2, 3), 2: (0, 1, 3), 3: (0, 1, 2)}


def sublabel_name(code: int) -> str:
    """Letters of a sub-label code (digits 1..26 in base 32 are ``a``..``z``).

    >>> sublabel_name(0), sublabel_name(2), sublabel_name(2 * 32 + 4)
    ('', 'b', 'bd')
    """
    code = int(code)
    letters = []
    while code > 0:
        code, digit = divmod(code, SUBLABEL_BASE)
        letters.append(chr(ord("a") + digit - 1))
    return "".join(reversed(letters))


def _as_darts(darts: ArrayLike) -> np.ndarray:
    return np.atleast_1d(np.asarray(darts, dtype=np.int64))


def _involution_key(involutions):
    key = tuple(sorted({int(i) for i in str(involutions)} if isinstance(involutions, str) else {int(i) for i in involutions}))
    if not key or any(i not in (0, 1, 2, 3) for i in key):
        raise GMapError(f"involutions must be a non-empty subset of 0..3, got {involutions!r}")
    return key


def _validity_problems(alpha, vol, face, n_volumes, darts=None):
    """The checks of :meth:`GMap3.validity_problems` on ``darts`` (all when None)."""
    n = alpha.shape[1]
    problems = []
    if darts is None:
        if alpha.min() < 0 or alpha.max() >= n:
            return ["alpha holds dart ids outside 0..n_darts-1"]
        darts = np.arange(n)
        a = alpha
    else:
        a = alpha[:, darts]
    for i in range(4):
        bad = np.count_nonzero(alpha[i][a[i]] != darts)
        if bad:
            problems.append(f"alpha{i} is not an involution ({bad} darts)")
    for i in range(3):
        bad = np.count_nonzero(a[i] == darts)
        if bad:
            problems.append(f"alpha{i} has {bad} fixed points")
    for i, j in ((0, 2), (0, 3), (1, 3)):
        c = alpha[i][a[j]]
        bad = np.count_nonzero(alpha[i][alpha[j][c]] != darts)
        if bad:
            problems.append(f"alpha{i}alpha{j} is not an involution ({bad} darts)")
    v = vol[darts]
    if v.size and (v.min() < 0 or v.max() >= n_volumes):
        problems.append("some darts point to no volume")
    elif any(np.any(vol[a[i]] != v) for i in range(3)):
        problems.append("a volume orbit <a0,a1,a2> mixes volume ids")
    f = face[darts]
    if any(np.any(face[a[i]] != f) for i in range(2)):
        problems.append("a face orbit <a0,a1> mixes face labels")
    return problems


def _compiled_validity_problems(alpha, vol, face, n_volumes, darts=None):
    """:func:`_validity_problems` by the compiled pass (same messages), or None when an id leaves the map."""
    from ramure.gmap.kernel import _validity_kernel as K

    every = darts is None
    counts = K.problem_counts(alpha, vol, face, n_volumes, np.zeros(0, np.int64) if every else darts, every)
    if counts[K.OUT_OF_RANGE]:
        return None
    problems = [f"alpha{i} is not an involution ({counts[K.INVOLUTION + i]} darts)" for i in range(4) if counts[K.INVOLUTION + i]]
    problems += [f"alpha{i} has {counts[K.FIXED + i]} fixed points" for i in range(3) if counts[K.FIXED + i]]
    for p, (i, j) in enumerate(K.PAIRS):
        if counts[K.PAIR + p]:
            problems.append(f"alpha{i}alpha{j} is not an involution ({counts[K.PAIR + p]} darts)")
    if counts[K.VOLUME_RANGE]:
        problems.append("some darts point to no volume")
    elif counts[K.VOLUME_MIX]:
        problems.append("a volume orbit <a0,a1,a2> mixes volume ids")
    if counts[K.FACE_MIX]:
        problems.append("a face orbit <a0,a1> mixes face labels")
    return problems


class _Atomic:
    def __init__(self, gm, local=None) -> None:
        self.gm = gm
        self.local = local

    def __enter__(self):
        self.snap = self.gm._snapshot(self.local)
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> Literal[False]:
        if kind is None:
            return False
        self.gm._restore(self.snap)
        if isinstance(exc, (IndexError, ValueError, KeyError)) and not isinstance(exc, RamureError):
            raise GMapError(f"operation refused, map unchanged: {exc}") from exc
        return False


class _OrbitState:
    """Orbits of one involution set in two levels (see :meth:`GMap3.orbit_count`).

    ``raw[d]`` (d < n) is dart d's raw orbit number, never rewritten once
    given; ``find[raw]`` today's orbit number (0..count-1); ``snap`` the alpha
    snapshot this state describes.  ``raw`` has room beyond ``n``; copies of a
    map share states, so a state appends in place only while it is the last
    one written into that array (``_end[0] == n``), else it copies.
    """

    __slots__ = ("raw", "_end", "n", "find", "count", "snap", "sid", "base", "new_loc")

    def __init__(self, raw, end, n, find, count, snap, base=None, new_loc=None) -> None:
        self.raw, self._end, self.n, self.find, self.count, self.snap = raw, end, n, find, int(count), snap
        self.sid = next(_SNAPSHOT_IDS)
        #: ``sid`` of the state this one extends without touching its orbits (new darts form
        #: new orbits ``new_loc``, numbered after the old ones), else None
        self.base, self.new_loc = base, new_loc

    @staticmethod
    def room(n: int, room: int = 0) -> np.ndarray:
        """An int32 buffer for ``n`` raw numbers, with room for ``room`` darts (the map's reserve) or half as many again."""
        return np.empty(max(16, n + n // 2, room), np.int32)

    @classmethod
    def fresh(cls, ids, count, snap, room=0) -> _OrbitState:
        """A state of the labels ``ids``, with room for ``room`` darts (the map's reserve) or half as many again."""
        raw = cls.room(len(ids), room)
        raw[: len(ids)] = ids
        return cls(raw, [len(ids)], len(ids), np.arange(count, dtype=np.int32), count, snap)

    def labels(self) -> np.ndarray:
        """Today's orbit number of every dart (one gather)."""
        return np.take(self.find, self.raw[: self.n])

    def label_of(self, darts) -> np.ndarray:
        return self.find[self.raw[darts]]

    def moved(self, snap) -> _OrbitState:
        """The same orbits, described against a newer snapshot."""
        return _OrbitState(self.raw, self._end, self.n, self.find, self.count, snap, self.sid, np.zeros(0, np.int32))

    def grown(self, n, loc, n_loc, relabel, count, snap, untouched=False, find=None, room=0) -> _OrbitState:
        """Darts ``self.n .. n - 1`` with raw numbers after ours (``loc``), orbits merged by ``relabel``.

        ``untouched``: no new link reaches an old orbit (old orbits are as they were).
        ``find``: the new table, already made (then ``relabel`` is not read);
        ``room``: darts to make room for when the raw numbers must move (the map's reserve).
        """
        raw, end = self.raw, self._end
        if end[0] != self.n or len(raw) < n:  # someone else appended here, or no room: copy
            grown = np.empty(max(n + n // 2, 16, room), np.int32)
            grown[: self.n] = raw[: self.n]
            raw, end = grown, [self.n]
        n_raw = len(self.find)
        raw[self.n : n] = loc + n_raw
        end[0] = n
        if find is None:
            find = np.concatenate([self.find, np.arange(self.count, self.count + n_loc, dtype=np.int32)])
            if relabel is not None:
                find = relabel[find].astype(np.int32)
        if untouched:
            return _OrbitState(raw, end, n, find, count, snap, self.sid, loc)
        return _OrbitState(raw, end, n, find, count, snap)


class _ColumnsView(Mapping):
    """Read-through mapping ``name -> array view`` over a :class:`Columns`."""

    def __init__(self, columns) -> None:
        self._columns = columns

    def __getitem__(self, name):
        return self._columns[name]

    def __iter__(self):
        return iter(self._columns.names())

    def __len__(self) -> int:
        return len(self._columns.names())


class MapStorage:
    """A 3-G-map's storage, orbits, cells, validity and embedding (see the module docstring for
    the layout); :class:`~ramure.gmap.kernel.map3.GMap3` adds the operations on top."""

    _orbit_memo: dict  # orbit labellings kept across edits, made on first use (see _orbit_state)
    _scratch: np.ndarray | None = None  # per-dart -1s for orbit walks, made on first use (see _marks)

    def __init__(self) -> None:
        self._alpha = np.empty((4, 0), np.int32)
        self._darts = Columns(DART_SPEC)
        self._volumes = Columns(VOLUME_SPEC)
        self._cache: dict = {}
        self._rules = dict(BUILTIN_RULES)
        #: free-form provenance (preset, parameters, seed) set by builders
        self.meta: dict = {}

    # ------------------------------------------------------------------ storage
    @property
    def n_darts(self) -> int:
        """Number of darts."""
        return len(self._darts)

    @property
    def n_volumes(self) -> int:
        """Number of volumes (rows of :attr:`volume_data`)."""
        return len(self._volumes)

    @property
    def alpha(self) -> np.ndarray:
        """The involutions, int32 array of shape (4, n_darts) (a view; edit via operations)."""
        return self._alpha[:, : self.n_darts]

    @property
    def dart_data(self) -> Mapping[str, np.ndarray]:
        """Per-dart arrays by name (views): volume, face, sublabel, fcorner, forward, point."""
        return _ColumnsView(self._darts)

    @property
    def volume_data(self) -> Mapping[str, np.ndarray]:
        """Per-volume arrays by name (views): label, tissue, order, stage, leaf_id, ..."""
        return _ColumnsView(self._volumes)

    @property
    def points(self) -> np.ndarray:
        """Per-dart positions (n_darts, 3), a writable view."""
        return self._darts["point"]

    @property
    def corners(self) -> np.ndarray:
        """Per-dart default corners (n_darts, 3), a writable view; :meth:`embed` reads them."""
        return self._darts["corner"]

    def set_corners_from_tables(self, table: np.ndarray, offset: np.ndarray, corner: np.ndarray) -> None:
        """Default corners from per-volume tables: dart ``d`` gets ``table[offset[v] + corner[d]]``, ``v`` its volume.

        ``table`` (m, 3) holds every volume's corners, volume ``v``'s from row
        ``offset[v]``; ``corner`` is each dart's corner index in its volume.
        An index outside the table is clipped to it (as ``np.take(mode="clip")``).
        """
        table = np.ascontiguousarray(table, np.float64)
        out = self._darts["corner"]
        if compiled_pays(self.n_darts):  # one pass, no index array
            from ._embed_kernel import gather_corners

            if not gather_corners(table, np.asarray(offset, np.int64), self.dart_volume, np.asarray(corner), out):
                raise GMapError("corners from tables: a dart's volume has no row offset")
            return
        vol = self.dart_volume
        if vol.size and (vol.min() < 0 or vol.max() >= len(offset)):
            raise GMapError("corners from tables: a dart's volume has no row offset")
        np.take(table, np.asarray(offset)[vol] + corner, axis=0, out=out, mode="clip")

    @property
    def dart_volume(self) -> np.ndarray:
        """Volume id of every dart."""
        return self._darts["volume"]

    def add_volume_data(self, name: str, dtype: DTypeLike, shape: tuple[int, ...] = (), fill: object = 0) -> None:
        """Add a per-volume attribute column, read back in :attr:`volume_data` (existing volumes get ``fill``)."""
        self._volumes.add(name, dtype, shape, fill)

    def add_dart_data(
        self, name: str, dtype: DTypeLike, shape: tuple[int, ...] = (), fill: object = 0, rule: str = "copy"
    ) -> None:
        """Add a per-dart attribute column, read back in :attr:`dart_data`, kept through every operation by ``rule``.

        ``rule`` is ``"copy"`` (a dart made by splitting an edge, a face or a
        cell takes the value of the dart it continues; darts of a new face
        take the value of the dart they are alpha2-glued to), ``"interpolate"``
        (linear along a split edge at the split fraction; subdivision's edge,
        face and cell points take the mean over the edge, the face side
        ``<a0,a1>`` or the volume; new faces take the glued dart's value) or
        ``"reset"`` (darts created by an operation get ``fill``).  Existing
        darts get ``fill``.  Texture coordinates interpolate; crack and healed
        markers copy or reset.

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3(); _ = gm.add_prisms(4)
        >>> gm.add_dart_data("uvw", float, (3,), rule="interpolate")
        >>> gm.dart_data["uvw"][:] = gm.points
        >>> new = gm.split_edge([0], 0.25)
        >>> bool(abs(gm.dart_data["uvw"][new[0]] - gm.points[new[0]]).max() < 1e-12)
        True
        """
        if rule not in PROPAGATION_RULES:
            raise GMapError(f"propagation rule must be one of {', '.join(PROPAGATION_RULES)}, got {rule!r}")
        if name in self._darts:
            raise GMapError(f"dart attribute {name!r} exists already")
        if rule == "interpolate" and not np.issubdtype(np.dtype(dtype), np.floating):
            raise GMapError(f"an interpolated attribute must have a float dtype, got {np.dtype(dtype)}")
        self._darts.add(name, dtype, tuple(shape), fill)
        self._rules[name] = rule

    def dart_rules(self) -> dict[str, str]:
        """``name -> propagation rule`` of every per-dart column."""
        return dict(self._rules)

    def dart_fill(self, name: str) -> object:
        """The value per-dart column ``name`` is reset to (its fill value)."""
        return self._darts.fill(name)

    def _propagate(self, new, src, other=None, frac=None, skip=()) -> None:
        """Give the new darts ``new`` values from ``src`` by each column's rule.

        ``interpolate`` columns get ``src + frac (other - src)`` when ``other``
        is given (else a copy of ``src``).
        """
        data = self._darts
        for name, rule in self._rules.items():
            if name in skip:
                continue
            col = data[name]
            if rule == "reset":
                col[new] = self.dart_fill(name)
            elif rule == "interpolate" and other is not None:
                f = np.asarray(frac, float).reshape((-1,) + (1,) * (col.ndim - 1))
                col[new] = col[src] + f * (col[other] - col[src])
            else:
                col[new] = col[src]

    def mark_changed(self) -> None:
        """Forget every cached orbit labelling and :attr:`cache` entry; call after editing arrays in place."""
        self._cache.clear()

    @property
    def cache(self) -> dict:
        """Derived data kept until the map changes (:meth:`mark_changed` clears it); keys are strings."""
        return self._cache

    def _snapshot(self, local=None):
        """What an operation may change (for :meth:`atomic`); ``local``: the only old darts it edits."""
        n, nvol = self.n_darts, self.n_volumes
        if local is None:
            return (n, nvol, None, self.alpha.copy(), self._darts.copy(), self._volumes.copy(), dict(self._rules))
        local = np.unique(np.asarray(local, np.int64))
        rows = {name: self._darts[name][local].copy() for name in self._darts.names()}
        return (n, nvol, local, self._alpha[:, local].copy(), rows, None, dict(self._rules))

    def _restore(self, snap) -> None:
        n, nvol, local, alpha, darts, volumes, rules = snap
        self._rules = rules
        if local is None:
            self._darts, self._volumes = darts, volumes
            self._alpha = np.empty((4, darts.capacity), np.int32)
            self._alpha[:, : alpha.shape[1]] = alpha
        else:
            self._darts.truncate(n)
            self._volumes.truncate(nvol)
            for name in list(self._darts.names()):
                if name not in darts:
                    self._darts.drop(name)
                else:
                    self._darts[name][local] = darts[name]
            self._alpha[:, local] = alpha
        self.mark_changed()

    def atomic(self, local: ArrayLike | None = None) -> _Atomic:
        """Context manager: a refused operation leaves the map exactly as it was.

        Any exception inside restores what was saved on entry and re-raises
        errors that are not Ramure errors as :class:`GMapError`.  Without
        ``local`` the whole map is copied (O(darts)); with ``local`` (every
        old dart the operation may edit: its volume's darts, the edge orbits
        it splits) only those rows are saved, and new darts and volumes are
        dropped by truncation, so the cost follows the operation's size.
        """
        return _Atomic(self, local)

    def reserve(self, n_darts: int) -> None:
        """Make room for ``n_darts`` darts in all arrays (avoids regrowing during a batch of operations)."""
        self._darts.reserve(int(n_darts))
        cap = self._darts.capacity
        if self._alpha.shape[1] < cap:
            grown = np.empty((4, cap), np.int32)
            grown[:, : self.n_darts] = self._alpha[:, : self.n_darts]
            self._alpha = grown

    def _new_darts(self, count, skip=(), free=(0, 1, 2, 3)):
        """Append ``count`` free darts (each alpha points to itself); return their ids.

        Per-dart columns named in ``skip`` are not filled (the caller writes them);
        only the alpha rows in ``free`` are set to the identity (the caller writes the others).
        """
        rows = self._darts.extend(count, skip)
        cap = self._darts.capacity
        if self._alpha.shape[1] < cap:
            grown = np.empty((4, cap), np.int32)
            grown[:, : rows.start] = self._alpha[:, : rows.start]
            self._alpha = grown
        ids = np.arange(rows.start, rows.stop, dtype=np.int32)
        for i in free:
            self._alpha[i, rows] = ids
        self.mark_changed()
        return ids

    def _new_volumes(self, count, **values):
        """Append ``count`` volumes with the given column values (others get their fill)."""
        for name in values:
            if name not in self._volumes:
                raise GMapError(f"unknown volume attribute {name!r}")
        rows = self._volumes.extend(count, skip=values)  # the given columns are written below
        try:
            for name, value in values.items():
                self._volumes[name][rows] = value
        except BaseException:
            self._volumes.truncate(rows.start)  # no half-written volumes
            raise
        return np.arange(rows.start, rows.stop)

    def copy(self) -> Self:
        """A deep copy."""
        other = type(self)()
        other._alpha = self.alpha.copy()
        other._darts = self._darts.copy()
        other._volumes = self._volumes.copy()
        other._rules = dict(self._rules)
        other._cache = dict(self._cache)  # cached labels are replaced on change, never edited
        other._orbit_memo = dict(self.__dict__.get("_orbit_memo", {}))  # snapshots are never edited
        other.meta = dict(self.meta)
        return other

    @classmethod
    def from_arrays(
        cls,
        alpha: ArrayLike,
        darts: Mapping[str, np.ndarray] | None = None,
        volumes: Mapping[str, np.ndarray] | None = None,
        rules: Mapping[str, str] | None = None,
    ) -> Self:
        """Build a map from full arrays: ``alpha`` (4, n), dicts of dart and volume arrays.

        Dart arrays beyond the built-in columns become attributes with the
        propagation rule given in ``rules`` (default ``copy``).  Without a
        ``corner`` array the default corners are the given points.

        >>> from ramure.gmap import GMap3
        >>> import numpy as np
        >>> one = GMap3()
        >>> _ = one.add_prisms(3)
        >>> two = GMap3.from_arrays(one.alpha, dict(one.dart_data), dict(one.volume_data))
        >>> two.n_darts, two.n_volumes, two.is_valid()
        (36, 1, True)
        """
        gm = cls()
        gm._alpha = np.ascontiguousarray(alpha, dtype=np.int32)
        n = gm._alpha.shape[1]
        darts = dict(darts or {})
        darts.setdefault("volume", np.zeros(n, np.int32))
        if "corner" not in darts and "point" in darts:
            darts["corner"] = darts["point"]
        gm._darts = Columns.from_arrays(DART_SPEC, {k: v for k, v in darts.items() if k in DART_SPEC})
        rules = dict(rules or {})
        for name, arr in darts.items():
            if name in DART_SPEC:
                continue
            arr = np.asarray(arr)
            rule = rules.get(name, "copy")
            if rule not in PROPAGATION_RULES:
                raise GMapError(f"propagation rule must be one of {', '.join(PROPAGATION_RULES)}, got {rule!r}")
            gm._darts.add(name, arr.dtype, arr.shape[1:], 0)
            gm._darts.put(name, np.ascontiguousarray(arr).copy())
            gm._rules[name] = rule
        volumes = dict(volumes or {})
        if not volumes:
            volumes = {"label": np.full(int(darts["volume"].max(initial=-1)) + 1, "A")}
        extra = {k: v for k, v in volumes.items() if k not in VOLUME_SPEC}
        gm._volumes = Columns.from_arrays(VOLUME_SPEC, {k: v for k, v in volumes.items() if k in VOLUME_SPEC})
        for name, arr in extra.items():
            arr = np.asarray(arr)
            gm._volumes.add(name, arr.dtype, arr.shape[1:], 0)
            gm._volumes[name][:] = arr
        return gm

    @classmethod
    def merge(cls, maps: Sequence[MapStorage]) -> Self:
        """Disjoint union of several maps (dart and volume ids are offset in order).

        >>> from ramure.gmap import GMap3
        >>> a = GMap3(); _ = a.add_prisms(4)
        >>> b = GMap3.merge([a, a])
        >>> b.n_darts, b.n_volumes, b.counts()["volumes"]
        (96, 2, 2)
        """
        maps = list(maps)
        if not maps:
            return cls()
        dart_off = np.cumsum([0] + [m.n_darts for m in maps])
        vol_off = np.cumsum([0] + [m.n_volumes for m in maps])
        alpha = np.concatenate([m.alpha.astype(np.int64) + o for m, o in zip(maps, dart_off)], axis=1)
        dnames = [n for n in maps[0].dart_data if all(n in m.dart_data for m in maps)]
        darts = {name: np.concatenate([m.dart_data[name] for m in maps]) for name in dnames}
        darts["volume"] = np.concatenate([m.dart_volume + o for m, o in zip(maps, vol_off)])
        if "sup" in darts:
            sup = np.concatenate([np.where(m.dart_data["sup"] >= 0, m.dart_data["sup"] + o, -1) for m, o in zip(maps, dart_off)])
            darts["sup"] = sup
        names = [n for n in maps[0].volume_data if all(n in m.volume_data for m in maps)]
        volumes = {name: np.concatenate([m.volume_data[name] for m in maps]) for name in names}
        parent = volumes["parent"].astype(np.int64)
        shift = np.repeat(vol_off[:-1], [m.n_volumes for m in maps])
        volumes["parent"] = np.where(parent >= 0, parent + shift, -1)
        return cls.from_arrays(alpha, darts, volumes, maps[0].dart_rules())

    # ------------------------------------------------------------------ orbits
    def orbit(self, dart: int, involutions: str | Sequence[int] = "0123") -> np.ndarray:
        """Sorted darts of the orbit ``<alpha_i, i in involutions>(dart)`` (breadth-first).

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3(); _ = gm.add_prisms(4)
        >>> len(gm.orbit(0, "01")), len(gm.orbit(0, "012")), len(gm.orbit(0, "12"))
        (8, 48, 6)
        """
        key = _involution_key(involutions)
        members, _ = self.orbits_from(_as_darts(dart)[:1], key)
        return members

    def orbits_from(self, starts: ArrayLike, key: Sequence[int], strict: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Breadth-first orbits of ``starts``: ``(members, labels)``.

        ``members`` is sorted; ``labels[i]`` is the index in ``starts`` of the
        orbit holding ``members[i]``.  The work is proportional to the orbits'
        size, not to the map's (a per-map scratch array of marks is set and
        reset only where the walk goes).  With ``strict``, two starts in one
        orbit raise :class:`GMapError`; without, darts reached from several
        starts keep one of their indices.
        """
        starts = _as_darts(starts)
        if starts.size and (starts.min() < 0 or starts.max() >= self.n_darts):
            raise GMapError(f"dart ids must be in 0..{self.n_darts - 1}")
        if strict and len(np.unique(starts)) != len(starts):
            raise GMapError("two of the given darts are the same dart")
        mark = self._marks()
        if strict and compiled_pays(self.n_darts):  # one compiled search: the calls, not the darts, cost here
            from ramure.gmap.kernel._walk_kernel import orbit_members

            found, which, status = orbit_members(self.alpha, np.asarray(key, np.int64), starts, mark)
            if status == 1:
                raise GMapError("two of the given darts lie in the same orbit")
            if status == 0:
                order = np.argsort(found)
                return found[order], which[order]
        rows = [self._alpha[i] for i in key]
        frontier = np.unique(starts)
        mark[starts[::-1]] = np.arange(len(starts))[::-1]  # a repeated start keeps its first index
        touched = [frontier]
        try:
            while frontier.size:
                nb = np.concatenate([r[frontier] for r in rows]).astype(np.int64)
                lab = np.tile(mark[frontier], len(key))
                m = mark[nb]
                seen = m >= 0
                if strict and np.any(m[seen] != lab[seen]):
                    raise GMapError("two of the given darts lie in the same orbit")
                nb, lab = nb[~seen], lab[~seen]
                if nb.size:
                    mark[nb] = lab
                    if strict and np.any(mark[nb] != lab):
                        raise GMapError("two of the given darts lie in the same orbit")
                    nb = np.unique(nb)
                    touched.append(nb)
                frontier = nb
            members = np.sort(np.concatenate(touched))
            labels = mark[members].astype(np.int64)
        finally:
            mark[np.concatenate(touched)] = -1
        return members, labels

    def _marks(self):
        """A per-dart scratch array of -1 (orbit walks set and reset only what they touch).

        int32: it holds indices of starts or faces, fewer than the darts (whose ids are int32).
        """
        n = self._alpha.shape[1]
        if self._scratch is None or len(self._scratch) < n:
            self._scratch = np.full(max(n, 16), -1, np.int32)
        return self._scratch

    def orbit_ids(self, involutions: str | Sequence[int]) -> tuple[np.ndarray, int]:
        """``(ids, count)``: the orbit of every dart under the given involutions.

        Ids run over ``0..count-1`` (their order is arbitrary).  Cached until
        the map changes.  After a change that only *added* darts and sewed
        free darts (growth: :meth:`add_prisms`, :meth:`sew3`, ...), the
        labelling is updated from the last one instead of recomputed (see
        :meth:`orbit_count`); anything else (unsew, split, removal)
        recomputes with scipy's connected components (the graph of
        involutions is symmetric, so strong components are the orbits).

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3(); _ = gm.add_prisms(4)
        >>> ids, count = gm.orbit_ids("01")   # faces of each volume
        >>> count, ids[:3].tolist()
        (6, [0, 0, 0])
        """
        key = _involution_key(involutions)
        if key not in self._cache:
            state = self._orbit_state(key)
            self._cache[key] = (state.labels(), state.count)
        return self._cache[key]

    def orbit_count(self, involutions: str | Sequence[int]) -> int:
        """Number of orbits under the given involutions, without labelling every dart after growth.

        The kernel keeps, per involution set, a labelling in two levels: a
        *raw* orbit number per dart, never rewritten once given, and a small
        table from raw numbers to today's orbit numbers.  When the map only
        grew since (darts appended, free darts linked: orbits can only
        merge), the new darts are labelled among themselves, the links that
        cross between them and old orbits -- or join two old orbits -- form
        a graph over the orbits they touch, and its components give the
        merges; only the table is rewritten.  The cost follows the new darts
        and the number of orbits, not the map's size.  :meth:`orbit_ids`
        gathers the table over the darts when asked.

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3(); _ = gm.add_prisms(4)
        >>> gm.orbit_count("123"), gm.orbit_count("013")
        (8, 6)
        """
        key = _involution_key(involutions)
        if key in self._cache:
            return int(self._cache[key][1])
        return self._orbit_state(key).count

    def _orbit_state(self, key) -> _OrbitState:
        """The two-level labelling of ``key`` for the map as it is now (updated or recomputed)."""
        cache_key = ("orbit_state", key)
        state = self._cache.get(cache_key)
        if state is None:
            memo = self.__dict__.setdefault("_orbit_memo", {})
            old = memo.get(key)
            state = self._grown_orbits(key, old) if old is not None else None
            if state is None:
                raw = _OrbitState.room(self.n_darts, self._alpha.shape[1])
                ids, count = orbit_labels(self.alpha, select=key, out=raw)  # written in place: no copy
                state = _OrbitState(raw, [len(ids)], len(ids), np.arange(count, dtype=np.int32), count, self._alpha_snapshot())
            memo[key] = self._cache[cache_key] = state
        return state

    def _alpha_snapshot(self):
        """``(id, copy of alpha)`` of the map as it is now (one copy per state, shared by all keys)."""
        snap = self._cache.get("alpha_snapshot")
        if snap is None:
            snap = self._cache["alpha_snapshot"] = (next(_SNAPSHOT_IDS), self.alpha.copy())
        return snap

    def _growth_since(self, snap, cached: bool = True):
        """``(r, d)`` links that are new since snapshot ``snap``, or None if the map did more than grow.

        ``cached=False`` compares afresh (validity must also see edits made
        without :meth:`mark_changed`).
        """
        cache_key = ("growth", snap[0])
        if not cached:
            self._cache.pop(cache_key, None)
        if cache_key not in self._cache:
            old = snap[1]
            n, n_old = self.n_darts, old.shape[1]
            result = None
            if n >= n_old:
                alpha = self._alpha
                changed = [np.flatnonzero(old[i] != alpha[i, :n_old]) for i in range(4)]
                r = np.repeat(np.arange(4), [len(c) for c in changed])
                d = np.concatenate(changed)
                if not np.any(old[r, d] != d):  # only free darts got linked: orbits merge
                    result = (r, d)
            self._cache[cache_key] = result
        return self._cache[cache_key]

    def _grown_orbits(self, key, old: _OrbitState) -> _OrbitState | None:
        """``old`` updated by the growth since it was made, or None (see :meth:`orbit_count`)."""
        growth = self._growth_since(old.snap)
        if growth is None:
            return None
        r, d = growth
        n, n_old = self.n_darts, old.n
        n_new = n - n_old
        in_key = np.zeros(4, bool)
        in_key[list(key)] = True
        mine = in_key[r]
        r, d = r[mine], d[mine]
        if n_new and (d.size + len(key) * n_new) > n:  # most of the map is new: recompute
            return None
        snap = self._alpha_snapshot()
        if d.size == 0 and n_new == 0:
            return old.moved(snap)
        if n_new and compiled_pays(n):  # the same steps, one compiled pass
            from ramure.gmap.kernel._components_kernel import grown_orbits

            local = self._new_dart_local(n_old)
            if local is None:
                return None
            loc, n_loc, find, total, linked, ok = grown_orbits(
                local, in_key, n_old, old.raw, old.find, old.count, r, d, self.alpha
            )
            if ok:
                return old.grown(n, loc, int(n_loc), None, int(total), snap, not linked, find, self._alpha.shape[1])
        new_rows = self._new_dart_rows(n_old)
        if new_rows is None:
            return None
        rows, involution, links_out, links_to = new_rows
        key = list(key)
        loc, n_loc = (
            orbit_labels(rows[key], involutions=all(involution[i] for i in key) or None) if n_new else (np.zeros(0, np.int32), 0)
        )
        count_old = old.count
        node_new = loc.astype(np.int64) + count_old  # graph nodes: old orbits, then new ones

        def node(darts):
            darts = np.asarray(darts, np.int64)
            is_old = darts < n_old
            out = np.empty(len(darts), np.int64)
            out[is_old] = old.label_of(darts[is_old])
            out[~is_old] = node_new[darts[~is_old] - n_old]
            return out

        u = np.concatenate([node(d)] + [node_new[links_out[i]] for i in key])
        v = np.concatenate([node(self.alpha[r, d])] + [old.label_of(links_to[i]) for i in key])
        total = count_old + n_loc
        relabel = None
        if u.size:
            touched = np.zeros(total, bool)
            touched[u] = True
            touched[v] = True
            nodes = np.flatnonzero(touched)
            index = np.cumsum(touched) - 1
            n_groups, group = components(index[u], index[v], len(nodes))
            if n_groups < len(nodes):
                first = np.full(n_groups, total, np.int64)
                np.minimum.at(first, group, nodes)
                merged = np.arange(total)
                merged[nodes] = first[group]
                keep = merged == np.arange(total)
                relabel = (np.cumsum(keep) - 1)[merged]
                total = int(np.count_nonzero(keep))
        return old.grown(n, loc, n_loc, relabel, total, snap, not u.size, room=self._alpha.shape[1])

    def _new_dart_rows(self, n_old: int):
        """The links of the darts from ``n_old`` on, shared by every key's update (cached per state).

        ``(rows, involution, links_out, links_to)``: ``rows[i]`` alpha_i of
        those darts in local numbers, a link to an older dart made a
        self-loop; ``involution[i]`` whether that row is an involution;
        ``links_out[i]`` the local darts whose alpha_i is older, and
        ``links_to[i]`` those older darts.  None if a link leaves the map.
        """
        cache_key = ("new_rows", n_old)
        if cache_key not in self._cache:
            n = self.n_darts
            local = self._new_dart_local(n_old)
            result = None
            if local is not None:
                to_old = local < 0
                ar = np.arange(n - n_old)
                rows = np.where(to_old, ar, local)
                involution = [bool(np.array_equal(row[row], ar)) for row in rows]
                links_out = [np.flatnonzero(t) for t in to_old]
                links_to = [local[i][links_out[i]] + n_old for i in range(4)]
                result = (rows, involution, links_out, links_to)
            self._cache[cache_key] = result
        return self._cache[cache_key]

    def _new_dart_local(self, n_old: int):
        """alpha of the darts from ``n_old`` on in local numbers (older darts negative), or None if a link leaves the map."""
        cache_key = ("new_local", n_old)
        if cache_key not in self._cache:
            n = self.n_darts
            local = self._alpha[:, n_old:n].astype(np.int64) - n_old
            ok = local.size == 0 or (local.max() < n - n_old and local.min() >= -n_old)
            self._cache[cache_key] = local if ok else None
        return self._cache[cache_key]

    def cells(self, i: int) -> tuple[np.ndarray, int]:
        """``(ids, count)`` of the i-cells (0 vertex, 1 edge, 2 face, 3 volume) of every dart."""
        if i not in CELL_INVOLUTIONS:
            raise GMapError(f"cell dimension must be 0, 1, 2 or 3, got {i!r}")
        return self.orbit_ids(CELL_INVOLUTIONS[i])

    def counts(self) -> dict[str, int]:
        """Numbers of darts and cells.

        ``faces`` counts 2-cells ``<a0,a1,a3>`` (a face shared by two volumes
        counts once); ``faces_per_volume`` counts ``<a0,a1>`` orbits, the way
        the thesis's table counts them (a shared face counts twice).
        """
        return {
            "darts": self.n_darts,
            "vertices": self.orbit_count(CELL_INVOLUTIONS[0]),
            "edges": self.orbit_count(CELL_INVOLUTIONS[1]),
            "faces": self.orbit_count(CELL_INVOLUTIONS[2]),
            "volumes": self.orbit_count(CELL_INVOLUTIONS[3]),
            "faces_per_volume": self.orbit_count("01"),
        }

    def euler_characteristic(self) -> int:
        """``V - E + F - C`` over the i-cells (1 for a map of a solid ball)."""
        v, e, f, c = (self.orbit_count(CELL_INVOLUTIONS[i]) for i in range(4))
        return v - e + f - c

    def vertex_ids(self) -> tuple[np.ndarray, int]:
        """Vertex (0-cell) id of every dart, and the number of vertices."""
        return self.cells(0)

    def vertex_positions(self) -> tuple[np.ndarray, np.ndarray]:
        """``(ids, positions)``: vertex id per dart and the mean point of each vertex."""
        ids, count = self.cells(0)
        pts = self.points
        pos = np.stack([np.bincount(ids, pts[:, j], minlength=count) for j in range(3)], axis=1)
        return ids, pos / np.bincount(ids, minlength=count)[:, None]

    def is_free(self, darts: ArrayLike, i: int) -> np.ndarray:
        """True where ``alpha_i(d) == d``."""
        d = _as_darts(darts)
        return self.alpha[i][d] == d

    # ------------------------------------------------------------------ validity
    def validity_problems(self) -> list[str]:
        """Plain-language list of what breaks the 3-G-map conditions (empty when valid).

        Checked, all vectorised: every alpha_i is an involution on 0..n-1;
        alpha0, alpha1, alpha2 have no fixed point; alpha0 alpha2, alpha0 alpha3
        and alpha1 alpha3 are involutions; every dart of a volume
        ``<a0,a1,a2>`` carries that volume's id and every dart of a face
        ``<a0,a1>`` the same face label.

        Incremental after growth: when the map was found valid before and
        since then darts were only appended and free darts linked, only the
        darts whose conditions read a changed dart are checked (see
        :meth:`_changed_since_valid`); a changed volume id or face label of
        an old dart counts as a change.  Anything else checks every dart.
        """
        n = self.n_darts
        if n == 0:
            return []
        alpha = self.alpha
        if alpha.shape != (4, n):
            return [f"alpha has shape {alpha.shape}, expected (4, {n})"]
        darts = self._changed_since_valid()
        problems = None
        if compiled_pays(n):  # same conditions and counts, one compiled pass
            problems = _compiled_validity_problems(alpha, self.dart_volume, self._darts["face"], self.n_volumes, darts)
        if problems is None:
            problems = _validity_problems(alpha, self.dart_volume, self._darts["face"], self.n_volumes, darts)
        if not problems:
            snap = self._alpha_snapshot()
            self._valid_memo = (snap, self.dart_volume.copy(), self._darts["face"].copy(), self.n_volumes)
        return problems

    def _changed_since_valid(self):
        """Darts whose conditions may have changed since the map was last found valid (None: all).

        ``S`` = new darts, old darts with a new link, old darts with a new
        volume id or face label.  The conditions at a dart ``x`` read the
        data of ``x``, ``a_i x`` (involution, fixed point, volume and face
        checks) and, for each pair ``(i, j)`` in (0,2), (0,3), (1,3), of
        ``a_j x``, ``a_i a_j x`` and ``a_j a_i a_j x``.  For an old dart
        ``x`` outside ``S`` the walk ``x -> a_j x -> a_i a_j x -> ...``
        steps back along old links until it meets ``S``: a changed link was
        free before, so in the old involution it could only have pointed
        back to its own dart.  So ``x`` is in ``S``, ``a_i S``,
        ``a_j a_i S`` or ``a_j a_i a_j S`` (new links, same pairs), and only
        those darts are checked (up to 11 per changed dart).
        """
        memo = self.__dict__.get("_valid_memo")
        if memo is None:
            return None
        snap, vol_old, face_old, nvol_old = memo
        growth = self._growth_since(snap, cached=False)
        n_old = len(vol_old)
        if growth is None or self.n_volumes < nvol_old:
            return None
        r, d = growth
        n = self.n_darts
        mask = np.zeros(n, bool)
        mask[d] = True
        mask[n_old:] = True
        mask[:n_old] |= (self.dart_volume[:n_old] != vol_old) | (self._darts["face"][:n_old] != face_old)
        seeds = np.flatnonzero(mask)
        if 3 * len(seeds) > n:  # most of the map: one full pass is cheaper
            return None
        alpha = self.alpha
        if compiled_pays(n):
            from ramure.gmap.kernel._validity_kernel import mark_reach

            return np.flatnonzero(mask) if mark_reach(alpha, seeds, mask) else None
        a = [alpha[i][seeds] for i in range(4)]
        if seeds.size and (min(x.min() for x in a) < 0 or max(x.max() for x in a) >= n):
            return None  # let the full check name the problem
        reach = list(a)
        for i, j in ((0, 2), (0, 3), (1, 3)):
            reach.append(alpha[j][a[i]])  # a_j a_i S
            reach.append(alpha[j][alpha[i][a[j]]])  # a_j a_i a_j S
        mask[np.concatenate(reach)] = True
        return np.flatnonzero(mask)

    def is_valid(self) -> bool:
        """True when :meth:`validity_problems` finds nothing."""
        return not self.validity_problems()

    def is_orientable(self) -> bool:
        """True when every connected component of the map can be oriented (CGAL's ``is_orientable``).

        A component is orientable when its darts split into two classes that every
        involution swaps (the dart graph of alpha0..alpha3 is bipartite); a free
        dart (``alpha_i(d) == d``) is a boundary, not a twist.  One connected-
        components pass on the double cover (dart, class).

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3(); _ = gm.add_prisms(4)
        >>> gm.is_orientable()
        True
        """
        n = self.n_darts
        if n == 0:
            return True
        alpha = self.alpha.astype(np.int64)
        own = np.arange(n)
        free = alpha == own
        # (d, 0) -> (alpha_i d, 1) and (d, 1) -> (alpha_i d, 0); a free dart stays in its class
        rows = np.concatenate([np.where(free, own, alpha + n), np.where(free, own + n, alpha)], axis=1)
        comp, _ = orbit_labels(rows)
        return bool(np.all(comp[:n] != comp[n:]))

    def check(self) -> Self:
        """Raise :class:`GMapError` listing the problems if the map is not valid."""
        problems = self.validity_problems()
        if problems:
            raise GMapError("invalid 3-G-map: " + "; ".join(problems))
        return self

    # ------------------------------------------------------------------ embedding
    def embed(self) -> np.ndarray:
        """Place every vertex at the weighted barycentre of its incident volumes' default corners.

        Each dart's ``corner`` holds its volume's default corner (set by
        :meth:`add_prisms`, interpolated by operations, re-derived by
        :func:`ramure.gmap.kernel.embedding.reframe`); ``point`` receives the
        embedded position.  A volume counts once per vertex however many of
        its darts meet there (once per corner, its ``<a1,a2>`` orbit), with its ``weight`` (volume column, default 1);
        where a vertex touches a volume flagged ``exclusive`` (the thesis's
        ``seulPourPl``: a branch base), only the exclusive volumes count, so
        the trunk's slot takes the branch's shape.  Corners are never
        overwritten, so embedding after every step or once at the end gives
        the same positions.  The ``radial`` scalar is averaged the same way.
        Returns the vertex positions.
        """
        if not self.n_darts:
            return np.zeros((0, 3))
        corners, points = self._darts["corner"], self._darts["point"]
        radial = self._darts["radial"]
        any_radial = bool(radial.any())  # all zero stays zero
        compiled = compiled_pays(self.n_darts)  # both paths sum in dart order: the same positions
        if compiled and not any_radial:  # the vertex labels in two levels: no per-dart gather
            state = self._orbit_state(CELL_INVOLUTIONS[0])
            raw, find, count = state.raw[: self.n_darts], state.find, state.count
        else:
            ids, count = self.cells(0)
            raw, find = ids, np.arange(count, dtype=ids.dtype)
        vol = self.dart_volume
        vweight = self._volumes["weight"]
        exclusive = self._volumes["exclusive"]
        if np.all(vweight == 1.0):
            if compiled and "corner_weights" not in self._cache:  # one pass, no per-dart sizes kept (16 bytes a dart)
                from ._embed_kernel import inverse_orbit_sizes

                corner = self._orbit_state((1, 2))
                weight = inverse_orbit_sizes(corner.raw[: self.n_darts], corner.find, corner.count)
            else:
                weight = self._inverse_corner_sizes()
        else:
            weight = vweight[vol].astype(float) / self._corner_sizes()
        any_exclusive = bool(exclusive.any())
        skip_in_pass = compiled and any_exclusive and not any_radial  # the compiled pass leaves those darts out
        if any_exclusive and not skip_in_pass:
            excl = exclusive[vol]
            at_excl = np.zeros(count, bool)
            at_excl[ids[excl]] = True
            weight = np.where(at_excl[ids] & ~excl, 0.0, weight)
        if compiled:
            from ._embed_kernel import exclusive_sums, scatter, weighted_sums

            weight = np.ascontiguousarray(weight, np.float64)
            if skip_in_pass:
                pos, total, ok = exclusive_sums(raw, find, weight, corners, count, vol, exclusive)
                if not ok:
                    raise GMapError("embedding: a dart points to no volume")
            else:
                pos, total = weighted_sums(raw, find, weight, corners, count)
        else:
            total = np.bincount(ids, weight, minlength=count)
            pos = np.column_stack([np.bincount(ids, weight * corners[:, j], minlength=count) for j in range(3)])
        if np.any(total <= 0):
            raise GMapError("embedding: a vertex has only volumes of weight 0 around it")
        pos /= total[:, None]
        if compiled:
            scatter(points, pos, raw, find)
        else:
            points[:] = pos[ids]
        if any_radial:
            radial[:] = np.take(np.bincount(ids, weight * radial, minlength=count) / total, ids)
        return pos

    def _corner_sizes(self):
        """Darts per corner of every dart: the size of its ``<a1,a2>`` orbit (a volume at a vertex).

        A volume that is a ball meets a vertex in one corner, so this is the
        number of its darts at that vertex (cached until the map changes).
        """
        return self._corner_weights()[0]

    def _inverse_corner_sizes(self):
        """``1 / _corner_sizes()`` (cached until the map changes): each corner's darts weigh 1 in all."""
        return self._corner_weights()[1]

    def _corner_weights(self):
        """``(sizes, 1 / sizes)`` per dart of its ``<a1,a2>`` orbit, cached until the map changes.

        After growth that leaves the old corners' orbits as they were (the
        usual case: alpha1 and alpha2 have no free dart in a valid map), the
        old darts keep their values and only the new darts' are computed;
        the arrays have room to grow in place.
        """
        if "corner_weights" not in self._cache:
            state = self._orbit_state((1, 2))
            n = self.n_darts
            memo = self.__dict__.get("_corner_memo")
            if memo is not None and state.base == memo[0] and memo[1] <= n:
                _, n_old, sizes, inverse = memo
                if n > len(sizes):  # more room: the old values move over, they still hold
                    room = max(n + n // 2 + 16, self._alpha.shape[1]) - n_old
                    sizes, inverse = (np.concatenate([a[:n_old], np.empty(room)]) for a in (sizes, inverse))
                loc = state.new_loc
                new = np.take(np.bincount(loc, minlength=int(loc.max(initial=-1)) + 1).astype(float), loc)
                sizes[n_old:n] = new
                inverse[n_old:n] = 1.0 / new
            else:
                ids = state.labels()
                sizes = np.empty(max(n + n // 2 + 16, self._alpha.shape[1]))  # room for growth (the reserve)
                inverse = np.empty_like(sizes)
                counts = np.bincount(ids, minlength=state.count).astype(float)
                np.take(counts, ids, out=sizes[:n], mode="clip")  # ids < count; 'raise' would buffer out
                np.divide(1.0, sizes[:n], out=inverse[:n])
            self._corner_memo = (state.sid, n, sizes, inverse)
            self._cache["corner_weights"] = (sizes[:n], inverse[:n])
        return self._cache["corner_weights"]

    def volume_means(self, values: np.ndarray) -> np.ndarray:
        """Mean of a per-dart vertex quantity over each volume's distinct corners.

        A volume counts each of its vertices once, however many of its darts
        meet there.  ``values`` is (n_darts,) or (n_darts, k).

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3(); _ = gm.add_prisms(4)
        >>> gm.volume_means(gm.points).round(6).tolist()
        [[0.5, 0.0, 0.0]]
        """
        values = np.asarray(values, float)
        flat = values.reshape(len(values), -1)
        vol = self.dart_volume
        weight = 1.0 / self._corner_sizes() if len(vol) else np.zeros(0)
        nv = self.n_volumes
        total = np.maximum(np.bincount(vol, weight, minlength=nv), 1e-300)
        out: np.ndarray = np.stack([np.bincount(vol, weight * flat[:, j], minlength=nv) for j in range(flat.shape[1])], axis=1)
        out /= total[:, None]
        return out.reshape((nv,) + values.shape[1:])

    def volume_centroids(self) -> np.ndarray:
        """Mean of each volume's distinct corners, shape (n_volumes, 3)."""
        return self.volume_means(self.points)

    def transform(self, rotation: ArrayLike | None = None, scale: float = 1.0, offset: ArrayLike | None = None) -> None:
        """Move the map in place: ``p -> scale * p @ rotation + offset``.

        ``rotation`` (3, 3) acts on row vectors.  Volume origins, frames and
        sizes follow, so the stored frames stay those of the moved volumes.

        >>> from ramure.gmap import GMap3
        >>> import numpy as np
        >>> gm = GMap3(); _ = gm.add_prisms(4)
        >>> gm.transform(scale=2.0, offset=[0, 0, 1])
        >>> float(gm.points[:, 2].max()), float(gm.volume_data["size"][0, 0])
        (2.0, 2.0)
        """
        rot = np.eye(3) if rotation is None else np.asarray(rotation, float)
        off = np.zeros(3) if offset is None else np.asarray(offset, float)

        def move(p):  # einsum: BLAS matmul is slow on tall (n, 3) arrays
            return scale * np.einsum("ni,ij->nj", p, rot) + off

        for name in ("point", "corner"):
            pts = self._darts[name]
            pts[:] = move(pts)
        vols = self._volumes
        vols["origin"][:] = move(vols["origin"])
        vols["frame"][:] = np.einsum("vki,ij->vkj", vols["frame"], rot)
        vols["size"][:] *= scale

    # ------------------------------------------------------------------ boundary
    def boundary(self) -> Boundary:
        """The boundary surface: a 2-G-map on the alpha3-free darts.

        Its alpha0 and alpha1 are restrictions; its alpha2 of a dart is found by
        iterating ``alpha2 alpha3`` from ``alpha2(d)`` until an alpha3-free dart.

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3(); _ = gm.add_prisms(4)
        >>> b = gm.boundary()
        >>> b.counts(), b.euler_characteristic()
        ({'darts': 48, 'vertices': 8, 'edges': 12, 'faces': 6}, 2)
        """
        alpha = self.alpha
        darts = np.flatnonzero(alpha[3] == np.arange(self.n_darts))
        x = alpha[2][darts]
        for _ in range(self.n_darts + 1):
            inner = alpha[3][x] != x
            if not inner.any():
                break
            x[inner] = alpha[2][alpha[3][x[inner]]]
        local = np.full(self.n_darts, -1, np.int64)
        local[darts] = np.arange(len(darts))
        sub = np.stack([local[alpha[0][darts]], local[alpha[1][darts]], local[x]])
        return Boundary(self, darts, sub)

    def boundary_euler_characteristic(self) -> int:
        """``V - E + F`` of :meth:`boundary` (2 for a sphere).

        Where compiled passes pay, one pass builds the surface and counts its
        cells without making the :class:`Boundary`; the counts are the same.
        """
        if compiled_pays(self.n_darts):
            from ramure.gmap.kernel._components_kernel import boundary_counts

            v, e, f, ok = boundary_counts(self.alpha, self.n_darts)
            if ok:
                return int(v - e + f)
        return int(self.boundary().euler_characteristic())

    def __repr__(self) -> str:
        return f"GMap3(darts={self.n_darts}, volumes={self.n_volumes})"


class Boundary:
    """A 2-G-map on the alpha3-free darts of a :class:`GMap3` (see :meth:`GMap3.boundary`).

    ``darts`` are the parent's dart ids; ``alpha`` (3, m) uses local indices.
    """

    def __init__(self, gmap: MapStorage, darts: np.ndarray, alpha: np.ndarray) -> None:
        self.gmap = gmap
        self.darts = darts
        self.alpha = alpha

    def orbit_ids(self, involutions: str | Sequence[int]) -> tuple[np.ndarray, int]:
        key = sorted({int(i) for i in involutions})
        return orbit_labels(self.alpha, select=key)

    def counts(self) -> dict[str, int]:
        return {
            "darts": len(self.darts),
            "vertices": self.orbit_ids("12")[1],
            "edges": self.orbit_ids("02")[1],
            "faces": self.orbit_ids("01")[1],
        }

    def euler_characteristic(self) -> int:
        """``V - E + F`` of the surface (2 for a sphere)."""
        c = self.counts()
        return c["vertices"] - c["edges"] + c["faces"]
