"""A labelled dataset of defective fruit for vision: ``ramure fruit batch`` (issues 17, 40).

The thesis's stated use of its defect rules is a database of varied, defective fruit to
train a sorting system.  :func:`make_dataset` writes, for fruit ``i`` of ``count``:

* ``fruit_0000_v0.png`` .. ``_v{views-1}.png``: views with a random camera, light,
  backdrop and stage (plain, conveyor belt, cup; see :mod:`ramure.app.fruit_views`), and
  with ``clean_pictures`` the same views of the fruit without its located defects
  (``_v0_clean.png``; shrunk when the fruit is); ``fruit_0000_cut.png``: the fruit cut through its axis by a plane of
  random direction;
* ``fruit_0000.vtu``: the damaged fruit's cells in millimetres, in the cameras' frame, with
  ``tissue`` and the 3D ground truth ``defect`` / ``defect_bits`` per cell;
* ``fruit_0000.json``: the labels: recipe, malformation, every defect's facts and cells,
  volume lost, the grade with its reasons, the split, and per view the camera (intrinsics,
  extrinsics), the scene, the fruit's mask and each located defect's exact mask (RLE),
  pixels, pixels that differ from the clean fruit, seen area fraction and ``visible``;

then ``coco_{train,val,test,all}.json`` and ``DATASET_CARD.md`` (:mod:`ramure.app.fruit_coco`)
and ``dataset.json``, the manifest: the settings, ``"complete"``, counts, one row per fruit.

**Visible** means: at least :data:`MIN_VISIBLE_PIXELS` pixels of the defect's mask differ
from the reference fruit (same shape, shrinkage, camera, light and stage, without the
located defects: crack, hail, rot, excrescence) by more than :data:`CHANGED_LEVEL` in a
channel.  Only visible defects get COCO annotations; the
others stay in the fruit's labels.  Shrinkage has no place: it is the fruit's (the camera
is never refitted, so a shrunk fruit is smaller in the picture).

**Nothing half-done.**  The manifest is written first, ``"complete": false``, and rewritten
``true`` last; a fruit's labels are its last file, so a fruit with labels is whole.  A folder
that is not empty is refused unless told: ``resume=True`` (``--resume``) finishes the dataset
there (same settings, only the fruit without labels are made), ``overwrite=True``
(``--overwrite``) removes the dataset files there first (``fruit_NNNN*`` and the manifest;
nothing else).  Labels and manifest hold no timings, so one seed gives byte-identical files.
Workers end when the process that started them dies (``kill -9`` included), instead of
writing on into a folder the user has seen the command give up on.

**Deterministic and independent.**  Fruit ``i`` draws all its random numbers from
``numpy.random.SeedSequence([seed, i])``: the same seed gives the same dataset, fruit
``i`` is the same whatever ``count`` and whichever worker builds it.

**Random defects** (``defects="random"``), per fruit: see :func:`random_recipe` (kinds
balanced: crack, hail, rot, shrink and excrescence equally likely, concentric cracks round
the stem scar among the cracks).  Hail stops at the endocarp when the fruit has one (two
volume subdivisions), else at the mesocarp.  ``defects="none"``: clean fruit that still
vary (shape variation, views).  The split (70/15/15) is drawn per fruit from the seed.

**Speed.**  A process pool (``workers``, default 2) builds, damages, renders and writes
the fruit; each worker keeps one off-screen plotter for all its pictures.  With
``scheduler`` the fruit are made on Dask workers and their files sent back here.  Fruit are
built with one volume subdivision by default (``levels=1``: exocarp, mesocarp and the
columella; 2 adds endocarp, locules and seeds, at about 40 times the cost).
"""

from __future__ import annotations

import contextlib
import json
import os
import pathlib
import re
import sys
import time
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

import ramure.io as atomic
from ramure.app.fruit_coco import CATEGORY_ID, MASK_FORMATS
from ramure.errors import RamureError, ValueRefused

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3

PICTURE = (256, 256)
#: Views per fruit unless told.
VIEWS = 4
#: Ranges the random defects are drawn from (mm on a fruit ``size_mm`` across).
RANDOM_RANGES: dict[str, tuple[Any, Any]] = {  # int ranges (counts, rings) and float ones
    "crack_width_mm": (0.5, 3.0),
    "crack_rings": (2, 5),
    "hail_count": (1, 6),
    "hail_depth_mm": (1.0, 5.0),
    "shrink_rate": (0.02, 0.10),
    "rot_rate": (0.02, 0.06),
    "malform_rate": (0.05, 0.4),
    "variation_rate": (0.0, 0.06),
    "excrescence_height_mm": (2.0, 6.0),
}
#: Defect kinds a random fruit draws from, each as likely as the others (crack: longitudinal,
#: transverse or concentric, one in three each).
DEFECT_KINDS = ("crack", "hail", "rot", "shrink", "excrescence")
CRACK_KINDS = ("longitudinal", "transverse", "concentric")
#: Probability of 0, 1 and 2 defect kinds on a random fruit.
DEFECT_COUNT_P = (0.2, 0.5, 0.3)
#: Order defects are applied in: those that keep the topology first (their vertex ids are
#: the clean fruit's), the one that grows cells, then the crack (unsews faces).
APPLY_ORDER = ("hail", "rot", "shrink", "excrescence", "crack")
#: A defect is visible in a view when at least this many pixels of its mask differ from the
#: clean fruit seen the same way (any channel by more than :data:`CHANGED_LEVEL`).
MIN_VISIBLE_PIXELS = 12
CHANGED_LEVEL = 8
#: Train / validation / test fractions of the split (per fruit, all its views together).
SPLIT = (("train", 0.7), ("val", 0.15), ("test", 0.15))
_STATE: dict[str, Any] = {}


