"""Hierarchical embedding: grow on faces, re-frame from parents' support faces, embed now or later."""

import numpy as np
import pytest

from ramure.gmap import GMap3, GMapError
from ramure.gmap.kernel.embedding import grow, reframe, support_frames
from ramure.gmap.kernel.topology import assert_solid


def trunk_with_rings(embed_each):
    """A 6-prism trunk, a cube on each side, a second layer on the cubes' E faces, rings joined."""
    gm = GMap3()
    gm.add_prisms(6, sizes=[[2.0, 2.0, 2.0]])
    snaps = []
    ring = grow(gm, gm.face_of(np.zeros(6, int), [f"C{j + 1}" for j in range(6)]), 4, height=0.5)
    if embed_each:
        snaps.append(gm.embed().copy())
    gm.identify(gm.face_of(ring, "C2"), gm.face_of(np.roll(ring, -1), "C4"))
    outer = grow(gm, gm.face_of(ring, "E"), 4, height=0.2, angles=[0.0, 0.0, 5.0])
    if embed_each:
        snaps.append(gm.embed().copy())
    gm.identify(gm.face_of(outer, "C2"), gm.face_of(np.roll(outer, -1), "C4"))
    gm.split_prism(int(outer[0]), 0.5)
    return gm, ring, outer


def test_grown_cubes_sit_on_their_support_faces():
    gm = GMap3()
    gm.add_prisms(4, sizes=[[1.0, 2.0, 3.0]])
    kids = grow(gm, gm.face_of([0, 0, 0], ["E", "C1", "C2"]), 4, height=0.5)
    assert_solid(gm)
    c = gm.dart_data["corner"]
    vid, _ = gm.cells(0)
    for k in kids:  # O corners of each child on the parent's face corners: 4 shared vertices
        o = gm.face_darts([k], "O")[0]
        parent_face = gm.alpha[3][o]
        assert np.abs(c[o] - c[parent_face]).max() < 1e-12
    size = gm.volume_data["size"][kids]
    assert np.allclose(size[:, 0], 0.5)
    assert np.allclose(np.sort(size[:, 1:], axis=1), [[2, 3], [1, 3], [1, 2]])  # E, C1 (+L), C2 (+U)


def test_support_frame_of_a_7_gon_is_the_quads_frame():
    gm = GMap3()
    gm.add_prisms(4)
    before = support_frames(gm, [gm.face_of(0, "C4")])
    gm.add_prisms(7, origins=[[0, -2, 0]])
    gm.sew3([gm.face_of(0, "C4")], [gm.face_of(1, "O")])
    after = support_frames(gm, [gm.face_of(0, "C4")])
    for x, y in zip(before, after):
        assert np.allclose(x, y)


def test_a_branch_of_16_sides_on_a_quad_is_one_solid():
    gm = GMap3()
    gm.add_prisms(4)
    (b,) = grow(gm, [gm.face_of(0, "C1")], 16, height=2.0, width=[[0.8, 0.8]], exclusive=True)
    assert_solid(gm)
    _, length = gm.face_walk([gm.face_of(0, "C1")])
    assert length[0] == 32
    assert gm.volume_data["exclusive"][b]


def test_embedding_each_step_or_once_gives_the_same_positions():
    each, _, _ = trunk_with_rings(True)
    once, _, _ = trunk_with_rings(False)
    assert_solid(each)
    a = each.embed()
    b = reframe(once)
    assert np.abs(a - b).max() < 1e-12
    assert np.abs(reframe(each) - a).max() < 1e-12  # re-framing changes nothing by itself


def test_reframe_moves_children_with_their_parent():
    gm, ring, outer = trunk_with_rings(False)
    before = reframe(gm).copy()
    gm.volume_data["size"][0] *= [1.0, 2.0, 2.0]  # fatter pith
    after = reframe(gm)
    c = gm.dart_data["corner"]
    o = gm.face_darts(ring, "O")[0]
    assert np.abs(c[o] - c[gm.alpha[3][o]]).max() < 1e-12  # rings still sit on the pith's faces
    assert np.linalg.norm(after, axis=1).max() > np.linalg.norm(before, axis=1).max() + 0.5
    assert_solid(gm)


def test_grow_refusals_change_nothing():
    gm = GMap3()
    gm.add_prisms(4)
    grow(gm, [gm.face_of(0, "E")], 4, height=1.0)
    before = gm.alpha.copy(), gm.n_volumes
    with pytest.raises(GMapError, match="sewn already"):
        grow(gm, [gm.face_of(0, "E")], 4, height=1.0)
    with pytest.raises(GMapError):
        grow(gm, [gm.face_of(0, "C1"), gm.face_of(0, "C1")], 4, height=1.0)
    with pytest.raises(GMapError):
        grow(gm, [gm.face_of(0, "C1")], 4, height=-1.0)
    assert np.array_equal(before[0], gm.alpha) and before[1] == gm.n_volumes


