"""Internal structure: exocarp, mesocarp, endocarp, septa, locules and seeds."""

import numpy as np
import pytest

from ramure.gmap.organs.fruit import build_fruit
from ramure.gmap.kernel.pyvista import to_unstructured_grid
from ramure.gmap.organs.tissue import CODES, TISSUES, layer_tissues, tissue_counts


@pytest.fixture(scope="module")
def tomato():
    return build_fruit("round_tomato", volume_levels=2, seeds=30, seed=7)


@pytest.fixture(scope="module")
def seedless():
    return build_fruit("round_tomato", volume_levels=2, seeds=0)


def test_every_tissue_is_present_and_each_cell_has_one(tomato):
    counts = tissue_counts(tomato)
    assert counts["pericarp"] == 0
    for name in ("columella", "exocarp", "mesocarp", "endocarp", "septum", "locule"):
        assert counts[name] > 0, name
    assert counts["seed"] == 30
    assert sum(counts.values()) == tomato.n_volumes
    assert tomato.is_valid(), tomato.validity_problems()
    assert tomato.euler_characteristic() == 1


def test_no_differentiation_without_volume_subdivision():
    counts = tissue_counts(build_fruit("round_tomato"))
    assert counts == {**{n: 0 for n in TISSUES}, "columella": 10, "pericarp": 100}


def test_layers_from_the_skin_inwards():
    assert [TISSUES[c] for c in layer_tissues(2)] == ["exocarp", "mesocarp"]
    assert [TISSUES[c] for c in layer_tissues(3)] == ["exocarp", "mesocarp", "locule"]
    assert [TISSUES[c] for c in layer_tissues(8)].count("endocarp") == 1


def test_exocarp_is_exactly_the_branch_cells_on_the_boundary(seedless):
    gm = seedless
    alpha = gm.alpha
    free = alpha[3] == np.arange(gm.n_darts)
    on_skin = np.zeros(gm.n_volumes, bool)
    on_skin[gm.dart_volume[free]] = True
    tissue = gm.volume_data["tissue"]
    branch = gm.volume_data["order"] == 1
    assert np.array_equal(tissue == CODES["exocarp"], branch & on_skin)


def test_septa_cut_the_locules_into_carpels():
    gm = build_fruit("round_tomato", volume_levels=2, seeds=0, carpels=4, septum=0.3)
    vd = gm.volume_data
    centre = gm.volume_centroids()
    theta = np.arctan2(centre[:, 1], centre[:, 0])  # the round tomato's axis is z
    u = np.mod(theta / (2 * np.pi) * 4, 1.0)
    band = np.minimum(u, 1 - u) < 0.15
    tissue = vd["tissue"]
    assert np.all(band[tissue == CODES["septum"]])
    assert not np.any(band[(tissue == CODES["locule"]) | (tissue == CODES["endocarp"])])
    # four carpels: the locule cells of the middle ring fall in four angular groups
    ring = vd["ring"] == 5
    sectors = np.unique(np.floor(theta[ring & (tissue == CODES["locule"])] / (2 * np.pi) * 4) % 4)
    assert sectors.tolist() == [0.0, 1.0, 2.0, 3.0]


def radial_chains(gm, count=40):
    """Vertex chains skin -> core along radial edges near the equator (positions)."""
    vid, pos = gm.vertex_positions()
    nv = len(pos)
    rho = np.bincount(vid, gm.dart_data["radial"], minlength=nv) / np.bincount(vid, minlength=nv)
    nb = {}
    for u, w in zip(vid, vid[gm.alpha[0]]):
        nb.setdefault(int(u), set()).add(int(w))
    mid = 0.5 * (pos[:, 2].max() + pos[:, 2].min())
    skin = np.flatnonzero(np.isclose(rho, 1.0) & (np.abs(pos[:, 2] - mid) < 8))[:count]
    chains = []
    for s in skin:
        chain = [int(s)]
        for level in (0.75, 0.5, 0.25, 0.0):
            nxt = [w for w in nb[chain[-1]] if np.isclose(rho[w], level)]
            assert len(nxt) == 1
            chain.append(nxt[0])
        chains.append(pos[chain])
    return np.array(chains)


def test_layer_thicknesses_are_fractions_of_the_pericarp_depth(seedless):
    chains = radial_chains(seedless)
    depth = np.linalg.norm(chains[:, 4] - chains[:, 0], axis=1)
    along = np.linalg.norm(chains[:, 1:4] - chains[:, :1], axis=2) / depth[:, None]
    assert np.allclose(along, [0.04, 0.34, 0.40], atol=1e-6)  # exocarp, + mesocarp, + endocarp
    thicker = build_fruit("round_tomato", volume_levels=2, seeds=0, exocarp=0.1, mesocarp=0.2, endocarp=0.1)
    chains = radial_chains(thicker)
    depth = np.linalg.norm(chains[:, 4] - chains[:, 0], axis=1)
    along = np.linalg.norm(chains[:, 1:4] - chains[:, :1], axis=2) / depth[:, None]
    assert np.allclose(along, [0.1, 0.3, 0.4], atol=1e-6)


def test_seeds_are_rounded_cells_inside_locules(tomato):
    gm = tomato
    tissue = gm.volume_data["tissue"]
    seeds = np.flatnonzero(tissue == CODES["seed"])
    side, _ = gm.orbit_ids("01")
    first = np.unique(side, return_index=True)[1]
    faces_per_seed = np.bincount(gm.dart_volume[first], minlength=gm.n_volumes)[seeds]
    assert np.all(faces_per_seed == 24)  # one surface subdivision: 6 x 4 quads
    # every neighbour of a seed is locule gel (seeds sit in locules, away from the columella)
    alpha = gm.alpha
    d = np.flatnonzero(np.isin(gm.dart_volume, seeds) & (alpha[3] != np.arange(gm.n_darts)))
    neighbours = np.unique(gm.dart_volume[alpha[3][d]])
    assert set(tissue[neighbours].tolist()) <= {CODES["locule"], CODES["endocarp"], CODES["septum"]}
    # seeds are smaller than the locule cells they were cut from
    grid = to_unstructured_grid(gm)
    vol = grid.compute_cell_sizes()["Volume"]
    assert np.all(vol > 0)
    assert np.median(vol[seeds]) < np.median(vol[tissue == CODES["locule"]])


def test_seed_placement_follows_the_random_seed():
    small = dict(precision=6, ph=8, volume_levels=2, seeds=5)
    a = build_fruit("round_tomato", seed=1, **small)
    b = build_fruit("round_tomato", seed=1, **small)
    c = build_fruit("round_tomato", seed=2, **small)
    assert tissue_counts(a)["seed"] == 5
    assert np.array_equal(a.volume_data["tissue"], b.volume_data["tissue"])
    assert np.allclose(a.points, b.points)
    assert a.n_darts == c.n_darts and not np.allclose(a.points, c.points)
