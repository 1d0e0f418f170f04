"""Leaf ageing and fall: the Open Markov Chain's laws, piles, streams that survive a regrow."""

from __future__ import annotations

import numpy as np
import pytest

import ramure
from ramure.errors import ValueRefused
from ramure.lsys.architecture.seasons import LeafChain, age_leaves, autumn_chain, bilinear

N = 100_000


def _two_states(half_life=4.0, fall=np.inf):
    targets = np.zeros((2, 2, 4))
    targets[0, 1] = 1.0
    return LeafChain(("green", "brown"), [[half_life] * 4, [1e9] * 4], targets, [fall, fall], [1.0, 1.0])


def _many(n=N):
    return np.arange(n), np.zeros((n, 3)) + [0, 0, 5]


def test_rows_sum_to_one_in_every_environment():
    chain = autumn_chain()
    a, b = np.meshgrid(np.linspace(0, 1, 11), np.linspace(0, 1, 11))
    mats = chain.matrices(a.ravel(), b.ravel(), dt=0.7)
    assert np.allclose(mats.sum(axis=2), 1.0) and (mats >= 0).all()


def test_half_the_leaves_have_left_a_state_after_its_half_life():
    season = age_leaves(_many(), _two_states(half_life=4.0), steps=4, seed=3)
    still_green = np.mean(season.states[4] == 0)
    assert abs(still_green - 0.5) < 0.005
    assert np.mean(season.states[2] == 0) == pytest.approx(2**-0.5, abs=0.005)


def test_bilinear_half_lives_and_weights_reproduce_their_corners():
    chain = autumn_chain()
    for corner, (a, b) in enumerate([(0, 0), (1, 0), (0, 1), (1, 1)]):
        m = chain.matrix(a, b, dt=1.0)
        tau = chain.half_life[:, corner]
        assert m[0, 0] == pytest.approx(np.exp(-np.log(2) / tau[0]))
        leaving = 1 - m[0, 0]
        assert m[0, 1] / leaving == pytest.approx(chain.targets[0, 1, corner])
        assert m[0, 2] / leaving == pytest.approx(chain.targets[0, 2, corner])
    assert bilinear([1.0, 2.0, 3.0, 4.0], 0.5, 0.5) == pytest.approx(2.5)


def test_in_still_air_half_the_leaves_stay_attached_after_the_fall_half_life():
    season = age_leaves(_many(), _two_states(half_life=1e9, fall=5.0), steps=5, seed=1)
    assert abs(np.mean(~season.fallen) - 0.5) < 0.005
    windy = age_leaves(_many(20_000), _two_states(half_life=1e9, fall=5.0), steps=5, seed=1, wind=0.5)
    assert np.mean(~windy.fallen) < np.mean(~season.fallen)  # wind tears leaves off


def test_fallen_leaves_pile_up_downwind_on_the_ground():
    organs = ramure.derive("fruit_tree").skeleton().organs
    season = age_leaves(organs, autumn_chain(), steps=16, seed=0, wind=(0.08, 0.0), thickness=0.05)
    landed = season.ground[season.fallen]
    assert len(landed) > 10 and np.isfinite(landed).all() and (landed[:, 2] >= 0.025 - 1e-12).all()
    start = organs.position[organs.kind == "Leaf"][season.fallen]
    assert landed[:, 0].mean() > start[:, 0].mean()  # carried downwind
    assert landed[:, 2].max() > 0.05  # some leaves landed on others
    assert season.intersection_tests >= len(landed)


def test_same_seed_same_autumn_and_a_leaf_keeps_its_fate_when_others_change():
    ids, pos = _many(5_000)
    full = age_leaves((ids, pos), autumn_chain(), steps=10, seed=7)
    again = age_leaves((ids, pos), autumn_chain(), steps=10, seed=7)
    assert np.array_equal(full.states, again.states) and np.array_equal(full.fallen, again.fallen)
    part = age_leaves((ids[::3], pos[::3]), autumn_chain(), steps=10, seed=7)  # as after a regrow elsewhere
    assert np.array_equal(part.states, full.states[:, ::3]) and np.array_equal(part.fall_step, full.fall_step[::3])
    other = age_leaves((ids, pos), autumn_chain(), steps=10, seed=8)
    assert not np.array_equal(other.states, full.states)


