"""Fruit organs of a plant become volumetric fruit that keep their history-leaf id."""

from types import SimpleNamespace

import numpy as np
import pytest

from ramure.gmap.kernel.errors import ValueRefused
from ramure.gmap.organs.plant import fruits_from_organs, fruits_from_skeleton
from ramure.gmap.kernel.pyvista import to_unstructured_grid
from ramure.gmap.organs.tissue import CODES


def organs(k=3):
    rng = np.random.default_rng(0)
    pos = rng.normal(size=(k, 3)) * 10
    heading = rng.normal(size=(k, 3))
    heading /= np.linalg.norm(heading, axis=1, keepdims=True)
    left = np.cross(heading, [0.3, 0.2, 1.0])
    left /= np.linalg.norm(left, axis=1, keepdims=True)
    frames = np.stack([heading, left, np.cross(heading, left)], axis=1)
    return pos, frames, np.linspace(1.0, 2.0, k), np.array([7, 19, 400])[:k]


def per_fruit(gm, leaf):
    mask = gm.volume_data["leaf_id"][gm.dart_volume] == leaf
    return gm.points[mask]


def extent_in_frame(pts, frame):
    """Largest extent of the points along the frame's axes (the fruit's own bounding box)."""
    local = pts @ np.asarray(frame).T
    return (local.max(axis=0) - local.min(axis=0)).max()


def test_each_fruit_hangs_from_its_organ_at_its_size():
    pos, frames, sizes, leaf = organs()
    gm = fruits_from_organs(pos, frames, sizes, leaf)
    assert gm.n_volumes == 3 * 110 and gm.is_valid()
    assert gm.euler_characteristic() == 3  # three solid balls
    for k in range(3):
        pts = per_fruit(gm, leaf[k])
        assert extent_in_frame(pts, frames[k]) == pytest.approx(sizes[k])
        rel = pts - pos[k]
        along = rel @ frames[k, 0]
        assert along.min() > -0.2 * sizes[k]  # stem end at the organ ...
        assert along.max() > 0.6 * sizes[k]  # ... body along the heading
        # the stem point (top of the axis) is exactly at the organ's position
        vd = gm.volume_data
        last_axis = np.flatnonzero((vd["leaf_id"] == leaf[k]) & (vd["order"] == 0))[-1]
        top = gm.points[(gm.dart_volume == last_axis) & (gm.dart_data["face"] == 1)].mean(axis=0)
        assert np.allclose(top, pos[k], atol=1e-9)
    grid = to_unstructured_grid(gm)
    assert sorted(set(grid.cell_data["leaf_id"].tolist())) == sorted(leaf.tolist())
    assert np.all(grid.compute_cell_sizes()["Volume"] > 0)


def test_regenerating_one_fruit_changes_only_that_fruit():
    pos, frames, sizes, leaf = organs()
    small = dict(precision=5, ph=8, seeds=4)
    base = fruits_from_organs(pos, frames, sizes, leaf, params=small, volume_levels=2, seed=1)
    again = fruits_from_organs(pos, frames, sizes, leaf, params=small, volume_levels=2, seed=1)
    assert np.allclose(base.points, again.points)
    regrown = fruits_from_organs(pos, frames, sizes, leaf, params=small, volume_levels=2, seed=1, overrides={19: {"seed": 12345}})
    for lid in (7, 400):
        assert np.array_equal(per_fruit(base, lid), per_fruit(regrown, lid))
    a, b = per_fruit(base, 19), per_fruit(regrown, 19)
    assert a.shape != b.shape or not np.allclose(a, b)
    tissue = regrown.volume_data["tissue"]
    assert np.sum(tissue[regrown.volume_data["leaf_id"] == 19] == CODES["seed"]) == 4
    # a new preset and size for one fruit
    other = fruits_from_organs(pos, frames, sizes, leaf, overrides={7: {"preset": "banana", "size": 5.0}})
    assert np.sum(other.volume_data["leaf_id"] == 7) == 110
    pts = per_fruit(other, 7)
    assert extent_in_frame(pts, frames[0]) == pytest.approx(5.0)
    assert np.array_equal(per_fruit(other, 19), per_fruit(fruits_from_organs(pos, frames, sizes, leaf), 19))


def test_bad_organs_are_refused():
    pos, frames, sizes, leaf = organs()
    with pytest.raises(ValueRefused, match="positive"):
        fruits_from_organs(pos, frames, [1.0, 0.0, 1.0], leaf)
    with pytest.raises(ValueRefused, match="disagree"):
        fruits_from_organs(pos, frames[:2], sizes, leaf)
    with pytest.raises(ValueRefused, match="not fruit"):
        fruits_from_organs(pos, frames, sizes, leaf, overrides={3: {"seed": 1}})
    with pytest.raises(ValueRefused, match="unknown fruit parameter"):
        fruits_from_organs(pos, frames, sizes, leaf, overrides={7: {"colour": 1}})
    assert fruits_from_organs(np.zeros((0, 3)), np.zeros((0, 3, 3)), [], []).n_darts == 0


def test_fruits_from_a_duck_typed_skeleton():
    pos, frames, sizes, leaf = organs()
    kind = np.array(["Fruit", "Leaf", "Fruit"], dtype=object)
    sk = SimpleNamespace(organs=SimpleNamespace(kind=kind, position=pos, frame=frames, size=sizes, leaf_id=leaf))
    gm = fruits_from_skeleton(sk, preset="cherry_tomato")
    assert sorted(set(gm.volume_data["leaf_id"].tolist())) == [7, 400]


def test_fruits_of_the_fruit_tree_grammar():
    from ramure.lsys import LSystem

    sk = LSystem.from_file("grammars/fruit_tree.lsys").derive().skeleton()
    is_fruit = np.array([k == "Fruit" for k in sk.organs.kind])
    gm = fruits_from_skeleton(sk)
    assert gm.n_volumes == 110 * is_fruit.sum() > 0
    assert set(gm.volume_data["leaf_id"].tolist()) == set(sk.organs.leaf_id[is_fruit].tolist())
    assert gm.is_valid()
