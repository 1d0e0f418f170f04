"""COCO files and the dataset card of a fruit dataset (``ramure fruit batch``).

:func:`write_coco_and_card` reads every fruit's labels and writes, next to them:

* ``coco_train.json``, ``coco_val.json``, ``coco_test.json`` and ``coco_all.json``: COCO
  instance-segmentation files (``images``, ``annotations``, ``categories``).  One image per
  view; one ``fruit`` annotation per image (the whole fruit, its grade in
  ``attributes``) and one annotation per defect *visible* in that view (its mask differs
  from the fruit without its located defects seen the same way, see
  :mod:`ramure.app.fruit_dataset`).  Masks are exact, as uncompressed RLE
  (``{"size": [h, w], "counts": [...]}``, ``iscrowd`` 0), read by pycocotools,
  torchvision's ``CocoDetection`` and detectron2 (``INPUT.MASK_FORMAT bitmask``).  Extra
  keys (``camera``, ``attributes``...) are ignored by those readers.
  Ids are given in fruit and view order, so the files are byte-identical for one seed.
* ``DATASET_CARD.md``: what the data are, what is simulated and what is not, the layout,
  conventions and counts.
"""

from __future__ import annotations

import hashlib
import json
import pathlib
from collections.abc import Mapping, Sequence
from typing import Any

import ramure.io as atomic

CARD = "DATASET_CARD.md"
#: COCO categories (``fruit``: the whole fruit, carrying its grade; one per defect kind with a place).
CATEGORIES = (
    {"id": 1, "name": "fruit"},
    {"id": 2, "name": "crack"},
    {"id": 3, "name": "hail"},
    {"id": 4, "name": "rot"},
    {"id": 5, "name": "excrescence"},
)
CATEGORY_ID = {c["name"]: c["id"] for c in CATEGORIES}
SPLITS = ("train", "val", "test")


def _labels(folder: pathlib.Path, row: Mapping[str, Any]) -> dict:
    return json.loads(atomic.read_regular(folder / row["labels"], 256 * 2**20, "fruit labels"))


MASK_FORMATS = ("rle", "polygon")


def coco_records(
    record: Mapping[str, Any], image_id: int, annotation_id: int, masks: str = "rle"
) -> tuple[list[dict], list[dict]]:
    """COCO images and annotations of one fruit's labels, ids from ``image_id`` and ``annotation_id``.

    ``masks``: ``"rle"`` (exact) or ``"polygon"`` (outer boundaries traced along pixel
    edges, :func:`ramure.app.fruit_views.polygons`: no holes; what ultralytics'
    ``convert_coco`` and detectron2's default mask format read).
    """
    from ramure.app.fruit_views import polygons, rle_decode

    def segmentation(rle):
        return rle if masks == "rle" else polygons(rle_decode(rle))

    images, annotations = [], []
    grade = record["grade"]
    shrink = [d for d in record["defects"] if d["kind"] == "shrink"]
    for view in record["views"]:
        cam = view["camera"]
        images.append(
            {
                "id": image_id,
                "file_name": view["file_name"],
                "width": cam["width"],
                "height": cam["height"],
                "fruit": record["index"],
                "view": view["view"],
                "split": record["split"],
                "stage": view["stage"],
                "camera": cam,
            }
        )
        fruit = view["fruit"]
        annotations.append(
            {
                "id": annotation_id,
                "image_id": image_id,
                "category_id": CATEGORY_ID["fruit"],
                "segmentation": segmentation(fruit["segmentation"]),
                "area": fruit["pixels"],
                "bbox": fruit["bbox"],
                "iscrowd": 0,
                "attributes": {
                    "grade": grade.get("grade"),
                    "reasons": grade.get("reasons", []),
                    "preset": record["preset"],
                    "shrink_rate": sum(d.get("rate", 0.0) for d in shrink),
                    "volume_lost_fraction": record["volume_lost_fraction"],
                },
            }
        )
        annotation_id += 1
        for d in view["defects"]:
            if not d["visible"]:
                continue
            fact = record["defects"][d["defect"]]
            attributes = {
                "defect": d["defect"],
                "changed_pixels": d["changed_pixels"],
                "seen_area_fraction": d["seen_area_fraction"],
            }
            if fact["kind"] == "crack":
                attributes.update(
                    crack_kind=fact.get("crack_kind"), healed=fact.get("healed_layers", 0) >= fact.get("depth_layers", 1)
                )
            annotations.append(
                {
                    "id": annotation_id,
                    "image_id": image_id,
                    "category_id": CATEGORY_ID[d["kind"]],
                    "segmentation": segmentation(d["segmentation"]),
                    "area": d["pixels"],
                    "bbox": d["bbox"],
                    "iscrowd": 0,
                    "attributes": attributes,
                }
            )
            annotation_id += 1
        image_id += 1
    return images, annotations


