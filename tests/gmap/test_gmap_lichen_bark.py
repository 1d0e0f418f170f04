"""Lichen on bark: a derived plant's branches welded into a closed surface, a volumetric wood's skin."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ramure.gmap.organs import _dla_kernel as kernel
from ramure.gmap.organs.lichen import grow_lichen
from ramure.gmap.organs.trimesh import tubes_surface


def _euler(mesh):
    edges = np.sort(np.concatenate([mesh.triangles[:, [0, 1]], mesh.triangles[:, [1, 2]], mesh.triangles[:, [2, 0]]]), axis=1)
    used = np.unique(mesh.triangles)
    return len(used) - len(np.unique(edges, axis=0)) + len(mesh.triangles)


def _on_surface(mesh, growth, tol=1e-9):
    a = mesh.points[mesh.triangles[growth.triangle, 0]]
    scale = float(np.ptp(mesh.points, axis=0).max())
    off = np.abs(((growth.position - a) * mesh.normals[growth.triangle]).sum(axis=1))
    bary = mesh.barycentric(growth.triangle, growth.position)
    return off.max() < tol * max(scale, 1.0) and bary.min() > -1e-6 and bary.max() < 1 + 1e-6


def _check_lichen(mesh, growth):
    assert _on_surface(mesh, growth)
    assert cKDTree(growth.position).query_pairs(2 * growth.r - 1e-12) == set()
    for c in np.unique(growth.cluster):
        members = growth.position[growth.cluster == c]
        graph = cKDTree(members).sparse_distance_matrix(cKDTree(members), 3 * growth.r + 1e-9)
        assert connected_components(graph, directed=False)[0] == 1


@pytest.fixture(scope="module")
def tree():
    from ramure.lsys import LSystem

    return LSystem.from_file("fruit_tree").derive(n=4, seed=0).skeleton()


def test_a_plant_s_branches_weld_into_one_closed_surface_of_genus_0(tree):
    from ramure.app.details import plant_bark

    _, mesh = plant_bark(tree, thinnest=0.0)  # accepted by TriMesh: every edge has two opposite triangles
    assert _euler(mesh) == 2  # one connected tree of tubes: a sphere
    lateral = np.pi * (tree.base_radius + tree.top_radius) * np.linalg.norm(tree.end - tree.start, axis=1)
    assert 0.6 * lateral.sum() < mesh.area() < 1.2 * lateral.sum()


def test_a_walker_crosses_a_tube_s_end_cap_and_never_leaves_the_surface():
    # one capped segment: walks cross the sharp rim between side and cap many times
    mesh = tubes_surface([[0, 0, 0]], [[0, 0, 1.0]], [0.1], [0.1], sides=10)
    rng = np.random.default_rng(1)
    tri, pos = mesh.random_points(300, rng)
    for t, p in zip(tri, pos):
        d = kernel.tangent_direction(mesh.normals[t], rng.uniform(0, 2 * np.pi))
        t, p, d = kernel.step_on_surface(mesh.points, mesh.triangles, mesh.across, mesh.normals, int(t), p, d, 1.7)
        a = mesh.points[mesh.triangles[t, 0]]
        assert abs((p - a) @ mesh.normals[t]) < 1e-9
        bary = mesh.barycentric(np.array([t]), p[None])[0]
        assert bary.min() > -1e-6
        assert abs(d @ mesh.normals[t]) < 1e-9  # the direction lies in its triangle's plane


def test_lichen_on_a_plant_s_bark_spaced_on_the_surface_and_connected(tree):
    from ramure.app.details import cover_radius, plant_bark

    _, mesh = plant_bark(tree)
    growth = grow_lichen(mesh, clusters=6, particles=600, r=cover_radius(mesh, 600), seed=2)
    assert growth.count == 600 and len(np.unique(growth.cluster)) == 6
    _check_lichen(mesh, growth)
    again = grow_lichen(mesh, clusters=6, particles=600, r=cover_radius(mesh, 600), seed=2)
    assert np.array_equal(again.position, growth.position)


def test_lichen_on_a_wood_s_bark():
    from ramure.app.details import cover_radius, wood_bark
    from ramure.gmap.organs.wood import grow_wood

    _, mesh = wood_bark(grow_wood("pine", years=4, branches=0))
    growth = grow_lichen(mesh, clusters=4, particles=400, r=cover_radius(mesh, 400), seed=0)
    assert growth.count == 400
    _check_lichen(mesh, growth)


def test_command_line_grows_lichen_on_a_plant_and_refuses_two_substrates(tmp_path, capsys):
    from PIL import Image

    from ramure.app.cli import main

    assert (
        main(
            [
                "lichen",
                "--on-plant",
                "fruit_tree",
                "-n",
                "4",
                "--clusters",
                "5",
                "--particles",
                "400",
                "--json",
                "-o",
                str(tmp_path / "bark.png"),
            ]
        )
        == 0
    )
    facts = json.loads(capsys.readouterr().out)
    assert facts["particles"] == 400 and facts["clusters"] == 5 and facts["on"] == "fruit_tree"
    picture = np.asarray(Image.open(tmp_path / "bark.png").convert("RGB")).astype(int)
    greenish = (picture[:, :, 1] > picture[:, :, 2] + 15) & (picture[:, :, 1] > picture[:, :, 0])
    assert greenish.mean() > 0.01  # the lichen discs show
    assert main(["lichen", "--on-plant", "fruit_tree", "--on-wood"]) == 2
    assert "not both" in capsys.readouterr().err


def test_the_welded_surface_owns_its_arrays():
    # A view into manifold3d's mesh (through a memoryview) kept that C++ object alive, and
    # nanobind reported it leaked at exit: the arrays must be numpy's own memory.
    mesh = tubes_surface([[0, 0, 0]], [[0, 0, 1.0]], [0.1], [0.1], sides=6)
    for array in (mesh.points, mesh.triangles):
        while isinstance(array.base, np.ndarray):
            array = array.base
        assert array.base is None and array.flags.owndata, type(array.base)
