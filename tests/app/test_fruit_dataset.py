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
    return folder, F.make_dataset(folder, count=4, seed=7, workers=2, picture=(128, 128), views=2, clean_pictures=True)


def rgb(path):
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB")).astype(int)


def test_files_labels_and_pictures(dataset):
    import pyvista as pv

    folder, summary = dataset
    assert summary["count"] == 4 and len(summary["fruit"]) == 4
    manifest = json.loads((folder / "dataset.json").read_text())
    assert manifest["fruit"] == summary["fruit"] and manifest["complete"] is True and "seconds" not in manifest
    for i in range(4):
        rec = labels(folder, i)
        assert rec["grade"]["grade"] in ("marketable", "rejected")
        assert (rec["grade"]["grade"] == "rejected") == bool(rec["grade"]["reasons"])
        assert [d["kind"] for d in rec["defects"]] == summary["fruit"][i]["defects"]
        grid = pv.read(folder / rec["files"]["grid"])
        assert grid.n_cells == rec["volumes"] and "tissue" in grid.cell_data
        for j, fact in enumerate(rec["defects"]):  # the 3D ground truth: each defect's cells carry its bit
            bits = np.asarray(grid.cell_data["defect_bits"])
            assert sorted(np.flatnonzero(bits & (1 << j)).tolist()) == sorted(fact["cells"])
        assert abs(max(np.ptp(grid.points, axis=0)) - 65.0) < 5.0  # millimetres
        assert len(rec["views"]) == 2
        for view in rec["views"]:
            img = rgb(folder / view["file_name"])
            assert img.shape == (128, 128, 3)
            assert 0.1 < view["fruit"]["pixels"] / 128**2 < 0.8  # a fruit, not a blank frame
        cut = rgb(folder / rec["files"]["cut_picture"])
        assert 0.05 < (cut != 255).any(axis=2).mean() < 0.9


def test_every_visible_defect_covers_pixels_that_differ_from_the_clean_fruit(dataset):
    """The done-test of issue 40: from the masks and the pictures on disk."""
    from ramure.app.fruit_views import rle_decode

    folder, summary = dataset
    visible = 0
    for i in range(summary["count"]):
        for view in labels(folder, i)["views"]:
            img, clean = rgb(folder / view["file_name"]), rgb(folder / view["clean_file_name"])
            differ = (np.abs(img - clean) > F.CHANGED_LEVEL).any(axis=2)
            fruit = rle_decode(view["fruit"]["segmentation"])
            assert fruit.sum() == view["fruit"]["pixels"]
            for d in view["defects"]:
                mask = rle_decode(d["segmentation"])
                assert mask.sum() == d["pixels"] and not (mask & ~fruit).any()  # on the fruit
                assert int((mask & differ).sum()) == d["changed_pixels"]
                assert d["visible"] == (d["changed_pixels"] >= F.MIN_VISIBLE_PIXELS)
                visible += d["visible"]
    assert visible >= 2
    assert summary["visible_defects"] >= 1


def test_no_two_different_labels_share_a_picture(dataset):
    import hashlib

    folder, summary = dataset
    owner = {}
    for i in range(summary["count"]):
        rec = labels(folder, i)
        for view in rec["views"]:
            digest = hashlib.sha256((folder / view["file_name"]).read_bytes()).hexdigest()
            assert digest not in owner, f"{view['file_name']} is the picture of {owner.get(digest)}"
            owner[digest] = view["file_name"]
    assert summary["duplicate_pictures"] == 0


def test_coco_files_load_and_boxes_agree_with_masks(dataset):
    from ramure.app.fruit_views import bbox, rle_decode

    folder, summary = dataset
    everything = json.loads((folder / "coco_all.json").read_text())
    parts = [json.loads((folder / f"coco_{s}.json").read_text()) for s in ("train", "val", "test")]
    assert sum(len(p["images"]) for p in parts) == len(everything["images"]) == 4 * 2
    assert sorted(a["id"] for p in parts for a in p["annotations"]) == [a["id"] for a in everything["annotations"]]
    names = {c["id"]: c["name"] for c in everything["categories"]}
    images = {im["id"]: im for im in everything["images"]}
    for a in everything["annotations"]:
        assert set(a) >= {"id", "image_id", "category_id", "segmentation", "area", "bbox", "iscrowd"} and a["iscrowd"] == 0
        mask = rle_decode(a["segmentation"])
        assert mask.shape == (images[a["image_id"]]["height"], images[a["image_id"]]["width"])
        assert a["bbox"] == bbox(mask) and a["area"] == int(mask.sum()) > 0
        assert a["category_id"] in names
    for split, part in zip(("train", "val", "test"), parts):  # a fruit's views stay in its split
        assert all(im["split"] == split for im in part["images"])
    pycocotools = pytest.importorskip("pycocotools.coco")
    coco = pycocotools.COCO(str(folder / "coco_all.json"))
    for a in everything["annotations"]:
        assert (coco.annToMask(coco.anns[a["id"]]).astype(bool) == rle_decode(a["segmentation"])).all()