def write_coco_and_card(folder: pathlib.Path, settings: Mapping[str, Any], rows: Sequence[Mapping[str, Any]]) -> dict:
    """Write the COCO files and the card (see the module docstring); returns the manifest's extra
    facts: images and annotations per split, labelled and visible defects, duplicate pictures."""
    per_split: dict[str, dict[str, list]] = {s: {"images": [], "annotations": []} for s in SPLITS}
    image_id, annotation_id = 1, 1
    labelled = visible = 0
    kinds: dict[str, list[int]] = {}
    pictures: dict[str, set[str]] = {}
    for row in rows:
        record = _labels(folder, row)
        images, annotations = coco_records(record, image_id, annotation_id, settings.get("coco_masks", "rle"))
        image_id += len(images)
        annotation_id += len(annotations)
        per_split[record["split"]]["images"] += images
        per_split[record["split"]]["annotations"] += annotations
        seen = {d["defect"] for v in record["views"] for d in v["defects"] if d["visible"]}
        for i, fact in enumerate(record["defects"]):
            count = kinds.setdefault(fact["kind"], [0, 0])
            count[0] += 1
            count[1] += i in seen
        labelled += len([d for d in record["defects"] if d["kind"] != "shrink"])
        visible += len(seen)
        for view in record["views"]:
            digest = hashlib.sha256((folder / view["file_name"]).read_bytes()).hexdigest()
            label = json.dumps(
                [record["grade"], [d["defect"] for d in view["defects"] if d["visible"]], record["defects"]], sort_keys=True
            )
            pictures.setdefault(digest, set()).add(label)
    info = {"description": "Ramure synthetic defective fruit (see DATASET_CARD.md)", "version": "2", "seed": settings["seed"]}
    everything: dict[str, list] = {"images": [], "annotations": []}
    for split in SPLITS:
        part = per_split[split]
        everything["images"] += part["images"]
        everything["annotations"] += part["annotations"]
        _write_coco(folder / f"coco_{split}.json", info, part)
    everything["images"].sort(key=lambda im: im["id"])
    everything["annotations"].sort(key=lambda a: a["id"])
    _write_coco(folder / "coco_all.json", info, everything)
    extra = {
        "splits": {s: {"images": len(per_split[s]["images"]), "annotations": len(per_split[s]["annotations"])} for s in SPLITS},
        "categories": list(CATEGORIES),
        "defects_by_kind": {k: {"labelled": v[0], "visible": v[1]} for k, v in sorted(kinds.items())},
        "located_defects": labelled,
        "visible_defects": visible,
        "duplicate_pictures": sum(len(v) > 1 for v in pictures.values()),
    }
    atomic.write_text(folder / CARD, card_text(settings, extra))
    return extra


def _write_coco(path: pathlib.Path, info: Mapping[str, Any], part: Mapping[str, list]) -> None:
    data = {
        "info": dict(info),
        "licenses": [],
        "images": part["images"],
        "annotations": part["annotations"],
        "categories": list(CATEGORIES),
    }
    atomic.write_text(path, json.dumps(data, separators=(",", ":")))


