"""Cracks cut topologically into 3-G-maps (a tomato's skin, a pine board's end grain)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ramure.gmap.organs.cracks import random_pattern
from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.organs.fruit import build_fruit
from ramure.gmap.organs.mapcracks import Skin, crack_edges, crack_map, wall_faces
from ramure.gmap.kernel.pyvista import boundary_polydata


@pytest.fixture(scope="module")
def fruit():
    return build_fruit("round_tomato", volume_levels=1)


@pytest.fixture(scope="module")
def side(fruit):
    _, pos = fruit.vertex_positions()
    return tuple(pos[np.argmax(pos[:, 0])])


@pytest.fixture(scope="module")
def pattern():
    return random_pattern(12, seed=0, length=8.0, width=3.0, depth=8.0).timing(speed=4.0, tau=2.0)


def test_the_cracked_fruit_is_a_valid_ball_with_its_crack_open(fruit, side, pattern):
    before = fruit.copy()
    out, facts = crack_map(fruit, pattern, anchor=side, direction=(0, 0, 1))
    assert facts["valid"] and out.is_valid()
    # a notch keeps the solid a ball and its skin a sphere
    assert (facts["euler_before"], facts["euler_after"]) == (1, 1) == (fruit.euler_characteristic(), out.euler_characteristic())
    assert (facts["skin_euler_before"], facts["skin_euler_after"]) == (2, 2) == (out.boundary().euler_characteristic(),) * 2
    # the crack cuts through the cells under its curve: each cut cell is now two
    assert out.n_volumes == fruit.n_volumes + facts["cells_split"] > fruit.n_volumes
    # the mouth runs through skin faces (one or more edges per cut face), the walls are the cuts' faces
    assert facts["skin_edges_opened"] >= 5 and facts["faces_unsewn"] >= 5 and facts["cells_split"] >= facts["faces_unsewn"]
    # each unsewn face is now two free faces on the skin: the crack's walls
    free_before = int((fruit.alpha[3] == np.arange(fruit.n_darts)).sum())
    free_after = int((out.alpha[3] == np.arange(out.n_darts)).sum())
    assert free_after > free_before
    walls = wall_faces(out)
    assert walls.sum() == 2 * facts["faces_unsewn"] and len(walls) == boundary_polydata(out).n_cells
    # the split vertices: the crack's own, off the tips and the bottom
    assert facts["duplicated_vertices"] > 0 and facts["cut_vertices"] > 0
    assert out.cells(0)[1] == fruit.cells(0)[1] + facts["cut_vertices"] + facts["duplicated_vertices"]
    assert facts["opened_vertices"] > 0 and 0 < facts["volume_lost"] < 0.05 * facts["volume_before"]
    # the input map is untouched
    assert np.array_equal(fruit.alpha, before.alpha) and np.array_equal(fruit.points, before.points)


def test_crack_length_is_monotone_in_time_and_ends_as_the_static_crack(fruit, side, pattern):
    end = float((pattern.start + pattern.duration).max())
    lengths, edge_sets = [], []
    skin = Skin(fruit)
    for t in np.linspace(0.0, end, 7):
        edges = crack_edges(skin, pattern, side, (0, 0, 1), t0=float(t))
        edge_sets.append(set(edges))
        if edges:
            _, facts = crack_map(fruit, pattern, anchor=side, direction=(0, 0, 1), t0=float(t))
            assert facts["euler_after"] == 1 and facts["skin_euler_after"] == 2
            lengths.append(facts["length"])
        else:
            lengths.append(0.0)
    assert lengths[0] == 0.0 and lengths[-1] > 0
    assert all(b >= a for a, b in zip(lengths, lengths[1:])), lengths
    assert all(a <= b for a, b in zip(edge_sets, edge_sets[1:]))  # an earlier crack is part of a later one
    _, static = crack_map(fruit, pattern, anchor=side, direction=(0, 0, 1))
    _, late = crack_map(fruit, pattern, anchor=side, direction=(0, 0, 1), t0=end + 5.0)
    assert late["length"] == static["length"] and late["faces_unsewn"] == static["faces_unsewn"]
    assert late["volume_lost"] == pytest.approx(static["volume_lost"], rel=1e-12)


def test_same_seed_same_crack_other_seed_other_crack(fruit, side):
    one = crack_map(fruit, random_pattern(10, seed=3, length=8.0, width=2.0, depth=8.0), anchor=side, direction=(0, 0, 1))
    two = crack_map(fruit, random_pattern(10, seed=3, length=8.0, width=2.0, depth=8.0), anchor=side, direction=(0, 0, 1))
    other = crack_map(fruit, random_pattern(10, seed=4, length=8.0, width=2.0, depth=8.0), anchor=side, direction=(0, 0, 1))
    assert np.array_equal(one[0].alpha, two[0].alpha) and np.array_equal(one[0].points, two[0].points)
    assert not np.array_equal(one[0].alpha, other[0].alpha)


def test_a_cracked_map_can_be_cut_again(fruit, side, pattern):
    from ramure.gmap.kernel.cut import cut_map

    out, _ = crack_map(fruit, pattern, anchor=side, direction=(0, 0, 1))
    # across the crack (which runs up from ``side`` near the plane y = 0, too near for a cut along it)
    half = cut_map(out, (0, 0, 1), (0, 0, side[2] + 10.0))
    assert half.is_valid() and half.n_volumes < out.n_volumes
    assert "crack" in half.dart_data and (np.asarray(half.dart_data["crack"]) == 1).any()


def test_bad_cracks_are_refused(fruit, pattern):
    from ramure.gmap import GMap3

    with pytest.raises(GMapError, match="not on the surface"):
        crack_map(fruit, pattern, anchor=(500.0, 0, 0))
    skin = Skin(fruit)
    tri, point, _ = skin.mesh.closest_point(skin.pos[skin.used].mean(axis=0) + (0, 0, 1000.0))
    with pytest.raises(GMapError, match="along the surface normal"):
        crack_map(fruit, pattern, anchor=tuple(point), direction=tuple(skin.mesh.normals[tri]))
    cube = GMap3()
    cube.add_prisms(4)
    cube.embed()
    _, pos = cube.vertex_positions()
    top = (pos[:, 0].mean(), pos[:, 1].mean(), pos[:, 2].max())
    with pytest.raises(GMapError, match="no cell to cut"):  # a crack shallower than the cube's one cell
        crack_map(cube, random_pattern(4, seed=0, length=0.1 * np.ptp(pos), width=0.01, depth=0.1), anchor=top)


def test_a_crack_too_wide_for_its_cells_still_opens(fruit, side):
    wide = random_pattern(63, seed=0, length=8.0, width=3.0, depth=8.0)  # the old default: refused before issue 40
    out, facts = crack_map(fruit, wide, anchor=side, direction=(0, 0, 1))
    assert facts["valid"] and facts["opened_vertices"] > 0 and facts["euler_after"] == 1
    # 3 units each side asked, on cells about 8 units across: the opening is capped by their room
    assert 0 < facts["opening"] < 2 * 3.0 and facts["narrowed"] <= 1.0
    _, same = crack_map(fruit, random_pattern(8, seed=2, length=8.0, width=3.0, depth=8.0), anchor=side, direction=(0, 0, 1))
    assert same["narrowed"] == 1.0 and same["held_vertices"] == 0


def test_command_line_cracks_a_pine_board_and_a_fruit(tmp_path, capsys):
    from ramure.app.cli import main

    assert main(["crack", "--on", "wood", "--years", "6", "--nodes", "8", "--json", "-o", str(tmp_path / "board.png")]) == 0
    facts = json.loads(capsys.readouterr().out)
    assert facts["valid"] and facts["euler_after"] == facts["euler_before"] == 1
    assert facts["skin_euler_after"] == 2 and facts["skin_edges_opened"] > 3 and facts["volume_lost"] > 0
    from PIL import Image

    picture = np.asarray(Image.open(tmp_path / "board.png").convert("RGB")).astype(int)
    dark = (picture.sum(axis=2) < 90).mean()  # the crack's walls are drawn near black
    assert picture.std() > 20 and 0.001 < dark < 0.3
    assert main(["crack", "--on", "fruit", "--json", "-o", str(tmp_path / "fruit.vtu")]) == 0  # the defaults work (issue 40)
    import pyvista as pv

    facts = json.loads(capsys.readouterr().out)
    grid = pv.read(tmp_path / "fruit.vtu")
    assert grid.n_cells == facts["volumes"] > 8000  # twice subdivided: a finer crack
    assert 0 < (grid.cell_data["wound"] == 1).sum() <= 2 * facts["faces_unsewn"]  # each wall has two cells
    assert facts["valid"] and facts["nodes"] == 6 and facts["skin_edges_opened"] > 3
    assert 10 < facts["length_mm"] < 65 and facts["volume_lost_mm3"] > 0  # on a 65 mm tomato
    assert main(["crack", "--on", "fruit", "--anchor", "0,0,900"]) == 2
    err = capsys.readouterr().err
    assert "not on the surface" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