def test_polygon_masks_rasterise_back_to_the_rle_masks(dataset):
    """``--coco-masks polygon`` (ultralytics, detectron2's default): pycocotools draws the
    polygons back onto the exact masks (holes aside) with the same boxes."""
    from ramure.app.fruit_coco import coco_records
    from ramure.app.fruit_views import bbox, polygons, rle_decode

    ring = np.zeros((12, 12), bool)
    ring[2:9, 2:9], ring[4:6, 4:6] = True, False
    assert polygons(ring) == [[2.0, 2.0, 9.0, 2.0, 9.0, 9.0, 2.0, 9.0]]  # the outer boundary, no hole
    mask_util = pytest.importorskip("pycocotools.mask")
    folder, _ = dataset
    record = labels(folder, 1)
    _, exact = coco_records(record, 1, 1)
    _, drawn = coco_records(record, 1, 1, masks="polygon")
    assert len(exact) == len(drawn) >= 2
    for a, b in zip(exact, drawn):
        mask = rle_decode(a["segmentation"])
        h, w = mask.shape
        assert isinstance(b["segmentation"], list) and all(len(p) >= 6 and len(p) % 2 == 0 for p in b["segmentation"])
        back = mask_util.decode(mask_util.merge(mask_util.frPyObjects(b["segmentation"], h, w))).astype(bool)
        assert bbox(back) == a["bbox"]
        assert (back & mask).sum() / (back | mask).sum() > 0.97


def test_cameras_project_the_mesh_onto_its_mask(dataset):
    import pyvista as pv

    from ramure.app.fruit_views import project

    folder, _ = dataset
    rec = labels(folder, 1)
    points = pv.read(folder / rec["files"]["grid"]).extract_surface(algorithm="dataset_surface").points
    for view in rec["views"]:
        uv = project(points, view["camera"])
        x, y, w, h = view["fruit"]["bbox"]
        assert abs(uv[:, 0].min() - x) < 1.5 and abs(uv[:, 0].max() - (x + w - 1)) < 1.5
        assert abs(uv[:, 1].min() - y) < 1.5 and abs(uv[:, 1].max() - (y + h - 1)) < 1.5


def test_deterministic_and_independent_per_fruit(dataset, tmp_path):
    folder, _ = dataset
    F.make_dataset(tmp_path, count=2, seed=7, workers=1, picture=(128, 128), views=2, clean_pictures=True)
    for i in range(2):
        assert (tmp_path / f"fruit_{i:04d}.json").read_bytes() == (folder / f"fruit_{i:04d}.json").read_bytes()
    other = F.random_recipe(F.fruit_rng(6, 0))
    assert other != F.random_recipe(F.fruit_rng(5, 0))


def test_random_recipes_balance_the_defect_kinds():
    from collections import Counter

    kinds, cracks, shapes, clean = Counter(), Counter(), 0, 0
    for i in range(400):
        recipe = F.random_recipe(F.fruit_rng(0, i))
        kinds.update(k for k, _ in recipe["defects"])
        cracks.update(o["kind"] for k, o in recipe["defects"] if k == "crack")
        shapes += recipe["malform"] is not None
        clean += not recipe["defects"]
        order = [F.APPLY_ORDER.index(k) for k, _ in recipe["defects"]]
        assert order == sorted(order)
    assert set(kinds) == set(F.DEFECT_KINDS) and max(kinds.values()) < 1.35 * min(kinds.values())
    assert set(cracks) == {"longitudinal", "transverse", "concentric"}
    assert 80 < shapes < 160 and 50 < clean < 120


def test_clean_fruit_vary():
    """``--defects none``: no defect, yet no two fruit nor views alike."""
    recipes = [F.random_recipe(F.fruit_rng(0, i)) for i in range(20)]
    assert len({r["variation"] for r in recipes}) > 15
    built = [F.build_one({**r, "malform": None, "defects": []})[1] for r in recipes[:3]]
    points = [np.round(gm.points, 6).tobytes() for gm in built]
    assert len(set(points)) == 3  # three different shapes