def test_a_regrow_resets_only_the_regrown_leaves():
    session = ramure.Session(ramure.load("fruit_tree"), n=5)
    before = age_leaves(session.derivation.skeleton().organs, autumn_chain(), steps=8, seed=2)
    session.regrow(session.leaves_with_symbol("Leaf")[:3], seed=9)
    after = age_leaves(session.derivation.skeleton().organs, autumn_chain(), steps=8, seed=2)
    kept, i, j = np.intersect1d(before.leaf_ids, after.leaf_ids, return_indices=True)
    assert len(kept) > 0 and np.array_equal(before.states[:, i], after.states[:, j])


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda t: t.__setitem__((0, 1, 0), 0.5), "state 'green'.*sum to"),
        (lambda t: t.__setitem__((0, 0, 0), 0.5), "state 'green'.*half-life"),
    ],
)
def test_bad_chains_are_refused_naming_the_state(change, message):
    targets = np.zeros((2, 2, 4))
    targets[0, 1] = 1.0
    change(targets)
    with pytest.raises(ValueRefused, match=message):
        LeafChain(("green", "brown"), [[4] * 4, [4] * 4], targets, [5, 5], [1, 1])


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"half_life": 0.0}, "half-lives must be > 0"),
    ],
)
def test_non_positive_half_life_is_refused(kwargs, message):
    with pytest.raises(ValueRefused, match=message):
        _two_states(**kwargs)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"wind": -1.0}, "wind strength"),
        ({"heat": np.full(3, np.nan)}, "heat"),
        ({"humidity": 1.5}, "humidity"),
        ({"steps": 2.5}, "steps"),
    ],
)
def test_bad_runs_are_refused(kwargs, message):
    with pytest.raises(ValueRefused, match=message):
        age_leaves(_many(3), autumn_chain(), **kwargs)


