"""Tube-only meshes share the cached quad indices instead of copying them, and stay correct."""

from __future__ import annotations

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy

from ramure.lsys import LSystem
from ramure.lsys.interpretation import geometry
from ramure.lsys.interpretation.geometry import skeleton_to_polydata, tube_quads


def _cells(mesh):
    polys = mesh.GetPolys()
    return vtk_to_numpy(polys.GetOffsetsArray()), vtk_to_numpy(polys.GetConnectivityArray())


def test_tube_only_meshes_wrap_the_cached_quads_and_list_each_segments_quads():
    small = LSystem.from_text("n: 3\nw: F\np: F -> F[+F]F").derive().skeleton()
    big = LSystem.from_text("n: 4\nw: F\np: F -> F[+F]F").derive().skeleton()
    a, b = skeleton_to_polydata(big, 5), skeleton_to_polydata(small, 5)
    (oa, ca), (ob, cb) = _cells(a), _cells(b)
    assert np.shares_memory(ca, cb) and np.shares_memory(oa, ob)  # one copy of the indices
    assert np.array_equal(ob, np.arange(0, 4 * 5 * len(small) + 1, 4))
    quads = cb.reshape(-1, 4)
    assert np.array_equal(quads, tube_quads(len(small), 5))
    # quad j of segment s joins ring points j, j+1 of its bottom and top rings
    s, j = 3, 4
    assert quads[s * 5 + j].tolist() == [s * 10 + 4, s * 10 + 0, s * 10 + 5, s * 10 + 9]
    assert not tube_quads(len(small), 5).flags.writeable  # shared: nobody may write into it


def test_a_mesh_a_few_segments_larger_shares_the_cached_indices_too():
    # an edit that adds segments (a stochastic regrow) finds room in the cached arrays
    small = LSystem.from_text("n: 5\nw: A\np: A -> F[+A]A").derive().skeleton()
    grown = LSystem.from_text("n: 5\nw: A[-FF]\np: A -> F[+A]A").derive().skeleton()
    assert len(small) + 2 == len(grown) <= len(small) * 9 // 8
    geometry._QUADS.pop(7, None)  # made anew for the smaller plant, as in a fresh process
    geometry._OFFSETS.clear()
    a, b = skeleton_to_polydata(small, 7), skeleton_to_polydata(grown, 7)
    (oa, ca), (ob, cb) = _cells(a), _cells(b)
    assert np.shares_memory(ca, cb) and np.shares_memory(oa, ob)
    assert np.array_equal(ob, np.arange(0, 4 * 7 * len(grown) + 1, 4))
    assert np.array_equal(cb.reshape(-1, 4)[-7:], tube_quads(len(grown), 7)[-7:])
    assert cb.max() == b.n_points - 1


def test_meshes_with_organs_get_their_own_index_arrays():
    sk = LSystem.from_text("n: 2\nw: F\np: F -> F[+F@O(0.2)]F").derive().skeleton()
    mesh = skeleton_to_polydata(sk, 4)
    offsets, conn = _cells(mesh)
    tubes = 4 * len(sk)
    assert mesh.n_cells == len(offsets) - 1 > tubes
    assert np.all(np.diff(offsets)[:tubes] == 4) and np.all(np.diff(offsets)[tubes:] == 3)
    assert conn.flags.writeable and conn.max() == mesh.n_points - 1


def test_tube_only_meshes_share_their_constant_cell_data_and_it_reads_as_before():
    small = LSystem.from_text("n: 3\nw: F\np: F -> F[+F]F").derive().skeleton()
    big = LSystem.from_text("n: 4\nw: F\np: F -> F[+F]F").derive().skeleton()
    a, b = skeleton_to_polydata(big, 6), skeleton_to_polydata(small, 6)
    cells = np.arange(b.n_cells)
    expected = {"segment": cells // 6, "organ": np.full(b.n_cells, -1), "polygon": np.full(b.n_cells, -1), "kind": 0 * cells}
    for name, values in expected.items():
        mine, theirs = np.asarray(b.cell_data[name]), np.asarray(a.cell_data[name])
        assert np.array_equal(mine, values), name
        assert np.shares_memory(mine, theirs), name  # one copy for every version of a plant
        assert mine.dtype == (np.int32 if name == "segment" else np.int8)
    assert np.array_equal(np.asarray(b.cell_data["leaf_id"]), np.repeat(small.leaf_id, 6))  # per plant
    assert not geometry._tube_cells("segment", len(small), 6).flags.writeable
    with_organs = skeleton_to_polydata(LSystem.from_text("n: 2\nw: F\np: F -> F[+F@O(0.2)]F").derive().skeleton(), 6)
    organ = np.asarray(with_organs.cell_data["organ"])
    assert organ.max() >= 0 and not np.shares_memory(organ, geometry._tube_cells("organ", 1, 6))  # its own
