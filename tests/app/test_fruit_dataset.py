"""ramure fruit batch: a labelled dataset of defective fruit (issue 17)."""

import json

import numpy as np
import pytest

from ramure.app import fruit_dataset as F


def labels(folder, i):
    rec = json.loads((folder / f"fruit_{i:04d}.json").read_text())
    assert "seconds" not in rec  # no timings: one seed gives byte-identical labels
    return rec


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ds")
    return folder, F.make_dataset(folder, count=3, seed=5, workers=2, picture=(160, 160))


def test_files_labels_and_pictures(dataset):
    import pyvista as pv
    from PIL import Image

    folder, summary = dataset
    assert summary["count"] == 3 and len(summary["fruit"]) == 3
    manifest = json.loads((folder / "dataset.json").read_text())
    assert manifest["fruit"] == summary["fruit"] and manifest["complete"] is True and "seconds" not in manifest
    for i in range(3):
        rec = labels(folder, i)
        assert rec["grade"]["grade"] in ("marketable", "rejected")
        assert (rec["grade"]["grade"] == "rejected") == bool(rec["grade"]["reasons"])
        assert [d["kind"] for d in rec["defects"]] == summary["fruit"][i]["defects"]
        grid = pv.read(folder / rec["files"]["grid"])
        assert grid.n_cells == rec["volumes"] and "tissue" in grid.cell_data
        whole = np.asarray(Image.open(folder / rec["files"]["picture"]).convert("RGB")).astype(int)
        cut = np.asarray(Image.open(folder / rec["files"]["cut_picture"]).convert("RGB")).astype(int)
        for img in (whole, cut):
            assert img.shape == (160, 160, 3)
            fruit = (img != 255).any(axis=2)
            assert 0.1 < fruit.mean() < 0.9  # a fruit, not a blank frame

        def beige(img):
            r, g, b = img[..., 0], img[..., 1], img[..., 2]
            return int(((r > 120) & (g > 90) & (g < 230) & (b > 60) & (b < 200)).sum())

        assert beige(cut) > 30 and beige(cut) > 3 * beige(whole), "the cut shows the columella, the skin not"


def test_deterministic_and_independent_per_fruit(dataset, tmp_path):
    folder, _ = dataset
    F.make_dataset(tmp_path, count=2, seed=5, workers=1, picture=(160, 160))  # fewer fruit, one worker
    for i in range(2):
        assert labels(tmp_path, i) == labels(folder, i)
    other = F.random_recipe(F.fruit_rng(6, 0))
    assert other != F.random_recipe(F.fruit_rng(5, 0))


def test_random_recipes_cover_every_defect():
    kinds, shapes, clean = set(), 0, 0
    for i in range(60):
        recipe = F.random_recipe(F.fruit_rng(0, i))
        kinds.update(k for k, _ in recipe["defects"])
        shapes += recipe["malform"] is not None
        clean += not recipe["defects"] and recipe["malform"] is None
    assert kinds == {"crack", "hail", "rot", "shrink"}
    assert 5 < shapes < 40 and clean >= 3


def test_cli_batch_refusals(capsys, tmp_path):
    from ramure.app.cli import main

    (tmp_path / "file").write_text("x")
    for argv, msg in (
        (["--count", "0", "-o", str(tmp_path / "a")], "--count"),
        (["--count", "2", "-o", str(tmp_path / "file")], "not a folder"),
        (["--size-mm", "nan", "-o", str(tmp_path / "b")], "--size-mm"),
    ):
        assert main(["fruit", "batch", *argv]) == 2
        err = capsys.readouterr().err
        assert msg in err and "Traceback" not in err
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_an_in_process_dataset_leaves_no_plotter_open(tmp_path):
    F.make_dataset(tmp_path, count=1, seed=1, workers=1, picture=(64, 64))
    assert "plotter" not in F._STATE  # a live GL context would break later Qt views


def test_a_folder_that_is_not_empty_is_refused_unless_told(tmp_path):
    folder = tmp_path / "ds"
    folder.mkdir()
    (folder / "notes.txt").write_text("mine")
    with pytest.raises(F.ValueRefused, match="is not empty: --resume finishes"):
        F.make_dataset(folder, count=1, workers=1, picture=(32, 32))
    with pytest.raises(F.ValueRefused, match="no dataset to finish"):
        F.make_dataset(folder, count=1, workers=1, picture=(32, 32), resume=True)
    (folder / "fruit_0007.json").write_text("stale")  # an earlier, larger dataset's fruit
    (folder / "dataset.json").write_text("stale")
    F.make_dataset(folder, count=1, workers=1, picture=(32, 32), overwrite=True)
    names = sorted(p.name for p in folder.iterdir())
    assert names == ["dataset.json", "fruit_0000.json", "fruit_0000.png", "fruit_0000.vtu", "fruit_0000_cut.png", "notes.txt"]
    with pytest.raises(F.ValueRefused, match=r"other settings \(seed\)"):
        F.make_dataset(folder, count=1, seed=9, workers=1, picture=(32, 32), resume=True)


def test_killed_batch_stops_its_workers_and_resumes_to_the_same_dataset(tmp_path):
    """Issue 37, item 11: kill -9 the command; its workers end at once and write nothing more;
    --resume then finishes the dataset, equal to one made in a single run."""
    import os
    import signal
    import subprocess
    import sys
    import time

    folder = tmp_path / "ds"
    code = (
        "from ramure.app.fruit_dataset import make_dataset; "
        f"make_dataset({str(folder)!r}, count=5, seed=3, workers=2, picture=(48, 48))"
    )
    proc = subprocess.Popen([sys.executable, "-c", code])
    deadline = time.monotonic() + 120
    while not list(folder.glob("fruit_*.json")) and time.monotonic() < deadline:
        time.sleep(0.05)
    workers = subprocess.run(["pgrep", "-P", str(proc.pid)], capture_output=True, text=True).stdout.split()
    assert workers, "the batch had started its workers"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    time.sleep(1.0)
    alive = [w for w in workers if os.path.exists(f"/proc/{w}") and "Z" not in open(f"/proc/{w}/stat").read().split()[2]]
    assert not alive, "workers outlived the command"
    manifest = json.loads((folder / "dataset.json").read_text())
    assert manifest["complete"] is False  # the manifest says the dataset is unfinished
    made = len(list(folder.glob("fruit_*.json")))
    assert 1 <= made < 5
    summary = F.make_dataset(folder, count=5, seed=3, workers=1, picture=(48, 48), resume=True)
    assert summary["complete"] and [r["index"] for r in summary["fruit"]] == list(range(5))
    fresh = F.make_dataset(tmp_path / "fresh", count=5, seed=3, workers=1, picture=(48, 48))
    assert (folder / "dataset.json").read_bytes() == (tmp_path / "fresh" / "dataset.json").read_bytes()
    assert summary["fruit"] == fresh["fruit"]
