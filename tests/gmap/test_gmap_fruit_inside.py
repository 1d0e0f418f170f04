"""Species that look like themselves inside (issue 40, item 1): an apple's core and pips in
the middle of its height, a drupe's stone of the right length with its kernel inside."""

import numpy as np
import pytest

from ramure.gmap.kernel.errors import ValueRefused
from ramure.gmap.organs.fruit import build_fruit
from ramure.gmap.organs.species import STONE_TISSUES
from ramure.gmap.organs.tissue import CODES, CORE_TISSUES, axial_coordinates


@pytest.fixture(scope="module")
def fruits():
    return {name: build_fruit(name, volume_levels=2) for name in ("apple", "pear", "plum", "cherry")}


def _span(gm, names):
    """Extent along the fruit's axis (z) of the cells of ``names`` over the fruit's, and that extent."""
    codes = [CODES[n] for n in names]
    z = gm.points[:, 2]
    cells = np.isin(gm.volume_data["tissue"][gm.dart_volume], codes)
    assert cells.any(), names
    return float(np.ptp(z[cells]) / np.ptp(z)), (float(z[cells].min()), float(z[cells].max()))


def test_apple_core_is_the_middle_of_its_height_with_pips_in_it(fruits):
    gm = fruits["apple"]
    share, (low, high) = _span(gm, CORE_TISSUES + ("seed",))
    assert 0.3 <= share <= 0.55  # a third to a half of the height, not a column
    z = gm.points[:, 2]
    assert low > z.min() + 0.15 * np.ptp(z) and high < z.max() - 0.15 * np.ptp(z)  # flesh above and below
    tissue = gm.volume_data["tissue"]
    pips = tissue == CODES["seed"]
    assert pips.sum() >= 10  # whole-cell pips: two per carpel, several cells each
    pip_share, (pip_low, pip_high) = _span(gm, ("seed",))
    assert low < pip_low and pip_high < high and pip_share < share  # inside the core
    # two pips per carpel: each carpel's pip cells fall into two groups along the axis
    s, _, theta = axial_coordinates(gm)
    carpel = (np.mod(theta / (2 * np.pi), 1.0) * 5).astype(int)  # septum to septum
    assert set(carpel[pips]) == set(range(5))
    for c in range(5):
        steps = np.diff(np.unique(np.round(s[pips & (carpel == c)], 6)))
        assert (steps > 1.5 * steps.min()).sum() == 1, (c, steps)  # one empty level between the two


def test_pear_core_sits_in_the_wide_blossom_half(fruits):
    gm = fruits["pear"]
    share, (low, high) = _span(gm, CORE_TISSUES + ("seed",))
    z = gm.points[:, 2]
    assert share <= 0.5 and high < z.min() + 0.6 * np.ptp(z)


@pytest.mark.parametrize("name, lo, hi", [("plum", 0.55, 0.65), ("cherry", 0.45, 0.55)])
def test_drupe_stone_length_over_fruit_length(fruits, name, lo, hi):
    share, _ = _span(fruits[name], STONE_TISSUES + ("seed",))
    assert lo <= share <= hi, share


@pytest.mark.parametrize("name", ["plum", "cherry"])
def test_drupe_kernel_lies_inside_its_stone(fruits, name):
    gm = fruits[name]
    tissue = gm.volume_data["tissue"]
    kernel = tissue == CODES["seed"]
    assert kernel.sum() > 20
    vol = gm.dart_volume
    a3 = gm.alpha[3]
    darts = np.flatnonzero(kernel[vol])
    assert (a3[darts] != darts).all()  # no kernel face on the skin
    around = set(tissue[vol[a3[darts]]].tolist())
    assert around <= {CODES[n] for n in STONE_TISSUES + ("seed",)}, around  # never touches the flesh
    kernel_share, _ = _span(gm, ("seed",))
    stone_share, _ = _span(gm, STONE_TISSUES + ("seed",))
    assert 0.3 * stone_share < kernel_share < stone_share
    coarse = build_fruit(name, volume_levels=1)  # no locules, no shell: no kernel on the flesh
    assert coarse.is_valid() and not (coarse.volume_data["tissue"] == CODES["seed"]).any()


@pytest.mark.parametrize("name", ["apple", "plum", "cherry"])
def test_inside_maps_stay_valid_and_deterministic(fruits, name):
    gm = fruits[name]
    again = build_fruit(name, volume_levels=2)
    assert gm.is_valid() and gm.euler_characteristic() == again.euler_characteristic()
    assert np.array_equal(gm.points, again.points)
    assert np.array_equal(gm.volume_data["tissue"], again.volume_data["tissue"])


def test_core_band_parameters_are_checked():
    with pytest.raises(ValueRefused, match="core_low < core_high"):
        build_fruit("apple", volume_levels=1, core_low=0.6, core_high=0.4)
    with pytest.raises(ValueRefused, match="kernel"):
        build_fruit("plum", volume_levels=1, kernel=1.5)
    with pytest.raises(ValueRefused, match="pips"):
        build_fruit("apple", volume_levels=1, pips=-1)


def test_tomato_default_is_unchanged_by_the_core_band():
    """The defaults (whole axis, no kernel, carved seeds) leave a tomato as it was built."""
    a = build_fruit("round_tomato", volume_levels=2, seed=4)
    b = build_fruit("round_tomato", volume_levels=2, seed=4, core_low=0.0, core_high=1.0, kernel=0.0, pips=0)
    assert np.array_equal(a.points, b.points) and (a.volume_data["tissue"] == CODES["seed"]).sum() == 120