def _embed_by_bincount(gm):
    """The embedding written with numpy (one bincount per coordinate): the compiled pass's reference."""
    ids, count = gm.cells(0)
    vol = gm.dart_volume
    weight = gm.volume_data["weight"][vol].astype(float) / gm._corner_sizes()
    excl = gm.volume_data["exclusive"][vol]
    at_excl = np.zeros(count, bool)
    at_excl[ids[excl]] = True
    weight = np.where(at_excl[ids] & ~excl, 0.0, weight)
    corners = gm.dart_data["corner"]
    total = np.bincount(ids, weight, minlength=count)
    return np.column_stack([np.bincount(ids, weight * corners[:, j], minlength=count) for j in range(3)]) / total[:, None]


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("weights", ["ones", "random"])
def test_compiled_embedding_equals_the_numpy_sums_bit_for_bit(weights, compiled, monkeypatch):
    monkeypatch.setattr("ramure.gmap.kernel.storage.compiled_pays", lambda n: compiled)
    gm = GMap3()
    gm.add_prisms(4)
    grow(gm, [gm.face_of(0, "C1")], 16, height=2.0, width=[[0.8, 0.8]], exclusive=True)
    grow(gm, gm.face_of([0, 0], ["C2", "E"]), 4, height=0.5)
    if weights == "random":
        gm.volume_data["weight"][:] = np.random.default_rng(3).uniform(0.5, 2.0, gm.n_volumes)
    pos = gm.embed()
    want = _embed_by_bincount(gm)
    assert np.array_equal(pos, want)
    ids, _ = gm.cells(0)
    assert np.array_equal(gm.dart_data["point"], want[ids])


def test_compiled_embedding_keeps_no_per_dart_corner_sizes(monkeypatch):
    """Weights 1: the compiled embedding weighs corners from their labels and keeps no per-dart arrays.

    Before, it cached each dart's corner size and its inverse (2 x 8 bytes a dart, with room
    to grow: about 45 MB on the 30-year pine) for as long as the map lived.
    """
    from ramure.gmap.kernel._embed_kernel import inverse_orbit_sizes

    monkeypatch.setattr("ramure.gmap.kernel.storage.compiled_pays", lambda n: True)
    gm = GMap3()
    gm.add_prisms(4)
    grow(gm, [gm.face_of(0, "C1")], 16, height=2.0, width=[[0.8, 0.8]], exclusive=True)
    grow(gm, gm.face_of([0, 0], ["C2", "E"]), 4, height=0.5)
    gm.mark_changed()  # as after any edit: nothing derived is cached
    gm.__dict__.pop("_corner_memo", None)
    gm.embed()
    assert "corner_weights" not in gm.cache and getattr(gm, "_corner_memo", None) is None
    ids, count = gm.orbit_ids("12")
    inverse = inverse_orbit_sizes(ids, np.arange(count, dtype=np.int32), count)
    assert np.array_equal(inverse, 1.0 / np.bincount(ids).astype(float)[ids])  # the same doubles
    assert set(np.unique(inverse).tolist()) <= {1 / 6, 1 / 4, 1 / 8}  # prism corners: 3 edges, split ones: 2 or 4


def test_compiled_embedding_with_a_radial_scalar_equals_the_numpy_one(monkeypatch):
    """The radial scalar takes the per-dart labels path of the compiled pass: same points, same radial."""
    out = []
    for compiled in (True, False):
        monkeypatch.setattr("ramure.gmap.kernel.storage.compiled_pays", lambda n, compiled=compiled: compiled)
        gm = GMap3()
        gm.add_prisms(4)
        grow(gm, [gm.face_of(0, "C1")], 16, height=2.0, width=[[0.8, 0.8]], exclusive=True)
        gm.dart_data["radial"][:] = np.random.default_rng(4).random(gm.n_darts)
        gm.embed()
        out.append((gm.points.copy(), gm.dart_data["radial"].copy()))
    assert np.array_equal(out[0][0], out[1][0]) and np.array_equal(out[0][1], out[1][1])
    assert len(np.unique(out[0][1])) < len(out[0][1])  # averaged per vertex


@pytest.mark.parametrize("compiled", [True, False])
def test_corners_from_per_volume_tables(compiled, monkeypatch):
    """Dart d gets table[offset[volume] + corner[d]]; indices past either end are clipped (both paths alike)."""
    monkeypatch.setattr("ramure.gmap.kernel.storage.compiled_pays", lambda n: compiled)
    gm = GMap3()
    gm.add_prisms(4, 3)
    table = np.arange(3 * 8 * 3, dtype=float).reshape(-1, 3)
    offset = np.array([0, 8, 16])
    corner = gm.dart_data["vcorner"].astype(np.int64)
    corner[[0, 5]] = [-1, 40]  # clipped to the first and the last row
    gm.set_corners_from_tables(table, offset, corner)
    want = table[np.clip(offset[gm.dart_volume] + corner, 0, len(table) - 1)]
    assert np.array_equal(gm.corners, want)
    assert np.array_equal(gm.corners[0], table[0]) and np.array_equal(gm.corners[5], table[-1])
    with pytest.raises(GMapError, match="no row offset"):  # a volume past the offsets: refused, not read past
        gm.set_corners_from_tables(table, offset[:2], corner)


def test_compiled_embedding_refuses_a_dart_of_no_volume(monkeypatch):
    monkeypatch.setattr("ramure.gmap.kernel.storage.compiled_pays", lambda n: True)
    gm = GMap3()
    gm.add_prisms(4)
    grow(gm, [gm.face_of(0, "C1")], 16, height=2.0, width=[[0.8, 0.8]], exclusive=True)
    gm.dart_data["volume"][3] = gm.n_volumes + 7  # read past the volumes: refused
    with pytest.raises(GMapError, match="no volume"):
        gm.embed()


def test_a_small_map_is_built_and_embedded_without_loading_numba():
    # numba costs about 1 s to load: a one-shot fruit must not pay it (COMPILED_FROM darts).
    import subprocess
    import sys

    code = "import sys; from ramure.gmap.organs.fruit import build_fruit; build_fruit(); print('numba' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