def card_text(settings: Mapping[str, Any], extra: Mapping[str, Any]) -> str:
    """The dataset card (Markdown)."""
    s = settings
    by_kind = "\n".join(f"| {k} | {v['labelled']} | {v['visible']} |" for k, v in extra["defects_by_kind"].items())
    splits = "\n".join(f"| {k} | {v['images']} | {v['annotations']} |" for k, v in extra["splits"].items())
    return f"""# Ramure synthetic fruit dataset

{s["count"]} simulated fruit (`{s["preset"]}`, {s["size_mm"]:g} mm across), {s["views"]} views each,
{s["picture"][0]}x{s["picture"][1]} pixels, dataset seed {s["seed"]}, defects `{s["defects"]}`,
{s["levels"]} volume subdivision(s), stage `{s["stage"]}`.  Made by `ramure fruit batch`
(Bohl 2015's 3G-map fruit and defect rules).  The same settings give byte-identical labels,
COCO files and manifest, whatever the number of workers or the cluster.

## What is simulated
- The fruit's shape from the thesis's grammar and preset, with a slight natural variation per
  fruit, or a malformation (a named shape or Grammar 3.1 at a random rate).
- Its inner tissues (exocarp, mesocarp, columella; with 2 subdivisions endocarp, locules, seeds).
- Geometric defects: cracks (longitudinal, transverse, concentric round the stem scar; fresh or
  healed), hail craters, rot (faster local drying), shrinkage, excrescences.
- Per view: a random camera (field of view 24-40 degrees, distance from the nominal size,
  never refitted, so a shrunk fruit looks smaller), a key light and a fill light of random
  direction, strength and tint, a little gloss, a random backdrop colour, and a stage:
  `plain`, `conveyor` (the fruit lies on a belt) or `cup` (it stands in a cup on the belt).
- The grade with its reasons, from the measured defect sizes in millimetres.

## What is not simulated
- Real skin optics: no texture, subsurface scattering, translucency, dirt, wax bloom or
  lenticels; colours are flat per tissue (and per defect look where the renderer has one).
- Camera effects: no lens distortion, blur, noise, motion, exposure or white balance changes.
- Fruit-to-fruit contact, several fruit per picture, leaves, labels on the fruit.
- Biological processes: rot and shrinkage are geometric (cells shrink), not grown in time.
- Defects that never change the picture: a defect whose mask does not differ (at least 12
  pixels by more than 8 levels) from the fruit without its located defects seen the same way
  is kept in the fruit's labels with `visible: false` and has no COCO annotation in that view.
- A crack's mask is its walls plus the pixels of its cells' skin it changes; a crater's is
  its bowl (the cells round its vertex); rot's the three rings of cells it dries faster.

## Files
- `fruit_NNNN_vK.png`: view K of fruit NNNN (`_clean.png`, when asked: the same view of
  the fruit without its located defects, shrunk if the fruit is: the reference of `visible`).
  `fruit_NNNN_cut.png`: the fruit cut through its axis.
- `fruit_NNNN.vtu`: the damaged fruit's cells in millimetres (frame of the cameras), with cell
  data `tissue`, `defect` (index + 1 of the first defect owning the cell, 0 none) and
  `defect_bits` (bit i: defect i): the 3D ground truth.
- `fruit_NNNN.json`: the labels: recipe, malformation, defects with their facts and `cells`
  (`dropped_defects`: random draws this fruit's shape refused, with the reason),
  the grade and its reasons, split, and per view the camera, the scene, and per defect its
  mask (RLE), pixels, `changed_pixels`, `seen_area_fraction` and `visible`.
- `coco_train.json`, `coco_val.json`, `coco_test.json`, `coco_all.json`: COCO instance
  segmentation; `dataset.json`: the manifest.

## Conventions
- Categories: {", ".join(f"{c['id']} {c['name']}" for c in extra["categories"])}.  Shrinkage
  has no place of its own: it is an attribute of the `fruit` annotation.
- Masks (`{s.get("coco_masks", "rle")}` in the COCO files): exact per pixel (from an id pass of the
  same camera), with occlusion by the fruit and the cup; `rle` is uncompressed COCO RLE
  (detectron2: `INPUT.MASK_FORMAT=bitmask`), `polygon` the outer boundaries along pixel edges
  (holes dropped; ultralytics' `convert_coco(use_segments=True)`).  The fruit's labels
  always hold the RLE.  `area` is the mask's pixel count; `bbox` is `[x, y, width, height]`
  of its pixels.
- Cameras (in each image's `camera`): OpenCV pinhole, `x_cam = R x_world + t` in mm, pixels
  `K x_cam` divided by depth, origin at the top-left pixel's centre.
- Splits: {", ".join(f"{n}" for n in ("train", "val", "test"))} drawn per fruit from the seed
  (70/15/15); all views of a fruit are in one split.

## Counts
| split | images | annotations |
|---|---|---|
{splits}

| defect kind | labelled | visible in at least one view |
|---|---|---|
{by_kind}

Pictures shared by two different labels: {extra["duplicate_pictures"]}.
"""