def fruit_rng(seed: int, index: int, stream: int = 0) -> np.random.Generator:
    """The random generator of fruit ``index`` in a dataset of ``seed``: stream 0 its recipe,
    1 its views, 2 its split."""
    key = [int(seed), int(index)] + ([int(stream)] if stream else [])
    return np.random.default_rng(np.random.SeedSequence(key))


def split_of(seed: int, index: int) -> str:
    """The split (train, val or test) of fruit ``index``: drawn from (seed, index), so it does
    not depend on the count."""
    u = float(fruit_rng(seed, index, 2).random())
    for name, share in SPLIT:
        if u < share:
            return name
        u -= share
    return SPLIT[-1][0]


def random_recipe(rng: np.random.Generator, preset: str = "round_tomato", levels: int = 1) -> dict:
    """Malformation (or a slight natural variation of the shape) and defect specs for one fruit.

    A malformation with probability 0.3 (a named shape or Grammar 3.1 at a rate up to 0.4),
    else a natural variation (Grammar 3.1 at a rate up to 0.06), so clean fruit vary too.
    Then 0, 1 or 2 defect kinds (:data:`DEFECT_COUNT_P`) drawn without replacement, each
    kind of :data:`DEFECT_KINDS` as likely; ranges in :data:`RANDOM_RANGES`.  Last, the
    ripeness: one of the species' stages (:func:`ramure.gmap.organs.species.stages`), each as likely.
    """
    from ramure.gmap.organs.malform import SHAPES
    from ramure.gmap.organs.species import species_of, stages

    r = RANDOM_RANGES
    variation = round(float(rng.uniform(*r["variation_rate"])), 3)  # used when not malformed
    malform = None
    if rng.random() < 0.3:
        if rng.random() < 0.5:
            malform = {"shape": str(rng.choice(sorted(SHAPES))), "rate": 0.0}
        else:
            malform = {"shape": None, "rate": round(float(rng.uniform(*r["malform_rate"])), 3)}
    n = int(rng.choice(len(DEFECT_COUNT_P), p=DEFECT_COUNT_P))
    kinds = [str(k) for k in rng.choice(DEFECT_KINDS, n, replace=False)]
    specs = [(kind, _random_spec(rng, kind, levels)) for kind in kinds]
    specs.sort(key=lambda s: APPLY_ORDER.index(s[0]))
    seed = int(rng.integers(0, 2**31 - 1))
    return {
        "preset": preset,
        "malform": malform,
        "variation": variation,
        "defects": specs,
        "seed": seed,
        "ripeness": str(rng.choice(stages(species_of(preset)))),
    }


def _random_spec(rng, kind, levels):
    r = RANDOM_RANGES
    if kind == "crack":
        first = int(rng.integers(1, 5))
        return {
            "kind": str(rng.choice(CRACK_KINDS)),
            "sector": int(rng.integers(0, 1000)),
            "rings": (first, first + int(rng.integers(*r["crack_rings"]))),
            "depth": 1,
            "width_mm": round(float(rng.uniform(*r["crack_width_mm"])), 2),
            "healed": int(rng.integers(0, 2)),
        }
    if kind == "hail":
        lo = float(rng.uniform(r["hail_depth_mm"][0], r["hail_depth_mm"][1] - 1.0))
        return {
            "count": int(rng.integers(*r["hail_count"])),
            "depth_mm": (round(lo, 2), round(lo + 1, 2)),
            "stop": "endocarp" if levels >= 2 else "mesocarp",
        }
    if kind == "rot":
        return {"rate": round(float(rng.uniform(*r["rot_rate"])), 3)}
    if kind == "shrink":
        return {"rate": round(float(rng.uniform(*r["shrink_rate"])), 3), "steps": int(rng.integers(1, 3))}
    # excrescence: near the stem scar or a mucron at the blossom end, on one sector
    return {
        "path": ("stem" if rng.random() < 0.7 else "blossom", int(rng.integers(0, 1000))),
        "height_mm": round(float(rng.uniform(*r["excrescence_height_mm"])), 2),
        "segments": int(rng.integers(1, 3)),
    }


