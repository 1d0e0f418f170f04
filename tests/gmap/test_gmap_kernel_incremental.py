"""Incremental kernel checks equal a full recomputation: orbit labels and counts, validity, chi.

The kernel updates orbit labellings and the validity check after growth
instead of redoing them (issue 13's speed target).  Each test here grows,
splits, unsews or corrupts a map and compares the incremental answer with
the one a fresh copy of the map (no memo) or a full pass gives.
"""

from unittest import mock

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import sparse
from scipy.sparse.csgraph import connected_components

from ramure.gmap import GMap3
from ramure.gmap.kernel import graphs
from ramure.gmap import GMapError
from ramure.gmap.kernel import _components_kernel, operations, storage
from ramure.gmap.kernel.storage import _compiled_validity_problems, _validity_problems
from ramure.gmap.kernel.topology import assert_solid, boundary_chi, chi, components

KEYS = ("123", "023", "013", "012", "0123", "12", "01", "3")


def _same_partition(a, b):
    pairs = np.unique(np.stack([a, b]), axis=1)
    return len(np.unique(pairs[0])) == pairs.shape[1] == len(np.unique(pairs[1]))


def _fresh(gm):
    return GMap3.from_arrays(
        gm.alpha.copy(), {k: v.copy() for k, v in gm.dart_data.items()}, {k: v.copy() for k, v in gm.volume_data.items()}
    )


def _assert_orbits_match_fresh(gm, where=""):
    clean = _fresh(gm)
    for key in KEYS:
        count = gm.orbit_count(key)
        ids, count_ids = gm.orbit_ids(key)
        fresh_ids, fresh_count = clean.orbit_ids(key)
        assert count == count_ids == fresh_count, (where, key)
        assert ids.min() == 0 and ids.max() == count - 1, (where, key)
        assert _same_partition(ids, fresh_ids), (where, key)
    assert chi(gm) == chi(clean) and components(gm) == components(clean)
    assert np.array_equal(gm._corner_sizes(), clean._corner_sizes())  # kept across growth
    assert np.array_equal(gm._inverse_corner_sizes(), 1.0 / clean._corner_sizes())
    gm.embed()
    clean.embed()
    assert np.array_equal(gm.points, clean.points)  # same sums, same order


def _row_of_cubes(gm, count, y):
    firsts = gm.add_prisms(4, count, origins=[[float(i), y, 0.0] for i in range(count)])
    for a, b in zip(firsts[:-1], firsts[1:]):
        gm.sew3(gm.prism_face(a, 4, "E"), gm.prism_face(b, 4, "O"))
    return [int(f) for f in firsts]


@pytest.mark.parametrize("compiled", [True, False])  # the compiled update and the numpy one
def test_two_old_solids_sewn_together_merge_their_orbits(compiled, monkeypatch):
    """Old-old links (no new dart) merge old orbits: counts drop, labels stay 0..count-1."""
    monkeypatch.setattr(storage, "compiled_pays", lambda n: compiled)
    gm = GMap3()
    left = _row_of_cubes(gm, 3, 0.0)
    right = _row_of_cubes(gm, 3, 5.0)
    for key in KEYS:
        gm.orbit_ids(key)
    assert components(gm) == 2
    gm.sew3(gm.prism_face(left[-1], 4, "E"), gm.prism_face(right[0], 4, "O"))  # no new darts
    _assert_orbits_match_fresh(gm, "sewn")
    assert components(gm) == 1 and chi(gm) == 1 and boundary_chi(gm) == 2
    assert_solid(gm)


