"""cut_map: a plane cut that returns a valid 3-G-map, agrees with the VTK clip, and commutes."""

import numpy as np
import pytest

from ramure.errors import ValueRefused
from ramure.gmap import GMap3
from ramure.gmap.kernel.cut import cut_map, plane_cut
from ramure.gmap.kernel.embedding import grow
from ramure.gmap.organs.fruit import build_fruit
from ramure.gmap.kernel.prism import FACE_CUT
from ramure.gmap.kernel.topology import assert_solid

pv = pytest.importorskip("pyvista")
from ramure.gmap.kernel.pyvista import to_unstructured_grid  # noqa: E402


def crown():
    gm = GMap3()
    gm.add_prisms(6, sizes=[[2.0, 2.0, 2.0]])
    ring = grow(gm, gm.face_of(np.zeros(6, int), [f"C{j + 1}" for j in range(6)]), 4, height=0.5)
    gm.identify(gm.face_of(ring, "C2"), gm.face_of(np.roll(ring, -1), "C4"))
    gm.embed()
    return gm


@pytest.fixture(scope="module")
def tomato():
    return build_fruit("round_tomato")


PLANES = [
    ((1.0, 0.0, 0.0), None),
    ((0.3, 0.2, 1.0), None),
    ((0.0, 0.0, 1.0), (0.0, 0.0, 0.3)),
    ((0.0, 1.0, 0.0), (0.0, 0.9, 0.0)),
]


@pytest.mark.parametrize("normal,origin", PLANES)
@pytest.mark.parametrize("model", ["crown", "tomato"])
def test_cut_map_is_one_solid_and_keeps_the_clip_volume(model, normal, origin, tomato):
    gm = crown() if model == "crown" else tomato
    if model == "tomato" and origin is not None:
        origin = tuple(40.0 * np.asarray(origin))
    before = gm.alpha.copy()
    cut = cut_map(gm, normal, origin)
    assert np.array_equal(gm.alpha, before)  # the input is not changed
    assert_solid(cut)
    ref = plane_cut(gm, normal, origin, mode="clip").volume
    got = to_unstructured_grid(cut).volume
    assert abs(got - ref) <= 1e-9 * max(1.0, ref)
    assert 0 < cut.n_volumes < gm.n_volumes + 2 * 12 * gm.n_volumes
    # cut faces: labelled X, alpha3-free, on the plane
    x = cut.dart_data["face"] == FACE_CUT
    assert x.any() and np.all(cut.alpha[3][x] == np.flatnonzero(x))
    n = np.asarray(normal) / np.linalg.norm(normal)
    o = np.asarray(origin if origin is not None else 0.5 * (gm.points.min(0) + gm.points.max(0)))
    s = (cut.points - o) @ n
    assert np.abs(s[x]).max() < 1e-9 * max(1.0, np.abs(gm.points).max())
    assert s.max() < 1e-9 * max(1.0, np.abs(gm.points).max())


def test_dart_oriented_volumes_match_vtk_on_the_crown_cut():
    from ramure.gmap.kernel.measure import total_volume, volumes

    gm = crown()
    assert abs(total_volume(gm) - to_unstructured_grid(gm).volume) < 1e-9
    cut = cut_map(gm, (0.3, 0.2, 1.0))
    assert abs(total_volume(cut) - plane_cut(gm, (0.3, 0.2, 1.0), None, mode="clip").volume) < 1e-9
    assert np.all(volumes(cut) > 0)


def test_two_cuts_commute(tomato):
    a = cut_map(cut_map(tomato, (1, 0, 0), (5.0, 0, 0)), (0.2, 1, 0.1), (0, -3.0, 0))
    b = cut_map(cut_map(tomato, (0.2, 1, 0.1), (0, -3.0, 0)), (1, 0, 0), (5.0, 0, 0))
    assert_solid(a)
    assert_solid(b)
    assert a.counts() == b.counts()
    va, vb = to_unstructured_grid(a).volume, to_unstructured_grid(b).volume
    assert abs(va - vb) <= 1e-9 * va
    pa = np.unique(np.round(a.vertex_positions()[1], 7), axis=0)
    pb = np.unique(np.round(b.vertex_positions()[1], 7), axis=0)
    assert np.allclose(pa, pb, atol=1e-6)


def test_a_cut_map_can_be_embedded_and_cut_again():
    once = cut_map(crown(), "x", (0.3, 0, 0))
    pts = once.points.copy()
    once.embed()
    assert np.abs(once.points - pts).max() < 1e-12  # manual embedding kept
    twice = cut_map(once, "y", (0, 0.2, 0))
    assert_solid(twice)


def test_attributes_follow_the_cut():
    gm = crown()
    gm.add_dart_data("uvw", float, (3,), rule="interpolate")
    gm.add_dart_data("crack", np.int8, rule="copy")
    gm.dart_data["uvw"][:] = gm.points
    gm.dart_data["crack"][gm.face_darts([1], "E")[0]] = 1
    cut = cut_map(gm, (1, 0.4, 0.2), (0.4, 0, 0))
    assert np.abs(cut.dart_data["uvw"] - cut.points).max() < 1e-12
    e = (cut.dart_data["face"] == 1) & (cut.dart_volume == 1)
    assert cut.dart_data["crack"][e].min() == 1


def test_bad_planes_are_refused_and_change_nothing():
    gm = crown()
    before = gm.alpha.copy(), gm.points.copy()
    with pytest.raises(ValueRefused, match="normal"):
        cut_map(gm, (0, 0, 0), (0, 0, 0))
    with pytest.raises(ValueRefused, match="misses the model"):
        cut_map(gm, "x", (100.0, 0, 0))
    with pytest.raises(ValueRefused, match="misses the model"):
        cut_map(gm, "x", (-100.0, 0, 0))
    assert np.array_equal(before[0], gm.alpha) and np.array_equal(before[1], gm.points)


def test_a_warped_face_crossing_the_plane_four_times_is_cut_in_two_rounds():
    """A cube whose end face is a saddle (corners alternately 0.3 before and after the plane): the
    face crosses the plane four times and the volume meets it in two loops.  Once refused; now the
    face is split twice and the volume once per loop: one kept solid, two caps on the other side."""
    from ramure.gmap.kernel import topology
    from ramure.gmap.kernel.incidence import move_vertices
    from ramure.gmap.kernel.measure import total_volume

    gm = GMap3()
    gm.add_prisms(4)
    gm.embed()
    vid, pos = gm.vertex_positions()
    top = np.flatnonzero(pos[:, 0] > 0.5)
    new = pos[top].copy()
    new[:, 0] = 1 + 0.3 * np.sign(new[:, 1] * new[:, 2])
    move_vertices(gm, np.array([np.flatnonzero(vid == v)[0] for v in top]), new)
    kept = cut_map(gm, "x", (1.0, 0, 0))
    caps = cut_map(gm, (-1, 0, 0), (1.0, 0, 0))
    assert_solid(kept)
    assert caps.n_volumes == 2 and caps.is_valid()
    assert topology.chi(caps) == 2 and topology.boundary_chi(caps) == 4 and topology.components(caps) == 2
    assert kept.points[:, 0].max() <= 1.0 + 1e-12 and caps.points[:, 0].min() >= 1.0 - 1e-12
    whole = total_volume(gm)
    assert abs(total_volume(kept) + total_volume(caps) - whole) < 0.05 * whole
