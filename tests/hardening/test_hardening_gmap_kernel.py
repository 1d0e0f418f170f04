"""The 3G-map kernel checks ids at the door (issue 37, item 12): a refused operation leaves the
map byte-identical, an accepted one leaves it valid.  A fixed-seed run of random operations,
with ids that are often wrong, checks both after every step."""

from __future__ import annotations

import numpy as np
import pytest

from ramure.errors import RamureError
from ramure.gmap import GMap3


def state(gm: GMap3) -> list[bytes]:
    """Every array of the map, as bytes: what 'unchanged' means."""
    arrays = [np.asarray(gm.alpha)]
    arrays += [np.asarray(v) for _, v in sorted(gm.dart_data.items())]
    arrays += [np.asarray(v) for _, v in sorted(gm.volume_data.items())]
    return [a.tobytes() for a in arrays] + [repr([a.shape for a in arrays]).encode()]


def refused_unchanged(gm, call):
    before = state(gm)
    with pytest.raises(RamureError):
        call()
    assert state(gm) == before


@pytest.fixture
def cube():
    gm = GMap3()
    gm.add_prisms(4)
    return gm


def test_add_prisms_of_an_order_past_int16_is_refused_before_any_dart(cube):
    refused_unchanged(cube, lambda: cube.add_prisms(32768))
    assert cube.n_darts == 48


def test_split_faces_with_two_darts_of_one_face_is_refused(cube):
    refused_unchanged(cube, lambda: cube.split_faces([0, 3], [2, 2]))
    assert cube.is_valid()


def test_split_faces_with_both_sides_of_a_sewn_face_is_refused():
    gm = GMap3()
    first = gm.add_prisms(4, 2, origins=[[0, 0, 0], [0, 0, 1]])
    top = gm.prism_face(first[0], 4, "E")
    bottom = gm.prism_face(first[1], 4, "O")
    gm.sew3([top], [bottom])
    sewn = int(gm.alpha[3][top])
    assert sewn != top
    refused_unchanged(gm, lambda: gm.split_faces([top, sewn], [2, 2]))
    assert gm.is_valid()


@pytest.mark.parametrize(
    "call",
    [
        lambda gm: gm.unsew3([-1]),
        lambda gm: gm.unsew3([48]),
        lambda gm: gm.split_face(-3, 4),
        lambda gm: gm.split_face(0, 10**9),
        lambda gm: gm.split_faces([-1], [2]),
        lambda gm: gm.split_faces([0], [2, 2]),
    ],
)
def test_dart_ids_are_checked_at_the_door(cube, call):
    refused_unchanged(cube, lambda: call(cube))


def random_operation(gm, rng):
    """One operation with arguments that are right about half of the time."""
    n = gm.n_darts

    def dart():
        return int(rng.integers(-2, n + 2)) if rng.random() < 0.2 else int(rng.integers(0, max(n, 1)))

    kind = rng.integers(6)
    if kind == 0:
        order = int(rng.choice([2, 3, 4, 5, 40000]))
        return lambda: gm.add_prisms(order, int(rng.integers(0, 3)))
    if kind == 1:
        return lambda: gm.split_edge([dart()], float(rng.uniform(0.1, 0.9)))
    if kind == 2:
        return lambda: gm.split_face(dart(), dart())
    if kind == 3:
        darts = [dart() for _ in range(int(rng.integers(1, 3)))]
        return lambda: gm.split_faces(darts, [int(rng.integers(1, 4)) for _ in darts])
    if kind == 4:
        return lambda: gm.sew3([dart()], [dart()])
    return lambda: gm.unsew3([dart()])


def test_random_operations_keep_the_map_valid_or_unchanged():
    rng = np.random.default_rng(12)
    gm = GMap3()
    gm.add_prisms(4, 2)
    accepted = refused = 0
    for _ in range(300):
        call = random_operation(gm, rng)
        before = state(gm)
        try:
            call()
        except RamureError:
            refused += 1
            assert state(gm) == before
            continue
        accepted += 1
        assert gm.is_valid(), gm.validity_problems()[:3]
        if gm.n_darts > 20_000:
            break
    assert accepted > 30 and refused > 30  # both paths are exercised