@pytest.mark.parametrize("compiled", [True, False])  # the compiled update and the numpy one
def test_orbits_follow_growth_then_split_then_unsew_then_growth(compiled, monkeypatch):
    monkeypatch.setattr(storage, "compiled_pays", lambda n: compiled)
    gm = GMap3()
    col = _row_of_cubes(gm, 2, 0.0)
    _assert_orbits_match_fresh(gm, "start")
    for step in range(4):  # growth: a new cube on top, sewn
        (new,) = gm.add_prisms(4, 1, origins=[[2.0 + step, 0, 0]])
        gm.sew3(gm.prism_face(col[-1], 4, "E"), gm.prism_face(new, 4, "O"))
        col.append(int(new))
        _assert_orbits_match_fresh(gm, f"grow {step}")
    gm.split_prism(0, 0.5)  # not growth: full pass
    _assert_orbits_match_fresh(gm, "split")
    gm.unsew3([gm.face_of(int(gm.dart_volume[col[2]]), "E")])  # orbits split: full pass
    _assert_orbits_match_fresh(gm, "unsew")
    assert components(gm) == 2
    (new,) = gm.add_prisms(4, 1, origins=[[9.0, 0, 0]])  # growth again after the full pass
    gm.sew3(gm.prism_face(col[-1], 4, "E"), gm.prism_face(new, 4, "O"))
    _assert_orbits_match_fresh(gm, "grow after unsew")


@pytest.mark.parametrize("compiled", [True, False])  # the compiled update and the numpy one
def test_copies_that_grow_differently_keep_their_own_labels(compiled, monkeypatch):
    """Copies share labelling states; a state appends in place only once (else it copies)."""
    monkeypatch.setattr(storage, "compiled_pays", lambda n: compiled)
    gm = GMap3()
    col = _row_of_cubes(gm, 3, 0.0)
    for key in KEYS:
        gm.orbit_count(key)
    other = gm.copy()
    (a,) = gm.add_prisms(4, 1, origins=[[3.0, 0, 0]])
    gm.sew3(gm.prism_face(col[-1], 4, "E"), gm.prism_face(a, 4, "O"))
    _assert_orbits_match_fresh(gm, "first copy")
    (b,) = other.add_prisms(3, 1, origins=[[0, 3.0, 0]])  # a loose prism: one more component
    _assert_orbits_match_fresh(other, "second copy")
    assert components(other) == 2 and components(gm) == 1
    _assert_orbits_match_fresh(gm, "first copy again")


@settings(max_examples=40, deadline=None)
@given(ops=st.lists(st.tuples(st.integers(0, 4), st.integers(0, 10_000)), min_size=1, max_size=8), compiled=st.booleans())
def test_random_growth_orbit_counts_equal_a_fresh_labelling(ops, compiled):
    with mock.patch.object(storage, "compiled_pays", lambda n: compiled):
        _random_growth(ops)


@settings(max_examples=30, deadline=None)
@given(ops=st.lists(st.tuples(st.integers(0, 4), st.integers(0, 10_000)), min_size=1, max_size=8))
def test_compiled_orbit_update_numbers_orbits_as_the_numpy_one(ops):
    """Not only the same partition: the same ids (embedding returns its vertices in id order)."""
    runs = []
    for compiled in (True, False):
        runs.append([])
        with mock.patch.object(storage, "compiled_pays", lambda n, compiled=compiled: compiled):
            _random_growth(ops, runs[-1])
    for a, b in zip(*runs):
        assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)


def test_compiled_orbit_update_hands_new_rows_that_are_not_involutions_to_numpy():
    """A one-way link among the new darts: strong components (the numpy path), whichever path is asked."""
    counts = {}
    for compiled in (True, False):
        gm = GMap3()
        col = _row_of_cubes(gm, 3, 0.0)
        for key in KEYS:
            gm.orbit_count(key)
        (new,) = gm.add_prisms(4, 1, origins=[[3.0, 0, 0]])
        gm.sew3(gm.prism_face(col[-1], 4, "E"), gm.prism_face(new, 4, "O"))
        n = gm.n_darts
        gm.alpha[0][n - 1] = n - 7  # one way: alpha0 is no longer an involution on the new darts
        gm.mark_changed()
        with mock.patch.object(storage, "compiled_pays", lambda n, compiled=compiled: compiled):
            counts[compiled] = [gm.orbit_count(key) for key in KEYS]
        assert counts[compiled] == [_fresh(gm).orbit_count(key) for key in KEYS]
    assert counts[True] == counts[False]