def build_one(recipe: dict, levels: int = 1, size_mm: float = 65.0) -> tuple[GMap3, GMap3, dict]:
    """Build one fruit from its recipe: ``(reference map, damaged map, labels)``.

    The reference is the fruit without its located defects (crack, hail, rot, excrescence):
    the clean fruit, shrunk when the recipe shrinks it, so that a located defect's mask is
    compared with the same fruit without it.  The labels' defects carry ``cells``, the
    volume ids of the damaged map each defect made or moved."""
    from ramure.gmap.organs.defect_specs import apply_defects
    from ramure.gmap.organs.fruit import build_fruit
    from ramure.gmap.organs.malform import malform_params, shape_facts

    params = {}
    malform = recipe.get("malform")
    if malform:
        params = malform_params(recipe["preset"], seed=recipe["seed"], **malform)
    elif recipe.get("variation"):  # a slight natural variation of a fruit that is not malformed
        params = malform_params(recipe["preset"], seed=recipe["seed"], rate=recipe["variation"])
    clean = build_fruit(
        recipe["preset"],
        seed=recipe["seed"],
        volume_levels=levels,
        ripeness=recipe.get("ripeness"),
        size_mm=size_mm,
        **params,
    )
    specs = [(kind, _fit(clean, kind, dict(opts))) for kind, opts in recipe["defects"]]
    from ramure.gmap.organs.defects import mm_per_unit

    lo, hi = clean.points.min(axis=0), clean.points.max(axis=0)
    labels = {
        "preset": recipe["preset"],
        "seed": recipe["seed"],
        "ripeness": clean.meta.get("ripeness"),
        "model_frame": {"centre": [float(x) for x in (lo + hi) / 2], "mm_per_unit": float(mm_per_unit(clean, size_mm))},
        "params": params,
        "variation": 0.0 if malform else recipe.get("variation", 0.0),
        "malformation": None if not malform else {**malform, **shape_facts(clean)},
    }
    gm, facts, specs, dropped = _apply_what_applies(clean, specs, size_mm, recipe["seed"])
    labels["dropped_defects"] = dropped
    whole = [spec for spec in specs if spec[0] not in CATEGORY_ID]  # shrinkage: no place of its own
    if len(whole) == len(specs):
        reference = gm  # nothing located: the fruit is its own reference
    else:
        reference = apply_defects(clean, whole, size_mm=size_mm, seed=recipe["seed"])[0] if whole else clean
    for fact in facts["defects"]:
        fact["cells"] = [int(c) for c in defect_cells(clean, gm, fact)]
    labels.update(
        defects=facts["defects"],
        volume_lost_fraction=facts["volume_lost_fraction"],
        grade=facts["grade"],
        darts=gm.n_darts,
        volumes=gm.n_volumes,
    )
    return reference, gm, labels


def _apply_what_applies(clean, specs, size_mm, seed):
    """Apply the specs; if the fruit refuses one (a crack that would turn a cell inside out on
    this shape...), drop specs from the last until the rest apply, so one rare draw never
    stops a batch.  Returns ``(map, facts, applied specs, dropped [{kind, reason}])``."""
    from ramure.gmap.organs.defect_specs import apply_defects

    reason = None
    for keep in range(len(specs), 0, -1):
        try:
            gm, facts = apply_defects(clean, specs[:keep], size_mm=size_mm, seed=seed)
        except RamureError as exc:
            reason = reason or str(exc)
            continue
        return gm, facts, specs[:keep], [{"kind": kind, "reason": reason} for kind, _ in specs[keep:]]
    gm, facts = apply_defects(clean, [], size_mm=size_mm, seed=seed)
    return gm, facts, [], [{"kind": kind, "reason": reason} for kind, _ in specs]


def defect_cells(clean: GMap3, damaged: GMap3, fact: Mapping[str, Any]) -> np.ndarray:
    """Volume ids (of ``damaged``) a defect made or moved: a crater's cells at its vertex (the
    crater's bowl), rot's three rings, an excrescence's grown cells, the cells
    whose faces a crack exposed; none for shrinkage, which is the whole fruit.

    Vertex ids of hail and rot are the clean fruit's (they are applied before any defect
    that changes the topology, see :data:`APPLY_ORDER`)."""
    from ramure.gmap.organs.defects import rot_rings

    kind = fact["kind"]
    if kind == "hail":
        cells = [rot_rings(clean, c["vertex"], 1)[0] for c in fact["craters"]]
        return np.unique(np.concatenate(cells)) if cells else np.zeros(0, np.int64)
    if kind == "rot":
        return np.unique(np.concatenate(rot_rings(clean, fact["vertex"], len(fact["coefficients"]))))
    if kind == "excrescence":
        return np.asarray(fact["volumes"], np.int64)
    if kind == "crack":
        n = clean.n_darts
        ids = np.arange(n)
        opened = (damaged.alpha[3][:n] == ids) & (clean.alpha[3] != ids)
        return np.unique(damaged.dart_volume[:n][opened]).astype(np.int64)
    return np.zeros(0, np.int64)


def _fit(gm, kind, opts):
    """Fit drawn positions to this fruit: a crack's sector modulo its sectors and rings inside
    (a concentric crack round the stem scar), an excrescence's path."""
    vd = gm.volume_data
    ph, rings = int(vd["sector"].max()) + 1, int(vd["ring"].max()) + 1
    if kind == "crack":
        opts["sector"] %= ph
        first, last = opts["rings"]
        last = min(last, rings - 2)
        opts["rings"] = (min(first, last), last)
        if opts["kind"] == "concentric":
            ring = max(0, rings - 3 - (first % 2))
            opts["rings"] = (ring, ring)
    elif kind == "excrescence" and isinstance(opts.get("path"), (tuple, list)):
        end, sector = opts["path"]
        stage = int(vd["stage"].max()) - 1 if end == "stem" else 1
        opts["path"] = f"({stage}, C{sector % ph + 1}, *)"
    return opts


def _renderer(size):
    from ramure.app.fruit_views import ViewRenderer

    renderer = _STATE.get("renderer")
    if renderer is None or renderer.size != tuple(size):
        if renderer is not None:
            renderer.close()
        renderer = _STATE["renderer"] = ViewRenderer(size)
    return renderer


def close_plotter() -> None:
    """Close this process's renderer (workers' renderers end with their process)."""
    renderer = _STATE.pop("renderer", None)
    if renderer is not None:
        renderer.close()


