"""The G-map guide (``docs/gmap.md``) runs: its examples, its pictures and the script that draws them."""

from __future__ import annotations

import doctest
import pathlib
import re
import sys

import numpy as np
import pytest

from ramure.gmap import GMap3

ROOT = pathlib.Path(__file__).resolve().parents[2]
GUIDE = ROOT / "docs" / "gmap.md"


def test_the_guide_examples_run(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = doctest.testfile(str(GUIDE), module_relative=False, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0
    assert result.attempted >= 30  # darts, orbits, sewing and attributes, not one line


def test_the_guide_pictures_are_there_and_not_blank():
    Image = pytest.importorskip("PIL.Image")
    pictures = re.findall(r"!\[[^\]]*\]\((images/[^)]+\.png)\)", GUIDE.read_text(encoding="utf-8"))
    assert sorted(pictures) == ["images/gmap_cube.png", "images/gmap_face.png", "images/gmap_sew.png"]
    for picture in pictures:
        path = ROOT / "docs" / picture
        assert path.stat().st_size < 80_000  # small, committed
        grey = np.asarray(Image.open(path).convert("L"), float)
        assert (grey < 128).mean() > 0.005, f"{picture} is blank"


@pytest.fixture(scope="module")
def pictures():
    sys.path.insert(0, str(ROOT / "docs" / "images"))
    try:
        import make_gmap_pictures
    finally:
        sys.path.pop(0)
    return make_gmap_pictures


def test_each_link_is_drawn_once(pictures):
    gm = GMap3()
    gm.add_prisms(4)
    darts = np.arange(gm.n_darts)
    assert [len(pictures.links(gm, i, darts)) for i in range(4)] == [24, 24, 24, 0]  # alpha3 all free
    assert len(pictures.links(gm, 0, gm.orbit(0, "01"))) == 4  # a square's four edges


def test_the_darts_of_a_face_stand_apart(pictures):
    gm = GMap3()
    gm.add_prisms(4)
    seg = pictures.dart_segments(gm)[gm.orbit(0, "01")]
    ends = seg.reshape(-1, 3)
    gaps = np.linalg.norm(ends[:, None] - ends[None], axis=2)[~np.eye(len(ends), dtype=bool)]
    assert gaps.min() > 0.05  # no two arrow ends of one face meet (the cube's side is 1)
    heads_to_middle = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1)
    assert np.allclose(heads_to_middle, 0.24)  # 0.42 .. 0.9 of a half side of 1