def test_compiled_orbit_update_declines_a_link_out_of_the_map():
    """An old free dart linked past the map: the compiled update says so instead of reading past its arrays."""
    gm = GMap3()
    col = _row_of_cubes(gm, 3, 0.0)
    gm.orbit_count("0123")
    old = gm._orbit_memo[(0, 1, 2, 3)]
    (new,) = gm.add_prisms(4, 1, origins=[[3.0, 0, 0]])
    gm.sew3(gm.prism_face(col[-1], 4, "E"), gm.prism_face(new, 4, "O"))
    r, d = gm._growth_since(old.snap)
    args = (gm._new_dart_local(old.n), np.ones(4, bool), old.n, old.raw, old.find, old.count, r, d, gm.alpha)
    assert _components_kernel.grown_orbits(*args)[5]  # a clean growth: accepted
    free = int(np.flatnonzero(gm.alpha[3][: old.n] == np.arange(old.n))[0])
    gm.alpha[3][free] = gm.n_darts + 9
    gm.mark_changed()
    r, d = gm._growth_since(old.snap)
    args = args[:6] + (r, d, gm.alpha)
    assert not _components_kernel.grown_orbits(*args)[5]


def _random_growth(ops, record=None):
    gm = GMap3()
    row = _row_of_cubes(gm, 2, 0.0)
    cols = [[row[0], row[-1]]]  # columns of cubes: (first, top) darts
    for kind, pick in ops:
        c = cols[pick % len(cols)]
        if kind <= 1:  # a cube on the free E face of a column's top
            (new,) = gm.add_prisms(4, 1, origins=[[pick % 7, 0, 0]])
            gm.sew3(gm.prism_face(c[1], 4, "E"), gm.prism_face(new, 4, "O"))
            c[1] = int(new)
        elif kind == 2:  # a new loose column (one more component)
            row = _row_of_cubes(gm, 1 + pick % 2, float(len(cols)) * 3)
            cols.append([row[0], row[-1]])
        elif kind == 3 and len(cols) > 1:  # two old columns sewn end to end (old-old links)
            other = cols[(pick + 1) % len(cols)]
            gm.sew3(gm.prism_face(c[1], 4, "E"), gm.prism_face(other[0], 4, "O"))
            cols.remove(other)
            c[1] = other[1]
        else:
            gm.split_edge([pick % gm.n_darts], 0.5)  # not growth: full pass next
        _assert_orbits_match_fresh(gm, (kind, pick))
        assert gm.is_valid()
        if record is not None:
            record.append({key: gm.orbit_ids(key)[0].copy() for key in KEYS})


def _grown_pair(cubes=6):
    """A row of ``cubes`` checked valid, then one more cube sewn on (the next check is incremental)."""
    gm = GMap3()
    col = _row_of_cubes(gm, cubes, 0.0)
    assert gm.validity_problems() == []
    (new,) = gm.add_prisms(4, 1, origins=[[float(cubes), 0, 0]])
    gm.sew3(gm.prism_face(col[-1], 4, "E"), gm.prism_face(new, 4, "O"))
    return gm


@settings(max_examples=150, deadline=None)
@given(kind=st.integers(0, 6), pick=st.integers(0, 1_000_000), other=st.integers(0, 1_000_000), row=st.integers(0, 3))
def test_incremental_validity_finds_a_defect_iff_the_full_check_does(kind, pick, other, row):
    gm = _grown_pair()
    n = gm.n_darts
    _corrupt(gm, kind, pick, other, row)
    darts = gm._changed_since_valid()
    incremental = gm.validity_problems()
    full = _validity_problems(gm.alpha, gm.dart_volume, gm.dart_data["face"], gm.n_volumes)
    assert bool(incremental) == bool(full), (kind, darts is None, incremental, full)
    if kind == 0:
        assert darts is not None and len(darts) < n  # the clean case really is incremental


def _corrupt(gm, kind, pick, other, row):
    """One defect of kind 1..6 (0: none) in a grown map, every id kept inside the map."""
    n = gm.n_darts
    a = gm.alpha
    free3 = np.flatnonzero(a[3] == np.arange(n))
    if kind == 1:  # a one-way link from a free dart (looks like growth)
        d = int(free3[pick % len(free3)])
        a[3][d] = other % n
    elif kind == 2:  # a two-way link between two free darts
        d, e = int(free3[pick % len(free3)]), int(free3[other % len(free3)])
        a[3][d], a[3][e] = e, d
    elif kind == 3:  # an old dart relabelled (volume)
        gm.dart_data["volume"][pick % n] = other % gm.n_volumes
    elif kind == 4:  # an old dart relabelled (face)
        gm.dart_data["face"][pick % n] = other % 6
    elif kind == 5:  # any entry of any dart rewritten
        a[row][pick % n] = other % n
    elif kind == 6:  # a new dart's link rewritten
        a[row][n - 1 - pick % 48] = other % n