def test_command_line_ages_a_plant_and_draws_the_ground(tmp_path):
    import json
    import subprocess
    import sys

    from matplotlib.image import imread

    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "ramure.app.cli",
            "autumn",
            "fruit_tree",
            "--steps",
            "12",
            "--wind",
            "0.05,0",
            "--json",
            "-o",
            str(tmp_path / "a.png"),
        ],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert out.returncode == 0, out.stderr
    facts = json.loads(out.stdout)
    assert facts["leaves"] == 50 and 0 < facts["fallen_leaves"] == facts["fallen_per_step"][-1]
    assert sum(facts["states"].values()) == 50
    picture = imread(tmp_path / "a.png")[..., :3]
    assert picture.std() > 0.05  # not blank
    bad = subprocess.run(
        [sys.executable, "-m", "ramure.app.cli", "autumn", "fruit_tree", "--heat", "2"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert bad.returncode == 2 and "--heat must be in [0, 1]" in bad.stderr


def test_polygon_leaves_age_fall_and_keep_their_streams_through_a_regrow():
    from ramure.lsys.architecture.seasons import plant_leaves

    session = ramure.Session(ramure.load("abop/bush_1_25"), n=4)
    skeleton = session.derivation.skeleton()
    ids, centres = plant_leaves(skeleton)
    polygons = skeleton.polygons
    assert len(ids) == len(polygons) == 42 and len(skeleton.organs.kind) == 0  # leaves made of '{ . }' only
    first = polygons.points[polygons.offsets[0] : polygons.offsets[1]]
    assert ids[0] == polygons.leaf_id[0] and np.allclose(centres[0], first.mean(axis=0))
    # the ids are those of the polygons' triangles in the mesh (what the views colour and hide)
    mesh = skeleton.to_polydata()
    leaf_cells = np.asarray(mesh.cell_data["kind"]) == 1
    assert set(np.asarray(mesh.cell_data["leaf_id"])[leaf_cells].tolist()) == set(ids.tolist())
    before = age_leaves(skeleton, autumn_chain(), steps=8, seed=3, wind=0.1)
    assert len(before.leaf_ids) == 42 and 0 < before.fallen.sum() < 42
    assert np.isfinite(before.ground[before.fallen]).all() and (before.ground[before.fallen, 2] >= 0).all()
    session.regrow([int(i) for i in polygons.leaf_id[:2]], seed=11)  # two leaves regrown
    after = age_leaves(session.derivation.skeleton(), autumn_chain(), steps=8, seed=3, wind=0.1)
    kept, i, j = np.intersect1d(before.leaf_ids, after.leaf_ids, return_indices=True)
    assert 0 < len(kept) < 42 and np.array_equal(before.states[:, i], after.states[:, j])


def test_a_plant_without_leaves_is_refused_by_name():
    """Issue 40: ``autumn`` on a leafless tree gave "0 leaves" and exit 0; now it says why."""
    skeleton = ramure.derive("abop_tree", n=3).skeleton()
    with pytest.raises(ValueRefused, match="no leaves to age.*Leaf module"):
        age_leaves(skeleton, autumn_chain(), steps=4)
    empty = age_leaves((np.arange(0), np.zeros((0, 3))), autumn_chain(), steps=4)  # an explicit empty set stays legal
    assert len(empty.leaf_ids) == 0


def test_autumn_command_refuses_a_leafless_plant(capsys, tmp_path):
    from ramure.app.cli import main

    out = tmp_path / "autumn.png"
    assert main(["autumn", "abop_tree", "-n", "3", "-o", str(out)]) == 2
    assert "no leaves to age" in capsys.readouterr().err
    assert not out.exists()


# -- litter: curled leaves on compacting piles ------------------------------------------------
def _area(points, triangles):
    c = points[triangles]
    return 0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1).sum()


def test_a_rolled_blade_keeps_its_area_and_lifts_its_edges_by_the_bend():
    from ramure.lsys.architecture.seasons import leaf_shape

    flat_points, triangles = leaf_shape(1.0, 0.5, rows=41, cols=21)
    u = np.linspace(0, 1, 20001)
    exact = np.trapezoid(0.5 * np.sin(np.pi * u) ** 0.7 * (1 - u / 4), u)  # 2 * half-width, length 1
    assert abs(_area(flat_points, triangles) - exact) < 0.03 * exact
    assert np.ptp(flat_points[:, 2]) == 0.0
    roll = 1.2
    points, same = leaf_shape(1.0, 0.5, roll=roll, rows=41, cols=21)
    assert abs(_area(points, same) - _area(flat_points, triangles)) < 0.01 * exact  # bent, not stretched
    middle = points.reshape(41, 21, 3)[20]  # the row at u = 1/2
    half = 0.25 * (1 - 0.5 / 4)
    np.testing.assert_allclose(middle[[0, -1], 2], half * (1 - np.cos(roll)) / roll, rtol=1e-9)


def _column(n, thickness=0.02):
    from ramure.lsys.architecture.seasons import Season

    ground = np.column_stack([np.full(n, 0.1), np.full(n, 0.1), thickness * (np.arange(n) + 0.5)])
    return Season(
        np.arange(n),
        np.zeros((3, n), np.int64),
        np.ones(n, bool),
        np.zeros(n, np.int64),
        ground,
        np.zeros(n, np.int64),
        thickness=thickness,
    )


def test_a_pile_compacts_to_the_closed_form():
    from ramure.lsys.architecture.seasons import COMPACTED, COMPACTION_DEPTH, pile_heights

    n, t = 12, 0.02
    z = pile_heights(_column(n, t))
    k = np.arange(n)[::-1]  # leaves above each one, bottom first
    pressed = t * (COMPACTED + (1 - COMPACTED) * np.exp(-k / COMPACTION_DEPTH))
    np.testing.assert_allclose(z, np.cumsum(pressed) - pressed / 2, rtol=1e-12)
    assert np.all(np.diff(z) > 0) and z[-1] + pressed[-1] / 2 < n * t  # lower than the leaves stacked loose
    assert pile_heights(_column(1, t))[0] == pytest.approx(t / 2)  # one leaf lies as it landed


def test_litter_curls_the_leaves_that_lay_longest():
    from ramure.lsys.architecture.seasons import leaf_shape, litter

    season = _column(2)
    season.fall_step[:] = [0, 2]  # the first fell two steps before the second
    season.ground[1, :2] += 1.0  # on open ground of its own
    points, triangles, leaf = litter(season, step=2, size=0.3)
    assert len(triangles) == 2 * len(leaf_shape()[1]) and set(leaf.tolist()) == {0, 1}
    rise = [np.ptp(points[np.unique(triangles[leaf == i])][:, 2]) for i in (0, 1)]
    assert rise[0] > 0.01 and rise[1] < 1e-9  # 2 steps on the ground against a leaf just fallen