def test_a_concentric_crack_rings_the_stem_scar():
    from ramure.gmap.organs.fruit import build_fruit

    gm = build_fruit("round_tomato", volume_levels=1)
    opts = F._fit(gm, "crack", {"kind": "concentric", "sector": 3, "rings": (2, 4)})
    rings = int(gm.volume_data["ring"].max()) + 1
    assert opts["rings"][0] == opts["rings"][1] >= rings - 4  # at the stem end (the dimple's rings)


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
    assert names == [
        "DATASET_CARD.md",
        "coco_all.json",
        "coco_test.json",
        "coco_train.json",
        "coco_val.json",
        "dataset.json",
        "fruit_0000.json",
        "fruit_0000.vtu",
        "fruit_0000_cut.png",
        "fruit_0000_v0.png",
        "fruit_0000_v1.png",
        "fruit_0000_v2.png",
        "fruit_0000_v3.png",
        "notes.txt",
    ]
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


def test_a_dask_local_cluster_makes_the_same_dataset(tmp_path):
    """Issue 40, section 5: ``--scheduler local``; the files come back to this process and are
    byte-identical to the pool's (labels, COCO files, card, manifest, pictures, grids)."""
    pytest.importorskip("dask.distributed")
    a, b = tmp_path / "dask", tmp_path / "pool"
    F.make_dataset(a, count=3, seed=4, views=1, picture=(64, 64), workers=2, scheduler="local")
    F.make_dataset(b, count=3, seed=4, views=1, picture=(64, 64), workers=1)
    names = sorted(p.name for p in b.iterdir())
    assert names == sorted(p.name for p in a.iterdir())
    for name in names:
        assert (a / name).read_bytes() == (b / name).read_bytes(), name


def test_cli_batch_views_and_stage(capsys, tmp_path):
    from ramure.app.cli import main

    assert main(["fruit", "batch", "--views", "0", "-o", str(tmp_path / "a")]) == 2
    assert "--views" in capsys.readouterr().err
    out = tmp_path / "b"
    assert (
        main(
            [
                "fruit",
                "batch",
                "--count",
                "1",
                "--views",
                "2",
                "--stage",
                "conveyor",
                "--size",
                "64x64",
                "--workers",
                "1",
                "-o",
                str(out),
                "--json",
            ]
        )
        == 0
    )
    summary = json.loads(capsys.readouterr().out)
    assert summary["views"] == 2 and summary["stage"] == "conveyor" and summary["splits"]
    record = labels(out, 0)
    assert [v["stage"] for v in record["views"]] == ["conveyor", "conveyor"]
    assert (out / "DATASET_CARD.md").read_text().count("What is not simulated") == 1


def test_the_camera_never_refits_a_shrunk_fruit():
    """Issue 40: shrinkage was undone by the renderer's framing.  The same fruit, views and
    camera, shrunk by 10 % of every edge twice (0.81 linear), covers about 0.66 of the pixels."""
    recipe = {"preset": "round_tomato", "malform": None, "variation": 0.0, "defects": [], "seed": 11}
    shrunk = {**recipe, "defects": [("shrink", {"rate": 0.1, "steps": 2})]}
    views = []
    for r in (recipe, shrunk):
        files = F.make_fruit(3, r, seed=2, picture=(96, 96), views=2)
        views.append(json.loads(files["fruit_0003.json"])["views"])
    for clean, small in zip(*views):
        assert clean["camera"] == small["camera"]
        assert 0.55 < small["fruit"]["pixels"] / clean["fruit"]["pixels"] < 0.75


def test_an_unreachable_scheduler_is_refused_before_anything_is_written(tmp_path, monkeypatch):
    pytest.importorskip("dask.distributed")
    monkeypatch.setattr(F, "DASK_CONNECT_SECONDS", 1.0)
    with pytest.raises(F.RamureError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:9"):
        F.make_dataset(tmp_path / "ds", count=1, scheduler="tcp://127.0.0.1:9")
    assert not (tmp_path / "ds").exists()


def test_a_defect_the_fruit_refuses_is_dropped_and_said():
    """One rare draw the fruit refuses must not stop a batch of thousands: it is dropped,
    with the reason, and the other defects stay."""
    recipe = {
        "preset": "round_tomato",
        "malform": None,
        "variation": 0.0,
        "defects": [("rot", {"rate": 0.03}), ("hail", {"count": 10**6})],
        "seed": 3,
    }
    _, _, record = F.build_one(recipe)
    assert [d["kind"] for d in record["defects"]] == ["rot"]
    assert record["dropped_defects"] == [{"kind": "hail", "reason": record["dropped_defects"][0]["reason"]}]
    assert "hail count" in record["dropped_defects"][0]["reason"]