@settings(max_examples=120, deadline=None)
@given(kind=st.integers(0, 6), pick=st.integers(0, 1_000_000), other=st.integers(0, 1_000_000), row=st.integers(0, 3))
def test_compiled_validity_equals_the_numpy_check(kind, pick, other, row):
    """Same darts to check after growth, same messages and counts, on the whole map and on those darts."""
    gm = _grown_pair()
    _corrupt(gm, kind, pick, other, row)
    with mock.patch.object(storage, "compiled_pays", lambda n: False):
        numpy_darts = gm._changed_since_valid()
    with mock.patch.object(storage, "compiled_pays", lambda n: True):
        compiled_darts = gm._changed_since_valid()
    assert (numpy_darts is None) == (compiled_darts is None)  # None: more than growth, a full check
    args = (gm.alpha, gm.dart_volume, gm.dart_data["face"], gm.n_volumes)
    assert _compiled_validity_problems(*args) == _validity_problems(*args)
    if numpy_darts is not None:
        assert np.array_equal(numpy_darts, compiled_darts)
        assert _compiled_validity_problems(*args, numpy_darts) == _validity_problems(*args, numpy_darts)
    if kind == 0:
        assert _validity_problems(*args) == []


@pytest.mark.parametrize("compiled", [True, False])
def test_validity_names_ids_outside_the_map_on_both_paths(compiled, monkeypatch):
    monkeypatch.setattr(storage, "compiled_pays", lambda n: compiled)
    gm = _grown_pair()
    gm.alpha[0][5] = gm.n_darts + 3  # the compiled pass stops there; the full numpy check names it
    assert gm.validity_problems() == ["alpha holds dart ids outside 0..n_darts-1"]
    gm = _grown_pair()
    gm.alpha[3][-1] = gm.n_darts + 3  # a new dart's link: the incremental step must not read past the map
    assert gm.validity_problems() == ["alpha holds dart ids outside 0..n_darts-1"]