def _cell_rgb(surface) -> np.ndarray:
    """Picture colour of each surface face: its cell's species colour, ripeness and damage marks,
    which every grid of the batch carries (``rgb``, made by :func:`_mm_grid`)."""
    return np.asarray(surface.cell_data["rgb"], np.uint8)


def _mm_grid(gm, centre, scale):
    """The map as a grid in millimetres about ``centre`` (model units times ``scale``), its cells
    coloured as the species looks at its ripeness, with the defects' marks (corky healed walls,
    wet wounds, bruises, rot): :func:`ramure.app.fruit_look.coloured_grid`, seeded by the fruit."""
    from ramure.app.fruit_look import coloured_grid

    grid = coloured_grid(gm, seed=int(gm.meta.get("seed", 0) or 0), round_marks=True)
    grid.points = (np.asarray(grid.points) - centre) * scale
    return grid


def render_views(
    index: int,
    seed: int,
    clean: GMap3,
    damaged: GMap3,
    labels: dict,
    size_mm: float,
    views: int,
    stage: str,
    picture: tuple[int, int],
) -> tuple[list[dict], list[np.ndarray], list[np.ndarray], Any]:
    """Render fruit ``index``'s views: ``(view records, pictures, clean pictures, damaged grid)``.

    Each record: the stage and camera (:func:`ramure.app.fruit_views.camera_matrices`),
    the fruit's mask, and per defect its mask (RLE), pixels, bounding box, the pixels that
    differ from the clean fruit seen the same way, the fraction of its surface area seen,
    and ``visible``.  The grid carries the per-cell ``defect`` (index + 1 of the first
    defect, 0 for none) and ``defect_bits`` (bit i: defect i).
    """
    from ramure.app import fruit_views as V

    frame = labels["model_frame"]  # the clean fruit's: a shrunk fruit is not refitted
    centre, scale = np.asarray(frame["centre"]), frame["mm_per_unit"]
    grid = _mm_grid(damaged, centre, scale)
    first = np.zeros(grid.n_cells, np.int16)
    bits = np.zeros(grid.n_cells, np.int32)
    for i, fact in reversed(list(enumerate(labels["defects"]))):
        cells = np.asarray(fact["cells"], np.int64)
        first[cells] = i + 1
        bits[cells] |= np.int32(1 << min(i, 30))
    grid.cell_data["defect"] = first
    grid.cell_data["defect_bits"] = bits
    surface = grid.extract_surface(algorithm="dataset_surface")
    same = clean is damaged  # no located defect: one surface, one picture per view
    clean_surface = surface if same else _mm_grid(clean, centre, scale).extract_surface(algorithm="dataset_surface")
    face_cell = np.asarray(surface.cell_data["vtkOriginalCellIds"], np.int64)
    pixel = size_mm / (max(V.FILL) * picture[1])  # mm: the largest a fruit is drawn
    surface, face_cell, round_bits, owner = _round_marks(
        surface, face_cell, bits, labels["defects"], grid, int(damaged.meta.get("seed", 0) or 0), pixel
    )
    for g in (grid, clean_surface):  # colours without the marks: only for drawing them
        if "rgb_plain" in g.cell_data:
            g.cell_data.remove("rgb_plain")
    cell_bits = bits[face_cell]
    face_bits = _face_bits(surface, cell_bits, labels["defects"])
    if round_bits is not None:
        face_bits = round_bits(face_bits)
    face_area = np.asarray(surface.compute_cell_sizes(length=False, volume=False).cell_data["Area"])
    rgb, clean_rgb = _cell_rgb(surface), _cell_rgb(clean_surface)
    renderer = _renderer(picture)
    records, pictures, cleans = [], [], []
    drawn = V.sample_views(fruit_rng(seed, index, 1), views, size_mm, stage)
    renderer.set_fruit(
        surface, rgb, clean_surface, clean_rgb, V.stage_meshes(drawn[0], np.asarray(clean_surface.points), size_mm)
    )
    for k, view in enumerate(drawn):
        img = renderer.picture(view)
        ref = img if same else renderer.picture(view, clean=True)
        faces = renderer.face_ids(view)
        seen = faces >= 0
        changed = (np.abs(img.astype(np.int16) - ref.astype(np.int16)) > CHANGED_LEVEL).any(axis=2)
        pix_bits = np.where(seen, face_bits[np.where(seen, faces, 0)], 0)
        pix_cells = np.where(seen, cell_bits[np.where(seen, faces, 0)], 0)
        seen_faces = np.zeros(surface.n_cells, bool)
        seen_faces[faces[seen]] = True
        if owner is not None:  # drawn round: a face is seen when any piece of the face it was cut from is
            seen_faces = np.bincount(owner[seen_faces], minlength=int(owner.max()) + 1)[owner] > 0
        defects = []
        for i, fact in enumerate(labels["defects"]):
            if fact["kind"] not in CATEGORY_ID:
                continue  # shrinkage: the whole fruit (its fruit-level facts say how much)
            mask = (pix_bits & (1 << min(i, 30))) != 0
            if fact["kind"] == "crack":  # its walls, and where it changes the skin of its cells
                mask |= ((pix_cells & (1 << min(i, 30))) != 0) & changed
            mine = (face_bits & (1 << min(i, 30))) != 0
            area = float(face_area[mine].sum())
            n_changed = int((mask & changed).sum())
            defects.append(
                {
                    "defect": i,
                    "kind": fact["kind"],
                    "pixels": int(mask.sum()),
                    "changed_pixels": n_changed,
                    "seen_area_fraction": round(float(face_area[mine & seen_faces].sum()) / area, 6) if area > 0 else 0.0,
                    "visible": n_changed >= MIN_VISIBLE_PIXELS,
                    "bbox": V.bbox(mask),
                    "segmentation": V.rle_encode(mask),
                }
            )
        records.append(
            {
                "view": k,
                "stage": view["stage"],
                "camera": V.camera_matrices(view, picture),
                "scene": {key: view[key] for key in view if key not in ("stage",)},
                "fruit": {"pixels": int(seen.sum()), "bbox": V.bbox(seen), "segmentation": V.rle_encode(seen)},
                "defects": defects,
            }
        )
        pictures.append(img)
        cleans.append(ref)
    return records, pictures, cleans, grid


