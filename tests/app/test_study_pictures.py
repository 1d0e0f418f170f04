"""Issue 38 §2: a study's pictures are rendered once, at creation, on one scale per set."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from ramure.app.cli import main
from ramure.app.stimuli import render_stimuli
from ramure.studies import Study, lattice_picks
from ramure.studies.design import StudyConfig


def honda_picks():
    """27 Honda trees whose r1 (the trunk's contraction, so the height) varies by PC1 level."""
    picks = []
    for p in lattice_picks(seed=3):
        c = p.params["constants"]
        constants = {"r1": round(0.6 + 0.35 * (p.id - 1) / 26, 4), "a2": c["a0"] * 60 / 45, "wr": c["wr"]}
        picks.append({"id": p.id, "variant": p.variant, "pca": list(p.pca), "params": {"rule": 1, "constants": constants}})
    return picks


def plant_rows(path):
    """(top row, bottom row) of the non-white pixels of a picture, the scale bar left out."""
    rgb = np.asarray(Image.open(path).convert("RGB")).astype(int)
    ink = (rgb.sum(axis=2) < 700) & ~(rgb.max(axis=2) < 40)  # not white, not the black bar
    rows = np.flatnonzero(ink.any(axis=1))
    return rows[0], rows[-1]


def bar_pixels(path):
    rgb = np.asarray(Image.open(path).convert("RGB")).astype(int)
    black = rgb.max(axis=2) < 40
    columns = np.flatnonzero(black.sum(axis=0) >= 5)  # the bar: a black column, not a dark twig pixel
    return columns.tolist(), int(black[:, columns].any(axis=1).sum())


@pytest.mark.parametrize("framing", ["shared", "own"])
def test_pictures_show_size_on_one_scale_per_set(tmp_path, framing):
    path = tmp_path / "study" / "study.db"
    with Study.create(path, grammars={"honda_sympodial": honda_picks()}, config=StudyConfig(framing=framing)) as study:
        assert render_stimuli(study, size=128) == {"honda_sympodial": "rendered"}
        picks = study.picks("honda_sympodial")
        stored = [r[0] for r in study.conn.execute("SELECT image FROM picks ORDER BY pick_id")]
        record = study.setting("stimuli")
    assert stored[0] == "stimuli/01-honda_sympodial/pick_01.png" and all(pathlib_ok(p.image) for p in picks)
    assert record["framing"] == framing and record["grammars"]["honda_sympodial"]["rendered"]
    heights = {p.id: np.subtract(*plant_rows(p.image)[::-1]) for p in picks}
    short, tall = heights[1], heights[27]  # r1 0.6 and 0.95: the tall tree is about twice as tall
    if framing == "shared":
        assert tall > 1.5 * short
        assert record["grammars"]["honda_sympodial"]["bar"] > 0
        bars = {tuple(bar_pixels(p.image)[0]) for p in picks}
        lengths = {bar_pixels(p.image)[1] for p in picks}
        assert len(bars) == 1 and len(lengths) == 1 and next(iter(lengths)) > 5  # the same bar in every picture
    else:
        assert tall < 1.2 * short  # framed on its own bounds: every tree fills its picture


def pathlib_ok(image):
    import pathlib

    return image is not None and pathlib.Path(image).is_file() and "stimuli" in image


def test_create_renders_once_and_a_copied_folder_still_shows_them(tmp_path, capsys):
    explore = tmp_path / "explore" / "tree"
    explore.mkdir(parents=True)
    (explore / "picks.json").write_text(json.dumps(honda_picks()))
    (explore / "pca.json").write_text(json.dumps({"grammar": "honda_sympodial", "n": 4, "seed": 0}))
    db = tmp_path / "study" / "study.db"
    assert main(["study", "create", str(db), "--grammar", f"tree={explore}", "--picture-size", "64"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["pictures"] == {"tree": "rendered"} and out["framing"] == "shared"
    files = sorted((tmp_path / "study" / "stimuli" / "01-tree").glob("*.png"))
    assert len(files) == 27 and Image.open(files[0]).size == (64, 64)
    import shutil

    shutil.copytree(tmp_path / "study", tmp_path / "copy")
    shutil.rmtree(tmp_path / "study")
    with Study.open(tmp_path / "copy" / "study.db", readonly=True) as study:
        assert all(p.image and p.image.startswith(str(tmp_path / "copy")) for p in study.picks("tree"))
    assert main(["study", "create", str(tmp_path / "x.db"), "--grammar", f"tree={explore}", "--picture-size", "9"]) == 2
