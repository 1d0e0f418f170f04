"""Where lichen starts: Miller's tangent-sphere accessibility and the seed map (light, humidity)."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv

from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.organs.lichen import accessibility, environment, grow_lichen, seed_map
from ramure.gmap.organs.trimesh import from_polydata

GAP = 1.4  # two unit spheres, centres 1.4 apart: a crease where they meet


@pytest.fixture(scope="module")
def twins():
    a = pv.Sphere(radius=1.0, theta_resolution=60, phi_resolution=60)
    b = pv.Sphere(radius=1.0, center=(GAP, 0, 0), theta_resolution=60, phi_resolution=60)
    return from_polydata(a.boolean_union(b).triangulate().clean())


def _tangent_radius(points):
    """The largest sphere tangent to sphere A at ``points`` that stays out of sphere B (closed form):
    |p + r n - c_B| = 1 + r with n = p (unit sphere at the origin) gives r = (|q|^2 - 1) / (2 (1 - q.n))."""
    q = points - [GAP, 0, 0]
    return (np.einsum("ij,ij->i", q, q) - 1) / (2 * (1 - np.einsum("ij,ij->i", q, points)))


def test_accessibility_matches_the_closed_form_between_two_spheres(twins):
    reference = 1.0
    acc = accessibility(twins, reference=reference)
    points = twins.points
    on_a = (points[:, 0] < GAP / 2 - 0.05) & (np.abs(np.linalg.norm(points, axis=1) - 1) < 1e-3)
    facing = on_a & (points[:, 0] > 0.2)  # the side of A that looks at B
    assert facing.sum() > 100
    exact = np.minimum(_tangent_radius(points[facing]), reference) / reference
    np.testing.assert_allclose(acc[facing], exact, atol=0.06)
    assert acc[points[:, 0] < -0.5].min() == 1.0  # the far side is open


def test_a_convex_surface_is_open_everywhere():
    sphere = from_polydata(pv.Sphere(radius=2, theta_resolution=30, phi_resolution=30))
    assert accessibility(sphere).min() == 1.0


def test_the_seed_map_keeps_the_band_around_the_target(twins):
    acc = accessibility(twins)
    weights = seed_map(twins, target=0.45, width=0.1)
    env = environment(twins)
    assert weights.max() == 1.0 and weights.min() >= 0
    band = np.abs(acc - 0.45) < 0.05
    assert (weights[band] / env[band]).min() > 3 * (weights[acc == 1.0] / env[acc == 1.0]).max()
    light_only = seed_map(twins, target=None)
    np.testing.assert_allclose(light_only, env / env.max())


def test_clusters_start_where_the_map_is_high(twins):
    weights = seed_map(twins, target=0.45, width=0.1)
    growth = grow_lichen(twins, clusters=12, particles=120, r=0.01, adhesion=weights, seed=2)
    seeds = growth.position[growth.age == 0]
    nearest = np.linalg.norm(twins.points[None] - seeds[:, None], axis=2).argmin(axis=1)
    # spores land in proportion to the map and stay with its probability: the band, not the open skin
    assert weights[nearest].mean() > 4 * weights.mean()


def test_bad_targets_and_dark_surfaces_are_refused(twins):
    with pytest.raises(GMapError, match="accessibility target"):
        seed_map(twins, target=1.5)
    with pytest.raises(GMapError, match="reference radius"):
        accessibility(twins, reference=0.0)
    with pytest.raises(GMapError, match="no place"):
        seed_map(twins, target=None, humidity=np.zeros(len(twins.points)), habit="foliose")


def test_the_command_seeds_by_accessibility_and_refuses_a_bad_target(capsys):
    from ramure.app.cli import main

    assert main(["lichen", "--seeding", "accessibility", "--accessibility", "2", "--particles", "50"]) == 2
    assert "--accessibility must be in [0, 1]" in capsys.readouterr().err
    assert main(["lichen", "--seeding", "light", "--clusters", "3", "--particles", "60", "--json"]) == 0
    assert '"seeding": "light"' in capsys.readouterr().out