#: Defect kinds drawn as round marks (:mod:`ramure.app.fruit_marks`): their masks are the drawn discs.
ROUND_KINDS = ("hail", "rot")


def _round_marks(surface, face_cell, bits, defects, grid, seed, pixel):
    """Draw the hail pits and rot lesions round (:func:`ramure.app.fruit_marks.draw_round_marks`,
    normals split at the renderer's 50 degrees, mould placed by ``seed``, faces down to about
    two ``pixel`` (mm) across):
    ``(surface, face cell, round_bits, owner)``.

    ``owner`` (None when nothing is drawn round): the face of ``surface`` each drawn face is
    cut from.  ``round_bits`` (None then too) turns per-face defect bits into the
    drawn surface's: a hail or rot defect that has a disc keeps its bit only on the faces
    where one of its discs weighs at least one half, so its mask is the round mark the
    picture shows, not the square skin faces of its cells.  A disc belongs to the defects
    whose cells carry the faces it was found from."""
    from ramure.app.fruit_marks import draw_round_marks, mark_discs

    centre = np.asarray(grid.center, float)
    discs = mark_discs(surface, centre) if "rgb_plain" in surface.cell_data else []
    drawn = draw_round_marks(surface, centre, seed=seed, feature_angle=50.0, discs=discs, pixel=pixel)
    if drawn is surface:
        return surface, face_cell, None, None
    round_mask = 0
    for i, fact in enumerate(defects):
        if fact["kind"] in ROUND_KINDS:
            round_mask |= 1 << min(i, 30)
    disc_bits = [int(np.bitwise_or.reduce(bits[face_cell[d.faces]], initial=0)) & round_mask for d in discs]
    marks = np.asarray(drawn.cell_data["mark_bits"], np.int64)
    owner = np.asarray(drawn.cell_data["face"], np.int64)
    face_cell = face_cell[owner]

    def round_bits(face_bits: np.ndarray) -> np.ndarray:
        out = face_bits.copy()
        for mine in disc_bits:
            out &= ~np.int32(mine)
        for k, mine in enumerate(disc_bits):
            out[(marks >> min(k, 62)) & 1 == 1] |= np.int32(mine)
        return out

    return drawn, face_cell, round_bits, owner


#: A crack's mask is its walls: faces of its cells turned away from the fruit's centre by
#: more than this (|normal . radial| below it); skin faces face outward.
WALL_COSINE = 0.6


def _face_bits(surface, bits: np.ndarray, defects: Sequence[Mapping[str, Any]]) -> np.ndarray:
    """Defect bits per surface face: the cell's, but a crack keeps only its walls (the faces it
    exposed, not the skin of its cells); its mask adds the pixels of its cells' skin that
    differ from the reference (the gap's shading), see :func:`render_views`."""
    cracks = [i for i, d in enumerate(defects) if d["kind"] == "crack"]
    if not cracks:
        return bits
    shown = surface.compute_normals(cell_normals=True, point_normals=False, auto_orient_normals=False)
    normal = np.asarray(shown.cell_data["Normals"])
    centre = np.asarray(surface.cell_centers().points)
    radial = centre / np.maximum(np.linalg.norm(centre, axis=1, keepdims=True), 1e-12)
    wall = np.abs(np.einsum("ij,ij->i", normal, radial)) < WALL_COSINE
    out = bits.copy()
    for i in cracks:
        out[~wall] &= ~np.int32(1 << min(i, 30))
    return out


def _cut_picture(grid, index, seed, picture):
    """A picture of the fruit cut through its axis by a plane of random direction, facing the cut."""
    from ramure.gmap.kernel.cut import plane_cut

    angle = float(fruit_rng(seed, index, 3).uniform(0, 2 * np.pi))
    normal = np.array([np.cos(angle), np.sin(angle), 0.0])
    cut = plane_cut(grid, normal=normal, origin=(0.0, 0.0, 0.0), mode="clip").extract_surface(algorithm="dataset_surface")
    b = np.asarray(cut.bounds, float).reshape(3, 2)
    extent = float(np.max(b[:, 1] - b[:, 0])) or 1.0
    look = normal + 0.35 * np.cross(normal, [0.0, 0.0, 1.0]) + np.array([0.0, 0.0, 0.25])
    look /= np.linalg.norm(look)
    view = {
        "eye": list(b.mean(axis=1) + look * extent * 2.6),
        "target": list(b.mean(axis=1)),
        "view_up": [0.0, 0.0, 1.0],
        "view_angle_deg": 30.0,
        "key_light": {"direction": list(look + np.array([0.3, 0.3, 0.6])), "intensity": 0.9},
        "fill_light": 0.35,
        "light_tint": [1.0, 1.0, 1.0],
        "ambient": 0.25,
        "gloss": 0.2,
        "background": [1.0, 1.0, 1.0],
    }
    renderer = _renderer(picture)
    colours = _cell_rgb(cut)
    renderer.set_fruit(cut, colours, cut, colours, [])
    return renderer.picture(view), {"normal": normal.tolist(), "origin": [0.0, 0.0, 0.0]}


