"""pyvista conversion and plane cuts."""

import numpy as np
import pytest
import pyvista as pv

from ramure.gmap import GMap3
from ramure.gmap.kernel import subdivide
from ramure.gmap.kernel.cut import parse_plane, plane_cut
from ramure.gmap.kernel.errors import ValueRefused
from ramure.gmap.organs.fruit import build_fruit
from ramure.gmap.kernel.pyvista import boundary_polydata, to_unstructured_grid
from ramure.gmap.organs.tissue import TISSUES


@pytest.fixture(scope="module")
def tomato():
    return build_fruit("round_tomato")


def test_one_cell_per_volume_with_the_right_types(tomato):
    grid = to_unstructured_grid(tomato)
    assert grid.n_cells == 110 and grid.n_points == 220
    types = np.asarray(grid.celltypes)
    assert np.all(types[:10] == pv.CellType.POLYHEDRON)  # 10-gon trunk prisms
    assert np.all(types[10:] == pv.CellType.HEXAHEDRON)  # quad branches
    v = subdivide.volume(tomato, 1)
    assert set(np.asarray(to_unstructured_grid(v).celltypes).tolist()) == {pv.CellType.HEXAHEDRON}
    tri = GMap3()
    tri.add_prisms(3)
    assert to_unstructured_grid(tri).celltypes.tolist() == [pv.CellType.WEDGE]


@pytest.mark.parametrize("levels", [dict(), dict(volume_levels=1), dict(surface_levels=1)])
def test_cells_have_positive_volumes_that_fill_the_closed_skin(levels):
    gm = build_fruit("round_tomato", **levels)
    grid = to_unstructured_grid(gm)
    vol = grid.compute_cell_sizes()["Volume"]
    assert np.all(vol > 0)
    skin = boundary_polydata(gm)
    assert skin.n_open_edges == 0 and skin.is_manifold
    # non-planar quads after smoothing are triangulated differently by the two filters
    assert vol.sum() == pytest.approx(skin.volume, rel=5e-3)


def test_cell_data_names_what_each_cell_is(tomato):
    grid = to_unstructured_grid(tomato)
    assert grid.cell_data["label"].tolist() == ["A"] * 10 + ["B"] * 100
    assert grid.cell_data["tissue"].tolist() == [0] * 10 + [1] * 100
    assert np.all(grid.cell_data["leaf_id"] == -1)
    assert grid.cell_data["volume"].tolist() == list(range(110))
    assert list(grid.field_data["tissue_names"]) == list(TISSUES)
    surf = boundary_polydata(tomato)
    assert surf.n_cells == 100 + 2 + 2 * 10  # skin, trunk caps, pole annuli


def test_vtu_round_trip_keeps_cells_and_data(tomato, tmp_path):
    grid = to_unstructured_grid(tomato)
    path = tmp_path / "tomato.vtu"
    grid.save(path)
    back = pv.read(path)
    assert back.n_cells == 110
    assert np.array_equal(back.cell_data["tissue"], grid.cell_data["tissue"])
    assert np.allclose(back.compute_cell_sizes()["Volume"], grid.compute_cell_sizes()["Volume"])


def test_plane_cuts_keep_what_lies_behind_the_plane(tomato):
    grid = to_unstructured_grid(tomato)
    clipped = plane_cut(grid, normal="z", origin=(0, 0, 0))
    assert clipped.bounds[5] <= 1e-9 and clipped.bounds[4] == pytest.approx(grid.bounds[4])
    assert clipped.compute_cell_sizes()["Volume"].sum() == pytest.approx(grid.compute_cell_sizes()["Volume"].sum() / 2, rel=0.25)
    cells = plane_cut(tomato, normal=(0, 0, 1), origin=(0, 0, 0), mode="cells")
    centres = cells.cell_centers().points
    assert np.all(centres[:, 2] <= 0) and 0 < cells.n_cells < 110
    assert set(cells.cell_data["volume"].tolist()) <= set(range(110))


def test_plane_parsing_and_refusals():
    assert parse_plane("x=-2") == ((1.0, 0.0, 0.0), (-2.0, 0.0, 0.0))
    for bad in ("w=1", "z", "z=a"):
        with pytest.raises(ValueRefused):
            parse_plane(bad)
    with pytest.raises(ValueRefused):
        plane_cut(build_fruit("round_tomato"), normal=(0, 0, 0))
    with pytest.raises(ValueRefused):
        plane_cut(build_fruit("round_tomato"), mode="slice")
