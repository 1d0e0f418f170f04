"""Open-DLA lichen on closed surfaces: spacing, surface, connectivity, environment, refusals."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.organs.lichen import age_classes, atlas_models, environment, grow_lichen, neighbours, to_polydata
from ramure.gmap.organs.trimesh import from_polydata

R = 0.05


@pytest.fixture(scope="module")
def stone():
    return from_polydata(pv.Sphere(radius=3, theta_resolution=36, phi_resolution=36))


@pytest.fixture(scope="module")
def growth(stone):
    return grow_lichen(stone, clusters=4, particles=400, r=R, seed=5)


def test_no_two_particles_are_closer_than_2r(growth):
    assert growth.count == 400
    pairs = cKDTree(growth.position).query_pairs(2 * R - 1e-12)
    assert pairs == set()


def test_every_particle_lies_on_its_triangle(stone, growth):
    a = stone.points[stone.triangles[growth.triangle, 0]]
    off_plane = np.abs(((growth.position - a) * stone.normals[growth.triangle]).sum(axis=1))
    assert off_plane.max() < 1e-9
    bary = stone.barycentric(growth.triangle, growth.position)
    assert bary.min() > -1e-7 and bary.max() < 1 + 1e-7


def test_every_cluster_is_connected(growth):
    step = R  # the default walk step: a particle joins within 2r + l of its cluster
    for c in np.unique(growth.cluster):
        members = growth.position[growth.cluster == c]
        graph = cKDTree(members).sparse_distance_matrix(cKDTree(members), 2 * R + step + 1e-9)
        count, _ = connected_components(graph, directed=False)
        assert count == 1


def test_the_grid_collision_test_equals_brute_force():
    rng = np.random.default_rng(0)
    points = rng.uniform(0, 2, (500, 3))
    query = rng.uniform(0, 2, (300, 3))
    dist, within = neighbours(points, query, r=0.05, step=0.05, rho=0.1)
    brute = np.linalg.norm(query[:, None] - points[None], axis=2)
    reach = 0.15  # the grid is exact up to its cell size max(2r + l, rho)
    close = brute.min(axis=1) <= reach
    assert np.allclose(dist[close], brute.min(axis=1)[close])
    assert np.array_equal(within, (brute <= 0.1).sum(axis=1))


def test_a_zero_environment_adds_nothing(stone):
    growth = grow_lichen(stone, clusters=3, particles=200, r=R, env=np.zeros(len(stone.points)), seed=1, b_tokens=2)
    assert growth.count == 3  # the seeds only


def test_same_seed_same_lichen(stone):
    one = grow_lichen(stone, clusters=2, particles=60, r=R, seed=9)
    two = grow_lichen(stone, clusters=2, particles=60, r=R, seed=9)
    assert np.array_equal(one.position, two.position) and np.array_equal(one.cluster, two.cluster)


def test_old_particles_inside_young_ones_on_the_rim(growth):
    classes = age_classes(growth, 3)
    spread = []
    for c in np.unique(growth.cluster):
        members = growth.cluster == c
        seed = growth.position[members & (growth.age == 0)][0]
        dist = np.linalg.norm(growth.position - seed, axis=1)
        spread.append((dist[members & (classes == 0)].mean(), dist[members & (classes == 2)].mean()))
    inner, rim = np.mean(spread, axis=0)
    assert rim > inner
    models = atlas_models(growth, [[(0, 0.5), (0.5, 1)]] * 3, seed=0)
    assert set(np.unique(models).tolist()) <= {0, 1}
    with pytest.raises(GMapError, match="disjoint and cover"):
        atlas_models(growth, [[(0, 0.4), (0.5, 1)]] * 3)


def test_habits_respond_to_light_and_humidity(stone):
    dry = environment(stone, "foliose", humidity=np.zeros(len(stone.points)))
    wet = environment(stone, "foliose", humidity=np.ones(len(stone.points)))
    assert dry.max() == 0.0 and wet.mean() > 0.2
    disc = to_polydata(grow_lichen(stone, clusters=1, particles=5, r=R, seed=0), stone)
    assert disc.n_cells > 0


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"r": 0.0}, "r must be"),
        ({"eps": -1.0}, "eps must be"),
        ({"step": 0.0}, "step l must be"),
        ({"alpha": 1.5}, "alpha"),
        ({"particles": 10**9}, "particles"),
        ({"habit": "moss"}, "unknown lichen habit"),
        ({"env": np.zeros(3)}, "environment map has 3 values"),
        ({"adhesion": np.full(1298, np.nan)}, "adhesion"),
        ({"env": lambda mesh: np.full(len(mesh.points), np.nan)}, "environment map must hold numbers"),
        ({"turn": 200.0}, "turn angle"),
    ],
)
def test_bad_parameters_are_refused(stone, kwargs, message):
    kwargs = {k: v(stone) if callable(v) else v for k, v in kwargs.items()}
    with pytest.raises(GMapError, match=message):
        grow_lichen(stone, **{"clusters": 2, "particles": 20, "r": R, **kwargs})


def test_an_open_surface_is_refused():
    with pytest.raises(GMapError, match="close the model first"):
        from_polydata(pv.Plane())


def test_a_non_manifold_surface_is_refused():
    from ramure.gmap.organs.trimesh import TriMesh

    # two closed tetrahedra sharing the edge 0-1: that edge has four triangles
    pts = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, 0.5, 1], [0.5, -1, 0], [0.5, -0.5, -1.0]])
    tris = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3], [0, 1, 4], [0, 5, 1], [1, 5, 4], [4, 5, 0]])
    with pytest.raises(GMapError, match=r"1 edge\(s\) shared by more than two triangles.*close the model first"):
        TriMesh(pts, tris)


def test_command_line_grows_lichen_on_a_stone(tmp_path):
    import json
    import subprocess
    import sys

    from matplotlib.image import imread

    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "ramure.app.cli",
            "lichen",
            "--clusters",
            "3",
            "--particles",
            "60",
            "--r",
            "0.05",
            "--json",
            "-o",
            str(tmp_path / "l.png"),
        ],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert out.returncode == 0, out.stderr
    facts = json.loads(out.stdout)
    assert facts["particles"] == 60 and facts["clusters"] == 3 and facts["intersection_tests"] > 0
    assert imread(tmp_path / "l.png")[..., :3].std() > 0.05
    bad = subprocess.run(
        [sys.executable, "-m", "ramure.app.cli", "lichen", "--r", "-1"], capture_output=True, text=True, cwd=tmp_path
    )
    assert bad.returncode == 2 and "r must be a number > 0" in bad.stderr and "Traceback" not in bad.stderr
