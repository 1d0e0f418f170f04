"""Topological operations of :class:`ramure.gmap.GMap3`, on its storage (a base class of GMap3).

Create labelled prisms in bulk, alpha3-sew and unsew faces, split an edge, a
face or a volume, remove volumes.  Every operation works on arrays of darts and
copies per-dart data (volume, face label, sub-label) to the darts it creates;
new darts get their point on the geometry of their own volume (an edge split
puts the new vertex on the segment, a face split reuses the face's corners).

>>> from ramure.gmap import GMap3
>>> gm = GMap3()
>>> a, b = gm.add_prisms(4, 2, origins=[[0, 0, 0], [1, 0, 0]])
>>> gm.sew3(gm.prism_face(a, 4, "E"), gm.prism_face(b, 4, "O"))
>>> gm.counts()["vertices"], gm.is_valid()
(12, True)
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel import prism as _prism
from ramure.gmap.kernel.errors import GMapError, ValueRefused
from ramure.gmap.kernel.graphs import compiled_pays
from ramure.gmap.kernel.storage import MapStorage

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3

_BUILTIN_SET = {"volume", "face", "sublabel", "fcorner", "forward", "point", "radial", "corner", "vcorner", "sup", "supt"}
#: per-dart columns :meth:`Operations.add_prisms` writes itself (no default fill first)
#: Highest prism order: a face's corner codes and a volume's degree are int16, and a round
#: trunk needs tens of sides, not thousands.
MAX_PRISM_ORDER = 4096
#: Most darts a map holds: alpha stores dart ids as int32.
MAX_MAP_DARTS = 2**31 - 1
#: The involutions that commute with alpha_i (``|i - j| >= 2``): sewing by alpha_i links whole orbits of them.
_SEW_ORBIT = {0: (2, 3), 1: (3,), 2: (0,), 3: (0, 1)}


def _dimension(i):
    """``i`` as a G-map dimension 0..3, or GMapError."""
    if not isinstance(i, (int, np.integer)) or isinstance(i, bool) or not 0 <= i <= 3:
        raise GMapError(f"the dimension i of an i-sew must be 0, 1, 2 or 3, got {i!r}")
    return int(i)


_PRISM_WRITES = ("volume", "face", "sublabel", "fcorner", "forward", "corner", "point", "vcorner", "sup")


def _darts(x: ArrayLike) -> np.ndarray:
    return np.atleast_1d(np.asarray(x, dtype=np.int64))


def _walked(walk: np.ndarray) -> np.ndarray:
    """The darts of face walks (rows padded with -1), row after row: a view when nothing is padded."""
    return walk.ravel() if walk.size == 0 or walk.min() >= 0 else walk[walk >= 0]


def _label_code(label):
    """Face label code of ``label`` (a name such as ``'C3'`` or a code), as GMapError when unknown."""
    if isinstance(label, (int, np.integer)):
        return int(label)
    try:
        return _prism.face_label_code(label)
    except ValueError as exc:
        raise GMapError(str(exc)) from None


class Operations(MapStorage):
    """The operations of a 3-G-map, on its storage; see the module docstring."""

    def _map(self) -> GMap3:
        """This map as the GMap3 it is (the only subclass of Operations), for the face and
        glue modules' functions, which take a GMap3."""
        return cast("GMap3", self)

    # ------------------------------------------------------------------ creation
    def add_prisms(
        self,
        n: int,
        count: int = 1,
        origins: ArrayLike | None = None,
        frames: ArrayLike | None = None,
        sizes: ArrayLike | None = None,
        label: str = "A",
        **volume_values: Any,
    ) -> np.ndarray:
        """Create ``count`` free prisms of order ``n`` (12 n darts each) in one go.

        ``origins`` (count, 3) are the centres of the O faces, ``frames``
        (count, 3, 3) the rows H, L, U, ``sizes`` (count, 3) the (H, L, W)
        extents (default a unit box).  Darts get their volume's default
        corners as points.  Extra keyword arguments set volume attributes
        (``tissue=``, ``order=``, ``stage=``, ...).  Returns the first dart of
        each prism; prism ``p`` owns darts ``first[p] .. first[p] + 12 n - 1``.

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3()
        >>> first = gm.add_prisms(10, 3, label="A", order=0, stage=[0, 1, 2])
        >>> first.tolist(), gm.n_darts, gm.volume_data["stage"].tolist()
        ([0, 120, 240], 360, [0, 1, 2])
        """
        n, count = int(n), int(count)
        if not 3 <= n <= MAX_PRISM_ORDER:
            raise ValueRefused(f"prism order must be from 3 to {MAX_PRISM_ORDER}, got {n}")
        if count < 0:
            raise ValueRefused(f"prism count must be at least 0, got {count}")
        if self.n_darts + 12 * n * count > MAX_MAP_DARTS:
            raise ValueRefused(f"{count:,} prisms of order {n} would pass the map's limit of {MAX_MAP_DARTS:,} darts")
        t = _prism.template(n)
        unit = origins is None and frames is None and sizes is None  # every prism gets the unit prism's corners
        origins = np.zeros((count, 3)) if origins is None else np.broadcast_to(np.asarray(origins, float), (count, 3))
        frames = (
            np.broadcast_to(np.eye(3), (count, 3, 3))
            if frames is None
            else np.broadcast_to(np.asarray(frames, float), (count, 3, 3))
        )
        sizes = np.ones((count, 3)) if sizes is None else np.broadcast_to(np.asarray(sizes, float), (count, 3))
        darts = self._new_darts(count * t.size, skip=_PRISM_WRITES, free=(3,))  # alpha0..2 written below
        base = int(darts[0]) if count else self.n_darts
        first = base + t.size * np.arange(count)
        rows = slice(base, base + count * t.size)  # the new darts, prism after prism

        def per_prism(column):  # (count, t.size, ...) view of the new rows
            return column[rows].reshape((count, t.size) + column.shape[1:])

        alpha = self._alpha
        first32 = first.astype(alpha.dtype)[:, None]  # dart ids fit alpha's int32 (the dart limit)
        for i in range(3):
            np.add(first32, t.alpha[i][None, :], out=per_prism(alpha[i]))
        volumes = self._new_volumes(count, label=label, degree=n, origin=origins, frame=frames, size=sizes, **volume_values)
        d = self._darts
        per_prism(d["volume"])[:] = volumes[:, None]
        per_prism(d["face"])[:] = t.face[None, :]
        d["sublabel"][rows] = 0
        per_prism(d["fcorner"])[:] = t.fcorner[None, :]
        per_prism(d["forward"])[:] = t.forward[None, :]
        corner = per_prism(d["corner"])
        if unit:
            corner[:] = _prism.unit_corners(n)[t.corner][None]
        else:  # gathered straight into the rows: no (count, darts, 3) temporary
            # mode='clip': the template's corner ids are valid, and 'raise' buffers out (2.5x slower)
            np.take(_prism.corners(n, origins, frames, sizes), t.corner, axis=1, out=corner, mode="clip")
        per_prism(d["point"])[:] = corner
        per_prism(d["vcorner"])[:] = t.corner[None, :]
        d["sup"][rows] = -1
        for name, rule in self._rules.items():
            if name not in _BUILTIN_SET:
                d[name][rows] = self.dart_fill(name)
        self.mark_changed()
        return first

    @staticmethod
    def prism_face(first: ArrayLike, n: int, face: str, j: int = 0) -> int | np.ndarray:
        """Dart ``j`` of face ``face`` ('O', 'E', 'C1'..'Cn') of prisms starting at ``first``.

        ``j = 0`` is the face's forward dart at its corner 0 (for ``Ck``, the
        base corner k-1).

        >>> Operations.prism_face(0, 4, "C2")
        24
        """
        code = _prism.face_label_code(face)
        n = int(n)
        if code == _prism.FACE_O:
            off = 0
        elif code == _prism.FACE_E:
            off = 2 * n
        elif 2 <= code <= n + 1:
            off = 4 * n + 8 * (code - 2)
        else:
            raise GMapError(f"a prism of order {n} has no face {face!r}")
        out = np.asarray(first) + off + j
        return int(out) if out.ndim == 0 else out

    # ------------------------------------------------------------------ faces by label
    def face_of(
        self,
        volumes: ArrayLike,
        label: str | int | Sequence[str | int] | np.ndarray,
        sublabel: ArrayLike | None = None,
        missing: str = "raise",
    ) -> int | np.ndarray:
        """Anchor dart of face ``label`` (O, E, C1..Cn, I) of each volume; see :mod:`ramure.gmap.kernel.faces`.

        Robust to split and sewn faces (labels ride on the darts).  Returns
        an int for an int volume, else an array.

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3(); _ = gm.add_prisms(4)
        >>> gm.face_of(0, "C2") == gm.prism_face(0, 4, "C2")
        True
        """
        from ramure.gmap.kernel import faces

        out = faces.face_of(self._map(), volumes, label, sublabel, missing)
        return int(out[0]) if np.ndim(volumes) == 0 else out

    def face_darts(
        self, volumes: ArrayLike, label: str | int | Sequence[str | int], sublabel: ArrayLike | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """All darts of face ``label`` of each volume: ``(darts, which)``; see :mod:`ramure.gmap.kernel.faces`."""
        from ramure.gmap.kernel import faces

        return faces.face_darts(self._map(), volumes, label, sublabel)

    def identify(self, a: ArrayLike, b: ArrayLike) -> None:
        """Glue the free faces of ``a[i]`` and ``b[i]`` that share an edge; see :mod:`ramure.gmap.kernel.identify`."""
        from ramure.gmap.kernel import identify

        identify.identify(self._map(), a, b)

    # ------------------------------------------------------------------ faces
    def face_walk(self, starts: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Walk the faces ``<a0,a1>`` of ``starts``: ``d, a0 d, a1 a0 d, ...``.

        Returns ``(walk, lengths)``: walk (k, L) padded with -1 and the number
        of darts of each face (twice its degree).

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3(); _ = gm.add_prisms(5)
        >>> walk, lengths = gm.face_walk([0, 20])
        >>> lengths.tolist(), walk[0, :4].tolist()
        ([10, 8], [0, 1, 2, 3])
        """
        starts = _darts(starts)
        a0, a1 = self._alpha[0], self._alpha[1]
        if compiled_pays(self.n_darts):  # the same walk dart by dart: the calls, not the darts, cost here
            from ramure.gmap.kernel._walk_kernel import face_walks

            walk, lengths, ok = face_walks(a0, a1, starts, self.n_darts, self.n_darts + 2)
            if ok:
                return walk, lengths
        k = len(starts)
        idx: np.ndarray | None = None  # faces still open (None: all of them)
        cur, first = starts, starts
        lengths = np.zeros(k, np.int64)
        steps: list[tuple[np.ndarray | None, np.ndarray]] = []
        step = 0
        while cur.size:  # only faces still open are walked on
            steps.append((idx, cur))
            cur = a0[cur]
            steps.append((idx, cur))
            cur = a1[cur]
            step += 2
            go = cur != first
            if not go.all():  # some faces closed: they have ``step`` darts
                done = ~go
                lengths[done if idx is None else idx[done]] = step
                idx = np.flatnonzero(go) if idx is None else idx[go]
                cur, first = cur[go], first[go]
            if step > self.n_darts + 2:
                raise GMapError("face walk does not close: the map is not valid")
        if k and all(rows is None for rows, _ in steps):
            # every face closed at the last step (faces of one degree): no padding to write
            return np.stack([values for _, values in steps], axis=1).astype(np.int64, copy=False), lengths
        walk = np.full((k, step), -1, np.int64)
        for j, (rows, values) in enumerate(steps):
            if rows is None:
                walk[:, j] = values
            else:
                walk[rows, j] = values
        return walk, lengths

    def sew3(self, a: ArrayLike, b: ArrayLike) -> None:
        """alpha3-sew the free faces of darts ``a`` and ``b`` (arrays pair up element-wise).

        Walking both faces in lock-step from ``a`` and ``b`` (``a0``, then
        ``a1``, ...) pairs their darts, so alpha3 commutes with alpha0 and
        alpha1.  ``a`` and ``b`` must therefore sit at the same corner of the
        same edge.  When a single pair of faces differs in degree, edges of
        the smaller face are split (evenly, starting at ``a``'s edge) until the
        degrees match; the new vertices are spaced evenly along the edges.
        (:meth:`identify` finds the start darts itself from the shared edge
        and splits edge runs by face side; prefer it.)  A refused sew raises
        :class:`GMapError` and leaves the map unchanged.
        """
        a, b = self.check_darts(a), self.check_darts(b)
        if a.shape != b.shape:
            raise GMapError(f"sew3 needs as many darts on each side, got {len(a)} and {len(b)}")
        wa, la = self.face_walk(a)
        wb, lb = self.face_walk(b)
        self.check_sewable(wa, wb)
        if np.all(la == lb):
            self.sew_walks(wa, wb)
            return
        if len(a) != 1:
            raise GMapError("faces of different degrees can only be sewn one pair at a time")
        with self.atomic(self.edge_zone(np.concatenate([wa.ravel(), wb.ravel()]))):
            small, big = (a, lb[0]) if la[0] < lb[0] else (b, la[0])
            self.split_face_edges(int(small[0]), int(min(la[0], lb[0]) // 2), int(big // 2))
            wa, la = self.face_walk(a)
            wb, lb = self.face_walk(b)
            if la[0] != lb[0]:
                raise GMapError(
                    f"sew3: the faces of darts {int(a[0])} and {int(b[0])} share an edge, so splitting one "
                    "splits the other and their degrees cannot be matched"
                )
            self.check_sewable(wa, wb)
            self.sew_walks(wa, wb)

    def edge_zone(self, darts: ArrayLike) -> np.ndarray:
        """Darts of every edge ``<a0,a2,a3>`` through ``darts``: all an edge split there may edit."""
        darts = np.asarray(darts, np.int64).reshape(-1)
        darts = darts[darts >= 0]
        if darts.size == 0:
            return darts
        members, _ = self.orbits_from(np.unique(darts), (0, 2, 3), strict=False)
        return members

    def _volume_zone(self, dart, edges=None):
        """Old darts a split of the volume of ``dart`` may edit.

        Its darts, their alpha3 partners (faces split on both sides) and the
        whole orbits of the edges in ``edges`` (the edges it splits); without
        ``edges``, of every edge of the volume.
        """
        vol, _ = self.orbits_from([int(dart)], (0, 1, 2))
        if edges is None:
            return self.edge_zone(vol)
        return np.concatenate([vol, self._alpha[3][vol], self.edge_zone(edges)])

    def check_darts(self, darts: ArrayLike) -> np.ndarray:
        """``darts`` as a flat int64 array; :class:`GMapError` when an id is not a dart of the map."""
        d = _darts(darts)
        if d.size and (d.min() < 0 or d.max() >= self.n_darts):
            raise GMapError(f"dart ids must be in 0..{self.n_darts - 1}")
        return d

    def check_sewable(self, wa: np.ndarray, wb: np.ndarray) -> None:
        """Refuse sewing faces that are not alpha3-free, or that overlap.

        ``wa``, ``wb``: face walks as :meth:`face_walk` returns them (rows
        padded with -1), matched dart for dart.
        """
        da, db = _walked(wa), _walked(wb)
        a3 = self._alpha[3]
        for side, d in (("first", da), ("second", db)):
            busy = d[a3[d] != d]
            if busy.size:
                raise GMapError(f"sew3 needs alpha3-free faces; the {side} face of dart {int(busy[0])} is sewn already")
        both = np.concatenate([da, db])
        mark = self._marks()  # O(faces), not O(darts of the map)
        order = np.arange(len(both))
        mark[both] = order
        twice = np.any(mark[both] != order)
        mark[both] = -1
        if twice:
            raise GMapError("sew3 would sew a face to itself or use a face twice")

    def sew_walks(self, wa: np.ndarray, wb: np.ndarray) -> None:
        """Set alpha3 between matched face walks ``wa``, ``wb`` (-1 padding ignored); no checks.

        The caller checks first (:meth:`check_sewable`, equal degrees); this
        is the raw step :meth:`sew3` and :func:`ramure.gmap.kernel.identify.identify` share.
        """
        if wa.size == 0 or wa.min() >= 0:  # no padding: the walks as they are
            da, db = wa.ravel(), wb.ravel()
        else:
            keep = wa >= 0
            da, db = wa[keep], wb[keep]
        alpha = self._alpha
        alpha[3][da] = db
        alpha[3][db] = da
        self.mark_changed()

    def split_face_edges(self, dart: int, degree: int, target: int) -> None:
        """Split the ``degree`` edges of ``dart``'s face evenly so that it gets ``target`` edges."""
        parts = np.full(degree, target // degree)
        parts[: target % degree] += 1
        walk, _ = self.face_walk([dart])
        edge_darts = walk[0, 0 : 2 * degree : 2]
        for d, m in zip(edge_darts, parts):
            current = int(d)
            for step in range(int(m) - 1, 0, -1):
                # cut 1/(step+1) of what is left, so the m pieces are equal
                new = self.split_edge([current], 1.0 / (step + 1))
                current = int(self._alpha[1][new[0]])

    def unsew3(self, darts: ArrayLike) -> None:
        """Make the faces of ``darts`` alpha3-free again (and their partners)."""
        walk, _ = self.face_walk(self.check_darts(darts))
        d = walk[walk >= 0]
        partners = self._alpha[3][d].copy()
        self._alpha[3][d] = d
        self._alpha[3][partners] = partners
        self.mark_changed()

    # ------------------------------------------------------------------ i-sewing (CGAL's sew<i>, unsew<i>)
    def sew(self, i: int, a: ArrayLike, b: ArrayLike) -> None:
        """i-sew dart ``a`` to dart ``b`` (arrays pair up element-wise), for ``i`` in 0..3.

        As CGAL's ``sew<i>``: the orbits of ``a`` and ``b`` under the involutions
        that commute with alpha_i (alpha_j with ``|i - j| >= 2``: ``<a2,a3>`` for
        i = 0, ``<a3>`` for 1, ``<a0>`` for 2, the face ``<a0,a1>`` for 3) are
        walked in lock-step and linked dart for dart by alpha_i, so the map stays
        valid.  ``sew(3, a, b)`` is :meth:`sew3` (faces of different degrees
        included).  Only the involutions change: per-dart attributes and points
        are the caller's.  Refused, the map unchanged, unless :meth:`is_sewable`.
        (:meth:`is_valid` also asks for closed volumes, no free alpha0..alpha2: a
        map unsewn below dimension 3 is a valid G-map, but open until sewn again.)

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3(); _ = gm.add_prisms(4)
        >>> partner = int(gm.alpha[2][0])
        >>> gm.unsew(2, 0); gm.counts()["edges"], gm.is_sewable(2, 0, partner)
        (13, True)
        >>> gm.sew(2, 0, partner); gm.counts()["edges"], gm.is_valid()
        (12, True)
        """
        if i == 3:
            self.sew3(a, b)
            return
        da, db = self._sew_orbits(_dimension(i), a, b)
        self._alpha[i][da] = db
        self._alpha[i][db] = da
        self.mark_changed()

    def unsew(self, i: int, a: ArrayLike) -> None:
        """Make the darts of ``a`` i-free again, with their orbits and partners (CGAL's ``unsew<i>``).

        The orbit of each dart under the involutions that commute with alpha_i
        (see :meth:`sew`) is unsewn, so the map stays valid; ``unsew(3, a)`` is
        :meth:`unsew3` (which, unlike this, lets free faces be).  Refused, the map
        unchanged, when a dart is i-free already.
        """
        i = _dimension(i)
        d = self.check_darts(a)
        if np.any(self._alpha[i][d] == d):
            raise GMapError(f"unsew({i}): dart {int(d[self._alpha[i][d] == d][0])} is {i}-free already")
        if i == 3:
            self.unsew3(d)
            return
        members, _ = self.orbits_from(np.unique(d), _SEW_ORBIT[i], strict=False)
        partners = self._alpha[i][members].copy()
        self._alpha[i][members] = members
        self._alpha[i][partners] = partners
        self.mark_changed()

    def is_sewable(self, i: int, a: ArrayLike, b: ArrayLike) -> bool:
        """Whether :meth:`sew` ``(i, a, b)`` would sew (a bool; nothing changes either way)."""
        try:
            if _dimension(i) < 3:
                self._sew_orbits(i, a, b)
                return True
            da, db = self.check_darts(a), self.check_darts(b)
            if da.shape != db.shape:
                return False
            (wa, la), (wb, lb) = self.face_walk(da), self.face_walk(db)
            self.check_sewable(wa, wb)
            if np.all(la == lb):
                return True
            if len(da) != 1:
                return False
            trial = self.copy()  # degrees differ: only splitting the smaller face tells (rare, one pair)
            trial.sew3(da, db)
            return True
        except GMapError:
            return False

    def _sew_orbits(self, i, a, b):
        """Matched darts ``(da, db)`` of the lock-step orbits :meth:`sew` links by alpha_i; GMapError if none."""
        a, b = self.check_darts(a), self.check_darts(b)
        if a.shape != b.shape:
            raise GMapError(f"sew({i}) needs as many darts on each side, got {len(a)} and {len(b)}")
        alpha = self._alpha
        da, db = a, b
        for j in _SEW_ORBIT[i]:  # the involutions commute, so the orbit is d, aj d, ak d, ak aj d
            da, db = np.concatenate([da, alpha[j][da]]), np.concatenate([db, alpha[j][db]])
        ua, ia = np.unique(da, return_inverse=True)
        ub, ib = np.unique(db, return_inverse=True)
        if len(np.unique(ia * len(ub) + ib)) != len(ua) or len(ua) != len(ub):
            raise GMapError(f"sew({i}): the orbits of the two sides do not have the same shape, or a dart is used twice")
        first = np.unique(ia, return_index=True)[1]
        da, db = ua, db[first]
        if np.any(alpha[i][da] != da) or np.any(alpha[i][db] != db):
            raise GMapError(f"sew({i}) needs {i}-free darts; one of them is {i}-sewn already")
        if np.intersect1d(da, db).size:
            raise GMapError(f"sew({i}) would sew an orbit to itself")
        return da, db

    # ------------------------------------------------------------------ splits
    def _set_support(self, new, a, b, t) -> None:
        """Record that the default corner of ``new`` is ``(1 - t) corner(a) + t corner(b)``."""
        d = self._darts
        d["sup"][new, 0] = a
        d["sup"][new, 1] = b
        d["supt"][new] = t

    def split_edge(self, darts: ArrayLike, t: ArrayLike = 0.5) -> np.ndarray:
        """Split the edges of ``darts`` (one dart per edge) at fraction ``t`` from each dart.

        The whole edge ``<a0,a2,a3>`` is split: every face and volume around
        it gets the new vertex.  Returns, for each given dart ``d``, the new
        dart ``a0(d)`` that sits at the new vertex on ``d``'s side.

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3(); _ = gm.add_prisms(4)
        >>> new = gm.split_edge([0])
        >>> gm.n_darts, gm.counts()["vertices"], gm.is_valid()
        (52, 9, True)
        """
        darts = _darts(darts)
        darts = self.check_darts(darts)
        t = np.broadcast_to(np.asarray(t, float), darts.shape)
        if not np.all((t > 0) & (t < 1)):
            raise GMapError("split_edge fractions must lie strictly between 0 and 1")
        members, which = self.orbits_from(darts, (0, 2, 3))
        side, side_which = self.orbits_from(darts, (2, 3))
        same_side = np.zeros(len(members), bool)
        same_side[np.searchsorted(members, side)] = True  # side darts are members too
        frac = np.where(same_side, t[which], 1.0 - t[which])
        alpha = self._alpha
        old_a0 = alpha[0][members].astype(np.int64)
        # every column (by its rule) and every alpha row of the new darts is written below: no fill pass
        new = self._new_darts(len(members), skip=tuple(self._rules), free=()).astype(np.int64)
        alpha = self._alpha

        def nmap(x):  # old member dart -> its new dart
            return new[np.searchsorted(members, x)]

        alpha[0][members] = new
        alpha[0][new] = members
        alpha[1][new] = nmap(old_a0)
        alpha[2][new] = nmap(alpha[2][members])
        alpha[3][new] = nmap(alpha[3][members])
        self._propagate(new, members, old_a0, frac)
        self._set_support(new, members, old_a0, frac)
        fw = self._darts["forward"]
        fw[new] = ~fw[members]
        self.mark_changed()
        return nmap(darts)

    def split_face(self, d1: int, d2: int) -> tuple[int, int]:
        """Split the face of ``d1`` by a new edge from ``d1``'s vertex to ``d2``'s vertex.

        ``d1`` and ``d2`` belong to one face ``<a0,a1>`` and sit at two
        vertices that are neither equal nor adjacent.  A face sewn by alpha3
        is split on both sides.  Both halves keep the face label.  Returns
        the two new darts at ``d1``'s vertex (in the half holding ``a0(d1)``
        and in the other half).

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3(); _ = gm.add_prisms(4)
        >>> _ = gm.split_face(0, 4)          # cut the O square along its diagonal
        >>> gm.counts()["faces"], gm.counts()["edges"], gm.is_valid()
        (7, 13, True)
        """
        d1, d2 = (int(d) for d in self.check_darts([d1, d2]))
        walk, length = self.face_walk([d1])
        walk = walk[0, : length[0]]
        where = np.flatnonzero(walk == d2)
        if where.size == 0:
            raise GMapError(f"darts {d1} and {d2} are not in the same face")
        q = int(where[0])
        if q in (0, len(walk) - 1):
            raise GMapError("split_face needs two different vertices")
        p = q if q % 2 == 1 else q - 1  # the dart at d2's vertex reached by a0
        if p in (1, len(walk) - 3):
            raise GMapError("split_face needs two vertices that are not adjacent")
        x, y, z = int(walk[p]), int(walk[-1]), int(walk[p + 1])
        a3 = self._alpha[3]
        sides = [(d1, x, y, z)]
        if a3[d1] != d1:
            sides.append((int(a3[d1]), int(a3[x]), int(a3[y]), int(a3[z])))
        new = self._new_darts(4 * len(sides)).reshape(len(sides), 4)
        alpha = self._alpha
        fw = self._darts["forward"]
        for (s1, sx, sy, sz), (n1, n2, m1, m2) in zip(sides, new):
            pairs = [(1, sx, n2), (1, n1, s1), (1, sz, m2), (1, m1, sy), (0, n1, n2), (0, m1, m2), (2, n1, m1), (2, n2, m2)]
            for i, u, v in pairs:
                alpha[i][u], alpha[i][v] = v, u
            self._propagate([n1, m1], [s1, s1])
            self._propagate([n2, m2], [sx, sx], skip=("volume", "face", "sublabel"))
            for name in ("volume", "face", "sublabel"):
                self._darts[name][[n2, m2]] = self._darts[name][s1]
            self._set_support([n1, m1], [s1, s1], [s1, s1], 0.0)
            self._set_support([n2, m2], [sx, sx], [sx, sx], 0.0)
            fw[[n1, n2, m1, m2]] = [not fw[s1], fw[s1], fw[s1], not fw[s1]]
        if len(sides) == 2:
            for k in range(4):
                alpha[3][new[0, k]], alpha[3][new[1, k]] = new[1, k], new[0, k]
        self.mark_changed()
        return int(new[0, 0]), int(new[0, 2])

    def split_faces(self, d1: ArrayLike, k2: ArrayLike) -> np.ndarray:
        """Split many faces at once: face of ``d1[i]`` from its vertex to the corner ``k2[i]`` steps on.

        Vectorised :meth:`split_face`: ``k2`` counts corners along the walk
        from ``d1`` (``a0`` first) and must be in ``2 .. degree - 2``.  Each
        face ``<a0,a1,a3>`` may appear once; sewn faces are split on both
        sides.  Returns the new darts at ``d1``'s vertex in the half holding
        ``a0(d1)``.
        """
        d1 = self.check_darts(d1)
        k2 = np.asarray(k2, np.int64).reshape(-1)
        if k2.shape != d1.shape:
            raise GMapError(f"split_faces needs one corner step per dart, got {len(k2)} for {len(d1)} darts")
        walk, length = self.face_walk(d1)
        deg = length // 2
        if np.any((k2 < 2) | (k2 > deg - 2)):
            raise GMapError("split_faces needs two vertices that are neither equal nor adjacent")
        self._check_distinct_faces(walk)
        rows = np.arange(len(d1))
        x = walk[rows, 2 * k2 - 1]
        y = walk[rows, length - 1]
        z = walk[rows, 2 * k2]
        a3 = self._alpha[3]
        sewn = a3[d1] != d1
        s1 = np.concatenate([d1, a3[d1[sewn]]]).astype(np.int64)
        sx = np.concatenate([x, a3[x[sewn]]]).astype(np.int64)
        sy = np.concatenate([y, a3[y[sewn]]]).astype(np.int64)
        sz = np.concatenate([z, a3[z[sewn]]]).astype(np.int64)
        m = len(s1)
        new = self._new_darts(4 * m).astype(np.int64).reshape(4, m)
        n1, n2, m1, m2 = new
        alpha = self._alpha
        for i, u, v in ((1, sx, n2), (1, n1, s1), (1, sz, m2), (1, m1, sy), (0, n1, n2), (0, m1, m2), (2, n1, m1), (2, n2, m2)):
            alpha[i][u], alpha[i][v] = v, u
        k = len(d1)
        other = np.flatnonzero(sewn)
        for row in (n1, n2, m1, m2):
            alpha[3][row] = row
            alpha[3][row[other]] = row[k:]
            alpha[3][row[k:]] = row[other]
        self._propagate(np.concatenate([n1, m1]), np.concatenate([s1, s1]))
        self._propagate(np.concatenate([n2, m2]), np.concatenate([sx, sx]))
        self._set_support(np.concatenate([n1, m1]), np.concatenate([s1, s1]), np.concatenate([s1, s1]), 0.0)
        self._set_support(np.concatenate([n2, m2]), np.concatenate([sx, sx]), np.concatenate([sx, sx]), 0.0)
        fw = self._darts["forward"]
        f1 = fw[s1].copy()
        fw[n1], fw[n2], fw[m1], fw[m2] = ~f1, f1, f1, ~f1
        self.mark_changed()
        return n1[:k]

    def _check_distinct_faces(self, walk: np.ndarray) -> None:
        """Refuse face walks (rows, -1 padded) of which two are one face ``<a0,a1,a3>``: a face
        named twice (two of its darts, or its two sides) would be split twice over."""
        none = np.int64(np.iinfo(np.int64).max)  # an int64 scalar: a Python int would take alpha's int32
        darts = np.where(walk >= 0, walk, none)
        sewn_side = np.where(walk >= 0, self._alpha[3][np.maximum(walk, 0)].astype(np.int64), none)
        key = np.minimum(darts.min(axis=1), sewn_side.min(axis=1))  # the face's smallest dart, either side
        if len(np.unique(key)) != len(key):
            raise GMapError("split_faces names one face twice (two of its darts, or both of its sides)")

    def split_volume(self, path: ArrayLike, labels: Sequence[str | int] = ("E", "O")) -> int:
        """Cut a volume in two along a closed loop of edges on its surface.

        ``path`` holds one dart per loop edge, all on the same side of the
        loop (part 1).  Two new faces close the parts, sewn to each other by
        alpha3: the one closing part 1 gets ``labels[0]``, the other
        ``labels[1]``.  Part 2 becomes a new volume with a copy of the
        attributes.  Returns the new volume id.  A refused split leaves the
        map unchanged.
        """
        codes = [_label_code(x) for x in labels]
        path = _darts(path)
        if path.size == 0 or path.min() < 0 or path.max() >= self.n_darts:
            raise GMapError(f"split_volume needs dart ids in 0..{self.n_darts - 1}")
        with self.atomic(self.orbits_from(path[:1], (0, 1, 2))[0]):
            return int(self.split_volumes(path, codes))

    def split_volumes(self, path: np.ndarray, codes: Sequence[int], many: bool = False) -> int | np.ndarray:
        """Split volumes along closed loops ``path`` (one loop per volume; ``many`` allows several).

        The unchecked kernel of :meth:`split_volume`: ``codes`` are face label
        codes (not names) and the caller wraps the call in :meth:`atomic`.
        Returns the new volume id, or with ``many`` the array of them.
        """
        alpha = self._alpha
        vol = self._darts["volume"]
        if not many and len(np.unique(vol[path])) != 1:
            raise GMapError("split_volume needs a path in one volume")
        p1 = np.unique(np.concatenate([path, alpha[0][path]]))
        if len(p1) != 2 * len(path):
            raise GMapError("split_volume needs one dart per path edge")

        def on_path(x):
            pos = np.minimum(np.searchsorted(p1, x), len(p1) - 1)
            return p1[pos] == x

        a1, a2 = alpha[1], alpha[2]
        # next path dart around each vertex, staying on part 1
        y = a1[p1].astype(np.int64)
        for _ in range(self.n_darts):
            todo = ~on_path(y)
            if not todo.any():
                break
            y[todo] = a1[a2[y[todo]]]
        else:
            raise GMapError("split_volume: the path is not a closed loop")
        if np.any(on_path(a2[p1])):
            raise GMapError("split_volume: the path touches itself")
        old_a2 = a2[p1].astype(np.int64)
        k = len(p1)
        new = self._new_darts(2 * k)
        alpha = self._alpha
        f, g = new[:k], new[k:]
        at = np.searchsorted(p1, alpha[0][p1])  # p1 is sorted and closed under alpha0
        ay = np.searchsorted(p1, y)
        alpha[2][p1], alpha[2][f] = f, p1
        alpha[2][old_a2], alpha[2][g] = g, old_a2
        alpha[0][f], alpha[0][g] = f[at], g[at]
        alpha[1][f], alpha[1][g] = f[ay], g[ay]
        alpha[3][f], alpha[3][g] = g, f
        data = self._darts
        self._propagate(f, p1)
        self._propagate(g, p1)
        self._set_support(f, p1, p1, 0.0)
        self._set_support(g, p1, p1, 0.0)
        data["face"][f] = codes[0]
        data["face"][g] = codes[1]
        data["sublabel"][new] = 0
        old_vols, first = np.unique(vol[p1], return_index=True)
        walk, length = self.face_walk(f[first])
        pos = np.broadcast_to(np.arange(walk.shape[1])[None, :], walk.shape)
        ok = walk >= 0
        w, pos = walk[ok], pos[ok]
        deg = np.broadcast_to((length // 2)[:, None], walk.shape)[ok]
        data["forward"][w] = pos % 2 == 0
        data["fcorner"][w] = ((pos + 1) // 2) % deg
        data["forward"][alpha[3][w]] = data["forward"][w]
        data["fcorner"][alpha[3][w]] = data["fcorner"][w]
        if len(w) != k:
            raise GMapError("split_volume: a volume holds more than one loop")
        self.mark_changed()
        part2, which = self.orbits_from(g[first], (0, 1, 2))
        if np.any(np.isin(part2, f)):
            raise GMapError("split_volume: the path does not separate the volume")
        new_vols = self._new_volumes(len(old_vols))
        for name in self._volumes.names():
            self._volumes[name][new_vols] = self._volumes[name][old_vols]
        data["volume"][part2] = new_vols[which]
        self.mark_changed()
        return new_vols if many else int(new_vols[0])

    def split_prism(self, volume: int, t: float = 0.5, face: int | None = None, labels: Sequence[str | int] = ("E", "O")) -> int:
        """Split prism ``volume`` parallel to one face (thesis rule ``A ->^O B C``).

        ``face`` is a dart of the face to cut parallel to (default: the
        volume's ``O`` face).  The edge leaving each corner of that face is
        split at fraction ``t``, every face around is cut between the new
        vertices (which must not be adjacent) and the volume is cut along the
        new loop.  The part holding ``face`` keeps the volume id;
        the other part is returned.  The new faces get ``labels`` (the kept
        part's first).

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3(); _ = gm.add_prisms(6)
        >>> upper = gm.split_prism(0)
        >>> gm.counts()["volumes"], gm.counts()["vertices"], gm.is_valid()
        (2, 18, True)
        """
        volume = int(volume)
        if not 0 <= volume < self.n_volumes:
            raise GMapError(f"volume ids must be in 0..{self.n_volumes - 1}, got {volume}")
        if not 0.0 < float(t) < 1.0:
            raise GMapError(f"split fraction must be strictly between 0 and 1, got {t}")
        if face is not None and not 0 <= int(face) < self.n_darts:
            raise GMapError(f"dart ids must be in 0..{self.n_darts - 1}, got {face}")
        codes = [_label_code(x) for x in labels]
        if face is not None and int(self._darts["volume"][int(face)]) != volume:
            raise GMapError(f"dart {face} is not in volume {volume}")
        anchor = face
        if anchor is None:
            anchor = int(self.face_of(volume, "O", missing="ignore"))
            if anchor < 0:
                raise GMapError(f"volume {volume} has no O face")
        walk, length = self.face_walk([anchor])
        w = walk[0, : length[0]]
        leaving = self._alpha[1][self._alpha[2][w[0::2]]]
        with self.atomic(self._volume_zone(anchor, leaving)):
            return self._split_prism(volume, float(t), face, codes)

    def _split_prism(self, volume, t, face, labels):
        if face is None:
            face = int(self.face_of(volume, "O"))
        walk, length = self.face_walk([face])
        w = walk[0, : length[0]]
        alpha = self._alpha
        starts = alpha[1][alpha[2][w[0::2]]]  # edges leaving the face, one per corner
        ends = alpha[1][alpha[2][w[1::2]]]  # the same edges seen from the previous side face
        new = self.split_edge(starts, t)
        path = []
        for i, s in enumerate(new):
            nxt = int(self._alpha[0][ends[i]])  # new vertex on the next edge, same side face
            n1, _ = self.split_face(int(s), nxt)
            path.append(n1)
        return int(self.split_volumes(_darts(path), labels))

    def split_prisms(
        self, volumes: ArrayLike, t: float = 0.5, faces: ArrayLike | None = None, labels: Sequence[str | int] = ("E", "O")
    ) -> np.ndarray:
        """Vectorised :meth:`split_prism` of many volumes at once; returns the new volume ids.

        ``faces`` (one dart per volume, default each volume's ``O`` anchor)
        give the face to cut parallel to.  Edges and faces shared by two of
        the volumes (ring cubes joined side by side) are split once, so
        neighbours split at the same fraction from the same side stay
        conforming.  A refused batch leaves the map unchanged.

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3(); _ = gm.add_prisms(5, 3, origins=[[0, 0, 0], [0, 3, 0], [0, 6, 0]])
        >>> gm.split_prisms([0, 1, 2], 0.25).tolist(), gm.is_valid(), gm.counts()["volumes"]
        ([3, 4, 5], True, 6)
        """
        volumes = np.atleast_1d(np.asarray(volumes, np.int64))
        if volumes.size == 0:
            return volumes
        if volumes.min() < 0 or volumes.max() >= self.n_volumes or len(np.unique(volumes)) != len(volumes):
            raise GMapError(f"split_prisms needs distinct volume ids in 0..{self.n_volumes - 1}")
        if not 0.0 < float(t) < 1.0:
            raise GMapError(f"split fraction must be strictly between 0 and 1, got {t}")
        codes = [_label_code(x) for x in labels]
        faces = np.asarray(self.face_of(volumes, "O")) if faces is None else self.check_darts(faces)
        if len(faces) != len(volumes) or np.any(self._darts["volume"][faces] != volumes):
            raise GMapError("split_prisms needs one face dart inside each volume")
        with self.atomic():
            return self._split_prisms(faces, float(t), codes)

    def _split_prisms(self, faces, t, codes):
        walk, length = self.face_walk(faces)
        corner = walk[:, 0::2]
        ok = corner >= 0
        alpha = self._alpha
        c = np.maximum(corner, 0)
        starts = np.where(ok, alpha[1][alpha[2][c]], -1)
        ends = np.where(ok, alpha[1][alpha[2][np.maximum(walk[:, 1::2], 0)]], -1)
        eid, _ = self.cells(1)
        s = starts[ok]
        _, first = np.unique(eid[s], return_index=True)
        self.split_edge(s[first], t)
        alpha = self._alpha
        d1 = alpha[0][starts[ok]].astype(np.int64)  # new vertex on each leaving edge
        d2 = alpha[0][ends[ok]].astype(np.int64)  # new vertex on the next edge, same side face
        fid, _ = self.cells(2)
        _, first = np.unique(fid[d1], return_index=True)
        d1u, d2u = d1[first], d2[first]
        fw, _ = self.face_walk(d1u)
        q = np.argmax(fw == d2u[:, None], axis=1)
        self.split_faces(d1u, (q + 1) // 2)
        alpha = self._alpha
        path = alpha[1][alpha[0][starts[ok]]].astype(np.int64)  # the new edge, in the part holding the face
        return np.asarray(self.split_volumes(path, codes, many=True))

    # ------------------------------------------------------------------ removal
    def remove_volumes(self, volumes: ArrayLike) -> None:
        """Delete volumes; the faces they were sewn to become alpha3-free.

        Dart and volume ids are renumbered (kept in order).

        >>> from ramure.gmap import GMap3
        >>> gm = GMap3()
        >>> a, b = gm.add_prisms(4, 2)
        >>> gm.sew3(gm.prism_face(a, 4, "E"), gm.prism_face(b, 4, "O"))
        >>> gm.remove_volumes([0])
        >>> gm.n_darts, gm.n_volumes, bool(gm.is_free(range(48), 3).all())
        (48, 1, True)
        """
        volumes = np.unique(_darts(volumes))
        if volumes.size and (volumes.min() < 0 or volumes.max() >= self.n_volumes):
            raise GMapError(f"volume ids must be in 0..{self.n_volumes - 1}")
        gone_volume = np.zeros(self.n_volumes, bool)
        gone_volume[volumes] = True
        gone = gone_volume[self._darts["volume"]]
        alpha = self.alpha
        partners = alpha[3][gone]
        alpha[3][partners] = partners
        keep = np.flatnonzero(~gone)
        remap = np.full(self.n_darts, -1, np.int64)
        remap[keep] = np.arange(len(keep))
        new_alpha = remap[alpha[:, keep]].astype(np.int32)
        self._darts.keep(keep)
        self._alpha[:, : len(keep)] = new_alpha
        sup = self._darts["sup"]
        sup[:] = np.where(sup >= 0, remap[np.maximum(sup, 0)], -1)
        vkeep = np.setdiff1d(np.arange(self.n_volumes), volumes)
        vremap = np.full(self.n_volumes, -1, np.int64)
        vremap[vkeep] = np.arange(len(vkeep))
        parent = self._volumes["parent"].astype(np.int64)
        self._volumes["parent"][:] = np.where(parent >= 0, vremap[np.maximum(parent, 0)], -1)
        self._volumes.keep(vkeep)
        self._darts["volume"][:] = vremap[self._darts["volume"]]
        self.mark_changed()