def _png(img: np.ndarray) -> bytes:
    import io

    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG")
    return buf.getvalue()


def make_fruit(
    index: int,
    recipe: dict,
    seed: int = 0,
    levels: int = 1,
    size_mm: float = 65.0,
    picture: tuple[int, int] = PICTURE,
    views: int = VIEWS,
    stage: str = "mixed",
    clean_pictures: bool = False,
) -> dict[str, bytes]:
    """Build, damage and picture fruit ``index``: its files as ``{name: bytes}`` (written by
    the caller, so a remote worker needs no shared folder); the labels (``.json``) last."""
    clean, gm, labels = build_one(recipe, levels, size_mm)
    stem = f"fruit_{index:04d}"
    records, pictures, cleans, grid = render_views(index, seed, clean, gm, labels, size_mm, views, stage, picture)
    files: dict[str, bytes] = {}
    for k, (record, img, ref) in enumerate(zip(records, pictures, cleans)):
        record["file_name"] = f"{stem}_v{k}.png"
        files[record["file_name"]] = _png(img)
        if clean_pictures:
            record["clean_file_name"] = f"{stem}_v{k}_clean.png"
            files[record["clean_file_name"]] = _png(ref)
    cut, plane = _cut_picture(grid, index, seed, picture)
    files[f"{stem}_cut.png"] = _png(cut)
    files[f"{stem}.vtu"] = _vtu_bytes(grid)
    names = {
        "views": [r["file_name"] for r in records],
        "cut_picture": f"{stem}_cut.png",
        "grid": f"{stem}.vtu",
        "labels": f"{stem}.json",
    }
    record = {
        "index": index,
        "split": split_of(seed, index),
        "units": "mm",
        "size_mm": float(size_mm),
        **labels,
        "cut_plane": plane,
        "views": records,
        "files": names,
    }
    files[f"{stem}.json"] = json.dumps(_plain(record), indent=1).encode()
    return files


def _vtu_bytes(grid) -> bytes:
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        path = pathlib.Path(tmp) / "fruit.vtu"
        atomic.save_mesh(grid, path)
        return path.read_bytes()


def write_files(folder: str | os.PathLike, files: Mapping[str, bytes]) -> None:
    """Write a fruit's files (each atomically), the labels last: a fruit with labels is whole."""
    folder = pathlib.Path(folder)
    for name in sorted(files, key=lambda n: n.endswith(".json")):
        atomic.write_bytes(folder / name, files[name])


def write_one(
    index: int,
    recipe: dict,
    folder: str | os.PathLike,
    levels: int = 1,
    size_mm: float = 65.0,
    picture: tuple[int, int] = PICTURE,
    seed: int = 0,
    views: int = VIEWS,
    stage: str = "mixed",
    clean_pictures: bool = False,
) -> dict:
    """Build, damage, picture and write fruit ``index``; returns its summary row."""
    files = make_fruit(index, recipe, seed, levels, size_mm, picture, views, stage, clean_pictures)
    write_files(folder, files)
    return summary_row(json.loads(files[f"fruit_{index:04d}.json"]))


def summary_row(record: Mapping[str, Any]) -> dict:
    """The manifest's row for a fruit, from its labels."""
    malformation = record["malformation"]
    return {
        "index": int(record["index"]),
        "split": record.get("split"),
        "grade": record["grade"]["grade"],
        "defects": [d["kind"] for d in record["defects"]],
        "visible_defects": sorted({d["defect"] for v in record.get("views", []) for d in v["defects"] if d["visible"]}),
        "malformation": None if not malformation else (malformation["shape"] or f"rate={malformation['rate']}"),
        "labels": record["files"]["labels"],
    }


def _plain(value):
    """JSON-ready copy: numpy scalars and tuples become Python numbers and lists."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _job(args):
    """A pool worker's job: make fruit ``args[0]`` and write it into the folder."""
    _end_if_orphaned()
    index, recipe, folder, options = args
    return write_one(index, recipe, folder, **options)


def _remote_job(args):
    """A Dask worker's job: make the fruit and send its files back (no shared folder needed)."""
    index, recipe, _folder, options = args
    return make_fruit(index, recipe, **options)


_PARENT: list[int] = []  # in a worker: the pid of the process that started it


def _worker_start(parent: int) -> None:
    """Worker initializer: end this worker when ``parent`` dies (Linux: the kernel sends SIGTERM
    at once, even to a worker blocked on the dead queue; elsewhere each job checks first)."""
    _PARENT[:] = [parent]
    if sys.platform.startswith("linux"):
        import ctypes
        import signal

        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGTERM))  # PR_SET_PDEATHSIG
    _end_if_orphaned()


def _end_if_orphaned() -> None:
    if _PARENT and os.getppid() != _PARENT[0]:
        import signal

        os.kill(os.getpid(), signal.SIGTERM)  # the command died: write nothing more into its folder