def test_incremental_validity_checks_few_darts_after_growth():
    gm = _grown_pair(40)
    darts = gm._changed_since_valid()
    assert darts is not None and len(darts) <= 4 * 48  # the new cube and its neighbour, not 41 cubes
    assert gm.validity_problems() == []


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(1, 40),
    k=st.integers(1, 4),
    seed=st.integers(0, 10_000),
    involution=st.booleans(),
    compiled=st.booleans(),
)
def test_orbit_labels_equal_scipy_public_components(n, k, seed, involution, compiled):
    """The compiled-search shortcut gives scipy's public partition, for involutions or not."""
    rng = np.random.default_rng(seed)
    rows = np.empty((k, n), np.int64)
    for i in range(k):
        if involution:  # random pairs and fixed points
            perm = rng.permutation(n)
            row = np.arange(n)
            m = (n // 2) * 2 if rng.random() < 0.7 else 0
            row[perm[:m:2]], row[perm[1:m:2]] = perm[1:m:2], perm[:m:2]
            rows[i] = row
        else:
            rows[i] = rng.integers(0, n, n)
    if k > 1 and n > 1:
        rows[-1, : n // 3] = rows[0, : n // 3]  # repeated links (the scipy hang)
        if involution:  # keep the last row an involution
            rows[-1] = rows[0]
    with mock.patch.object(graphs, "compiled_pays", lambda n: compiled):  # both paths, same labels
        labels, count = graphs.orbit_labels(rows)
    if involution:  # symmetric graph: weak components are the orbits
        graph = sparse.csr_matrix((np.ones(n * k), rows.T.ravel(), np.arange(0, n * k + 1, k)), shape=(n, n))
        want_count, want = connected_components(graph, directed=True, connection="weak")
        assert np.array_equal(labels, want)  # the union-find numbers components as scipy does
    else:  # repeats made self-loops first (scipy hangs on them)
        graph = sparse.csr_matrix(
            (np.ones(n * k), np.where(_repeats(rows), np.arange(n), rows).T.ravel(), np.arange(0, n * k + 1, k)), shape=(n, n)
        )
        want_count, want = connected_components(graph, directed=True, connection="strong")
    assert count == want_count and _same_partition(labels, want)


def _repeats(rows):
    out = np.zeros(rows.shape, bool)
    ar = np.arange(rows.shape[1])
    for i in range(len(rows)):
        for j in range(i + 1, len(rows)):
            out[j] |= (rows[i] == rows[j]) & (rows[j] != ar)
    return out


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("size", [0, 1, 5, 300])
def test_components_of_edges_equal_scipy(size, compiled, monkeypatch):
    monkeypatch.setattr(graphs, "compiled_pays", lambda n: compiled)
    rng = np.random.default_rng(size)
    u = rng.integers(0, max(size, 1), 2 * size)
    v = rng.integers(0, max(size, 1), 2 * size)
    count, labels = graphs.components(u, v, size)
    graph = sparse.csr_matrix((np.ones(len(u)), (u, v)), shape=(size, size))
    want_count, want = connected_components(graph, directed=True, connection="weak")
    assert count == want_count and len(labels) == size and np.array_equal(labels, want)


@pytest.mark.parametrize("compiled", [True, False])  # the compiled walk and the batched numpy one
def test_face_walk_of_mixed_faces_equals_a_dart_by_dart_walk(compiled, monkeypatch):
    """The batched walk (faces drop out as they close) gives each face's darts in walk order."""
    monkeypatch.setattr(operations, "compiled_pays", lambda n: compiled)
    gm = GMap3()
    gm.add_prisms(5, 2)
    gm.add_prisms(3)
    gm.split_edge([0, 70], 0.5)  # some faces of 6 and 4 corners
    pentagon_and_square = [0, int(gm.prism_face(0, 5, "C1"))]  # two degrees: the last two steps differ
    for starts in (np.arange(0, gm.n_darts, 7), np.array(pentagon_and_square), np.arange(16, 24)):
        _assert_walks(gm, starts)
    empty, none = gm.face_walk([])
    assert empty.shape == (0, 0) and none.size == 0


def _boundary_cases():
    from ramure.gmap.organs import wood

    one = GMap3()
    one.add_prisms(5)
    row, pair = GMap3(), GMap3()
    _row_of_cubes(row, 4, 0.0)
    _row_of_cubes(pair, 2, 0.0)
    _row_of_cubes(pair, 3, 4.0)  # two solids: chi of the boundary 4
    loose = GMap3()
    loose.add_prisms(4, 3)
    loose.sew3(loose.prism_face(0, 4, "C1"), loose.prism_face(48, 4, "C3"))
    split = GMap3()
    _row_of_cubes(split, 3, 0.0)
    split.split_edge([0, 60], 0.5)  # faces of different degrees sewn
    return [one, row, pair, loose, split, wood.grow_wood("pine", years=2, branches=[(0, 3)]).gm]


@pytest.mark.parametrize("case", range(6))
def test_compiled_boundary_counts_equal_the_boundary_surface(case):
    gm = _boundary_cases()[case]
    v, e, f, ok = _components_kernel.boundary_counts(gm.alpha, gm.n_darts)
    c = gm.boundary().counts()
    assert ok and (v, e, f) == (c["vertices"], c["edges"], c["faces"])
    with mock.patch.object(storage, "compiled_pays", lambda n: True):
        assert gm.boundary_euler_characteristic() == gm.boundary().euler_characteristic() == v - e + f
    assert v - e + f == (4 if case in (2, 3) else 2)  # two balls in cases 2 and 3


def test_compiled_boundary_hands_a_broken_surface_to_numpy():
    gm = _boundary_cases()[1]
    free = np.flatnonzero(gm.alpha[3] == np.arange(gm.n_darts))
    gm.alpha[2][free[0]] = free[5]  # alpha2 no longer an involution on the surface
    assert not _components_kernel.boundary_counts(gm.alpha, gm.n_darts)[3]
    with mock.patch.object(storage, "compiled_pays", lambda n: True):
        assert gm.boundary_euler_characteristic() == gm.boundary().euler_characteristic()


@pytest.mark.parametrize("compiled", [True, False])
def test_face_walk_of_a_broken_face_is_refused_on_both_paths(compiled, monkeypatch):
    monkeypatch.setattr(operations, "compiled_pays", lambda n: compiled)
    gm = GMap3()
    gm.add_prisms(4)
    gm.alpha[1][1] = 1  # a0 then a1 from dart 0 stalls on dart 1: the face never closes
    with pytest.raises(GMapError, match="does not close"):
        gm.face_walk([0])
    gm.alpha[1][1] = gm.n_darts + 5  # an id outside the map: the compiled walk hands over to numpy
    with pytest.raises(IndexError):
        gm.face_walk([0])


def _assert_walks(gm, starts):
    walk, lengths = gm.face_walk(starts)
    assert walk.dtype == np.int64 and walk.shape == (len(starts), lengths.max())
    for row, d, length in zip(walk, starts, lengths):
        want, cur = [], int(d)
        while True:
            want.append(cur)
            cur = int(gm.alpha[0][cur])
            want.append(cur)
            cur = int(gm.alpha[1][cur])
            if cur == d:
                break
        assert length == len(want) and row[:length].tolist() == want and np.all(row[length:] == -1)


def _alpha_view(gm, spare=7):
    """``gm``'s alpha as the kernel holds it after growth: int32 rows with spare capacity (a strided view)."""
    room = np.empty((4, gm.n_darts + spare), np.int32)
    room[:, : gm.n_darts] = gm.alpha
    return room[:, : gm.n_darts]


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("key", [(0, 1, 2, 3), (1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2), (1, 2), (3,)])
def test_orbit_labels_select_equals_copied_rows(key, compiled, monkeypatch):
    """``select`` on a strided int32 alpha labels as the int64 copy of those rows (the old call)."""
    gm = GMap3()
    a, b, c = gm.add_prisms(5, 3)
    gm.sew3(gm.prism_face(a, 5, "E"), gm.prism_face(b, 5, "O"))
    gm.sew3(gm.prism_face(b, 5, "E"), gm.prism_face(c, 5, "O"))
    gm.add_prisms(4)  # and a free cube
    alpha = _alpha_view(gm)
    assert not alpha.flags.c_contiguous
    monkeypatch.setattr(graphs, "compiled_pays", lambda n: compiled)
    labels, count = graphs.orbit_labels(alpha, select=key)
    monkeypatch.setattr(graphs, "compiled_pays", lambda n: False)
    want, want_count = graphs.orbit_labels(np.array(gm.alpha[list(key)], np.int64))
    assert labels.dtype == np.int32 and count == want_count and np.array_equal(labels, want)
    assert count == gm.orbit_count(key)
    monkeypatch.setattr(graphs, "compiled_pays", lambda n: compiled)
    buffer = np.full(gm.n_darts + 5, -7, np.int32)  # labels with room, written in place (the orbit states' raw numbers)
    into, count = graphs.orbit_labels(alpha, select=key, out=buffer)
    assert np.shares_memory(into, buffer) and np.array_equal(buffer[: gm.n_darts], want) and count == want_count
    assert buffer[gm.n_darts :].tolist() == [-7] * 5


def test_orbit_labels_select_falls_back_when_not_an_involution(monkeypatch):
    """A selected row that is not an involution takes the strong search: the same partition as before."""
    monkeypatch.setattr(graphs, "compiled_pays", lambda n: True)
    rows = np.array([[1, 0, 3, 2, 4], [0, 1, 2, 3, 4], [1, 2, 0, 3, 4]], np.int32)  # row 2: a 3-cycle
    labels, count = graphs.orbit_labels(rows, select=(0, 2))
    assert count == 2 and labels[0] == labels[1] == labels[2] == labels[3] != labels[4]
    labels, count = graphs.orbit_labels(rows, select=(1,))
    assert count == 5 and labels.tolist() == [0, 1, 2, 3, 4]


def test_orbit_labels_of_alpha_makes_no_widened_copy(monkeypatch):
    """Labelling 3 rows of an int32 alpha allocates far less than their int64 copy (3 x 8 bytes a dart).

    Before, ``orbit_labels(alpha[key])`` copied the rows (12 bytes a dart), widened them
    to int64 (24) and made int64 temporaries for the involution check: the growth
    peak of the 30-year pine (2.8 million darts) was there.
    """
    import tracemalloc

    monkeypatch.setattr(graphs, "compiled_pays", lambda n: True)
    gm = GMap3()
    gm.add_prisms(8, count=2000)
    n = gm.n_darts
    graphs.orbit_labels(gm.alpha, select=(1, 2, 3))  # compiled and loaded before measuring
    tracemalloc.start()
    try:
        labels, count = graphs.orbit_labels(gm.alpha, select=(1, 2, 3))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert count == 2000 * 16  # free prisms of order 8: 16 vertices each
    assert peak < 10 * n, f"{peak / n:.1f} bytes a dart"  # int32 parents and labels: 8


def _orbit_test_map():
    """Three prisms in a column, the middle one's edges split: orbits of several sizes."""
    gm = GMap3()
    a, b, c = gm.add_prisms(5, 3)
    gm.sew3(gm.prism_face(a, 5, "E"), gm.prism_face(b, 5, "O"))
    gm.sew3(gm.prism_face(b, 5, "E"), gm.prism_face(c, 5, "O"))
    gm.split_edge([gm.prism_face(b, 5, "C2"), gm.prism_face(b, 5, "C4")], [0.3, 0.6])
    return gm


@pytest.mark.parametrize("key", [(0, 2, 3), (2, 3), (0, 1, 2), (1, 2, 3), (0, 1, 2, 3), (3,)])
def test_compiled_orbits_from_equals_the_numpy_walk(key, monkeypatch):
    """Members (sorted) and the index of each member's start: the compiled search as the numpy one."""
    gm = _orbit_test_map()
    ids, count = gm.orbit_ids(key)
    firsts = np.unique(ids, return_index=True)[1]  # one dart of each orbit
    starts = firsts[np.linspace(0, count - 1, min(count, 5)).astype(int)][::-1]  # some orbits, not in dart order
    from ramure.gmap.kernel import _walk_kernel

    out = []
    for compiled in (True, False):
        monkeypatch.setattr(storage, "compiled_pays", lambda n, compiled=compiled: compiled)
        with mock.patch.object(_walk_kernel, "orbit_members", wraps=_walk_kernel.orbit_members) as search:
            out.append(gm.orbits_from(starts, key))
        assert search.call_count == int(compiled)  # compiled: one search, not the numpy rings
    (m1, l1), (m2, l2) = out
    assert np.array_equal(m1, m2) and np.array_equal(l1, l2)
    assert np.all(np.diff(m1) > 0) and set(l1.tolist()) == set(range(len(starts)))
    for j, s in enumerate(starts):  # each start's orbit is the one gm.orbit gives
        assert np.array_equal(m1[l1 == j], np.sort(gm.orbit(int(s), key)))
    assert np.all(gm._marks() == -1)  # the scratch is left clean


@pytest.mark.parametrize("compiled", [True, False])
def test_orbits_from_refuses_two_starts_in_one_orbit(compiled, monkeypatch):
    monkeypatch.setattr(storage, "compiled_pays", lambda n: compiled)
    gm = _orbit_test_map()
    other = int(gm.alpha[0][7])  # same edge as dart 7
    with pytest.raises(GMapError, match="same orbit"):
        gm.orbits_from([7, 100, other], (0, 2, 3))
    assert np.all(gm._marks() == -1)
    members, labels = gm.orbits_from([7, other], (0, 2, 3), strict=False)  # not strict: one orbit, both starts allowed
    assert len(members) == len(gm.orbit(7, (0, 2, 3)))


@pytest.mark.parametrize("cubes", [1, 5, 6, 7, 40])
def test_compiled_orbits_from_grows_its_room(cubes, monkeypatch):
    """Whole cubes (48 darts) from one dart each: the search outgrows its first room (8 darts a start).

    With 6 cubes the room is full exactly when the next start comes (it wrote past it once).
    """
    gm = GMap3()
    first = gm.add_prisms(4, cubes)
    monkeypatch.setattr(storage, "compiled_pays", lambda n: True)
    members, labels = gm.orbits_from(first[::-1], (0, 1, 2))
    assert np.array_equal(members, np.arange(48 * cubes))
    assert np.array_equal(labels, (cubes - 1 - np.arange(48 * cubes) // 48))