def make_dataset(
    folder: str | os.PathLike,
    count: int = 100,
    seed: int = 0,
    defects: str = "random",
    preset: str = "round_tomato",
    levels: int = 1,
    size_mm: float | None = None,
    workers: int = 2,
    picture: tuple[int, int] = PICTURE,
    resume: bool = False,
    overwrite: bool = False,
    views: int = VIEWS,
    stage: str = "mixed",
    clean_pictures: bool = False,
    scheduler: str | None = None,
    coco_masks: str = "rle",
) -> dict:
    """Write ``count`` labelled fruit into ``folder`` (see the module docstring); the summary
    (the manifest, plus ``"seconds"``).

    ``size_mm``: the fruit's real size in millimetres (default the preset's:
    :data:`ramure.gmap.organs.species.SIZE_MM`, a cherry tomato 25, a banana 180).
    ``coco_masks``: ``"rle"`` (exact) or ``"polygon"`` in the COCO files (see
    :func:`ramure.app.fruit_coco.coco_records`).  ``scheduler``: None (a process pool of ``workers``), ``"local"`` (a Dask
    ``LocalCluster`` of ``workers`` processes) or a Dask scheduler address
    (``tcp://host:8786``).  Refused before anything is written: count outside 1..100000,
    an unknown ``defects`` mode, preset or stage, levels outside 1..2, views outside
    1..64, workers < 1, a folder that is not empty without ``resume`` or ``overwrite``, a
    ``resume`` with other settings than the folder's.
    """
    from ramure.app.fruit_views import STAGES
    from ramure.gmap.organs.fruit import PRESETS

    if int(count) != count or not 1 <= count <= 100_000:
        raise ValueRefused(f"--count must be a whole number in 1..100000, got {count}")
    if defects not in ("random", "none"):
        raise ValueRefused(f"--defects must be 'random' or 'none', got {defects!r}")
    if preset not in PRESETS:
        raise ValueRefused(f"unknown fruit preset {preset!r}; choose one of {', '.join(PRESETS)}")
    if levels not in (1, 2):
        raise ValueRefused(f"--levels must be 1 or 2 (volume subdivisions; tissues need at least 1), got {levels}")
    if int(workers) != workers or workers < 1:
        raise ValueRefused(f"--workers must be >= 1, got {workers}")
    if int(views) != views or not 1 <= views <= 64:
        raise ValueRefused(f"--views must be a whole number in 1..64, got {views}")
    if stage not in (*STAGES, "mixed"):
        raise ValueRefused(f"--stage must be one of {', '.join(STAGES)} or mixed, got {stage!r}")
    if size_mm is None:
        from ramure.gmap.organs.species import SIZE_MM

        size_mm = SIZE_MM[preset]
    if not (np.isfinite(size_mm) and size_mm > 0):
        raise ValueRefused(f"--size-mm must be a finite number > 0, got {size_mm}")
    if coco_masks not in MASK_FORMATS:
        raise ValueRefused(f"--coco-masks must be one of {', '.join(MASK_FORMATS)}, got {coco_masks!r}")
    if resume and overwrite:
        raise ValueRefused("--resume and --overwrite exclude each other")
    folder = pathlib.Path(folder)
    if folder.exists() and not folder.is_dir():
        raise ValueRefused(f"-o {folder}: exists and is not a folder")
    settings = {
        "count": int(count),
        "seed": int(seed),
        "defects": defects,
        "preset": preset,
        "levels": levels,
        "size_mm": float(size_mm),
        "picture": [int(v) for v in picture],
        "views": int(views),
        "stage": stage,
        "clean_pictures": bool(clean_pictures),
        "coco_masks": coco_masks,
    }
    dask = _dask_client(scheduler, int(workers)) if scheduler is not None else None  # unreachable: nothing written
    try:
        _prepare(folder, settings, resume, overwrite)
        t0 = time.perf_counter()
        write_manifest(folder, settings, [], complete=False)
        done = {i for i in range(int(count)) if resume and (folder / f"fruit_{i:04d}.json").is_file()}
        options = {
            "seed": int(seed),
            "levels": levels,
            "size_mm": float(size_mm),
            "picture": tuple(int(v) for v in picture),
            "views": int(views),
            "stage": stage,
            "clean_pictures": bool(clean_pictures),
        }
        jobs = []
        for i in range(int(count)):
            if i in done:
                continue
            recipe = random_recipe(fruit_rng(seed, i), preset, levels)
            if defects == "none":
                recipe.update(malform=None, defects=[])
            jobs.append((i, recipe, str(folder), options))
        if not jobs:
            rows = []
        elif dask is not None:
            rows = _run_dask(jobs, dask[0], folder)
        else:
            rows = _run(jobs, int(workers))
        rows += [_row_of(folder, i) for i in sorted(done)]
        rows.sort(key=lambda r: r["index"])
        from ramure.app.fruit_coco import write_coco_and_card

        extra = write_coco_and_card(folder, settings, rows)
        summary = write_manifest(folder, settings, rows, complete=True, extra=extra)
        return {**summary, "seconds": round(time.perf_counter() - t0, 3)}
    finally:
        if dask is not None:
            dask[0].close()
            if dask[1] is not None:
                dask[1].close()


MANIFEST = "dataset.json"
_OURS = re.compile(
    r"fruit_\d{4,}(_cut|_v\d+|_v\d+_clean)?\.(png|vtu|json)|coco_(train|val|test|all)\.json|DATASET_CARD\.md|"
    + re.escape(MANIFEST)
)


def write_manifest(
    folder: pathlib.Path,
    settings: Mapping[str, Any],
    rows: Sequence[dict],
    complete: bool,
    extra: Mapping[str, Any] | None = None,
) -> dict:
    """Write ``dataset.json`` (atomically) and return what it holds."""
    summary = {
        "format": "ramure-fruit-dataset",
        "version": 2,
        **settings,
        "complete": complete,
        "marketable": sum(r["grade"] == "marketable" for r in rows),
        **(extra or {}),
        "fruit": list(rows),
    }
    atomic.write_text(folder / MANIFEST, json.dumps(_plain(summary), indent=1))
    return summary


def _prepare(folder: pathlib.Path, settings: Mapping[str, Any], resume: bool, overwrite: bool) -> None:
    """Make ``folder`` ready: created, or checked for ``resume``, or cleared of ours for ``overwrite``."""
    entries = sorted(folder.iterdir()) if folder.is_dir() else []
    if resume:
        old = _read_manifest(folder)
        if old is None:
            raise ValueRefused(f"--resume: {folder} holds no dataset to finish (no readable {MANIFEST})")
        differ = [k for k in settings if old.get(k) != settings[k]]
        if differ:
            raise ValueRefused(
                f"--resume: the dataset in {folder} was made with other settings ({', '.join(differ)}); "
                "give the same ones, or --overwrite"
            )
        return
    if entries and not overwrite:
        raise ValueRefused(f"-o {folder} is not empty: --resume finishes the dataset there, --overwrite replaces it")
    for entry in entries:
        if entry.is_file() and _OURS.fullmatch(entry.name):
            entry.unlink()
    folder.mkdir(parents=True, exist_ok=True)


def _read_manifest(folder: pathlib.Path) -> dict | None:
    try:
        data = json.loads(atomic.read_regular(folder / MANIFEST, 64 * 2**20, MANIFEST))
    except (RamureError, ValueError):
        return None
    return data if isinstance(data, dict) and data.get("format") == "ramure-fruit-dataset" else None


def _row_of(folder: pathlib.Path, index: int) -> dict:
    """The manifest row of fruit ``index`` made before a resume, from its labels."""
    path = folder / f"fruit_{index:04d}.json"
    try:
        return summary_row(json.loads(atomic.read_regular(path, 64 * 2**20, "fruit labels")))
    except (ValueError, KeyError, TypeError) as exc:
        raise RamureError(f"--resume: {path} is not a fruit's labels ({type(exc).__name__}); --overwrite remakes them") from None


def _warm() -> None:
    """Import and load in this process what every fruit needs (forked workers inherit it):
    pyvista and VTK's rendering modules, the compiled defect loops, a tiny fruit's path."""
    from ramure.app.render import headless_setup

    headless_setup()
    import pyvista  # noqa: F401
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
    from ramure.gmap.organs.defect_specs import apply_defects
    from ramure.gmap.organs.fruit import build_fruit

    gm = build_fruit("round_tomato", precision=4, ph=4, nbvolangle=2, volume_levels=1, seeds=0)
    apply_defects(gm, [("shrink", {"rate": 0.01})])
    import ramure.app.fruit_views  # noqa: F401


def _run(jobs, workers):
    if workers == 1 or len(jobs) == 1:
        try:
            return [_job(j) for j in jobs]
        finally:
            close_plotter()  # this process's GL context must not outlive the dataset
    _warm()
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    ctx = mp.get_context("fork" if hasattr(os, "fork") else "spawn")
    chunk = max(1, len(jobs) // (4 * workers))
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_worker_start, initargs=(os.getpid(),)) as pool:
        return list(pool.map(_job, jobs, chunksize=chunk))


#: How long to try to reach a Dask scheduler before giving up.
DASK_CONNECT_SECONDS = 20.0
#: How long a LocalCluster worker may take to start (and, once started, how long it outlives
#: a scheduler that died with this process; it writes nothing: the files come back here).
LOCAL_WORKER_START_SECONDS = 180.0


def _dask_client(scheduler: str, workers: int):
    """``(client, cluster)``: a client of the scheduler at ``scheduler``, or of a new
    ``LocalCluster`` of ``workers`` processes for ``"local"`` (its cluster, else None)."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise RamureError("running on a Dask cluster needs Dask: pip install 'ramure[dask]'") from None
    cluster = None
    try:
        if scheduler == "local":
            cluster = LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=":0",
                death_timeout=LOCAL_WORKER_START_SECONDS,  # a loaded machine starts workers slowly
            )
            return Client(cluster), cluster
        return Client(scheduler, timeout=f"{DASK_CONNECT_SECONDS}s"), None
    except (OSError, TimeoutError) as exc:
        if cluster is not None:
            cluster.close()
        raise RamureError(f"cannot reach the Dask scheduler at {scheduler} ({exc})") from None


def _run_dask(jobs, client, folder):
    """Make the fruit on the Dask ``client``'s workers and write their files here as they
    arrive; returns the summary rows."""
    from dask.distributed import as_completed

    futures = []
    rows = []
    try:
        futures = client.map(_remote_job, jobs, pure=False)
        for future in as_completed(futures):
            files = future.result()
            write_files(folder, files)
            label = next(name for name in files if name.endswith(".json"))
            rows.append(summary_row(json.loads(files[label])))
            future.release()
    finally:
        if futures:
            client.cancel(futures)
        with contextlib.suppress(Exception):  # release the workers' GL contexts; a gone worker has none
            client.run(close_plotter)
    return rows
