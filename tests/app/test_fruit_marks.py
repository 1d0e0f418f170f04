"""Round damage marks (issue 40, "defects that look like defects"): hail pits and rot lesions are
drawn as discs on the skin, not as the square skin faces of the cells the defects marked."""

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage

from ramure.app import fruit_look as L
from ramure.app import fruit_marks as M
from ramure.app.fruit_gallery import _first_site
from ramure.gmap.organs.defect_specs import apply_defects
from ramure.gmap.organs.fruit import build_fruit
from ramure.gmap.organs.species import CORK, ROT, hex_rgb, mark_weight, round_mark_rgb

#: The defect sheet's Class I hail: one healed 0.8 mm pit on a twice-subdivided tomato.
HAIL = "hail:count=1,depth_mm=0.8,healed=1,vertex=-1"


@pytest.fixture(scope="module")
def hail_tomato():
    gm = build_fruit("round_tomato", volume_levels=2)
    damaged, facts = apply_defects(gm, [_first_site(gm, HAIL)])
    (crater,) = [c for d in facts["defects"] if d["kind"] == "hail" for c in d["craters"]]
    return damaged, crater


def _pixels(path):
    return np.asarray(Image.open(path).convert("RGB")).astype(float)


def _largest(mask):
    lab, n = ndimage.label(mask)
    assert n > 0
    return lab == (np.argmax(np.bincount(lab.ravel())[1:]) + 1)


def _roundness(region):
    """Area over the circle about the region's centroid through its farthest pixel: 1 for a
    disc, 2/pi = 0.64 for a square, less for anything longer."""
    ys, xs = np.nonzero(region)
    r = np.hypot(ys - ys.mean(), xs - xs.mean()).max() + 0.5
    return region.sum() / (np.pi * r * r), (ys.mean(), xs.mean())


def test_a_hail_pit_is_drawn_round_with_a_corky_centre(tmp_path, hail_tomato):
    damaged, _ = hail_tomato
    L.render_png(damaged, tmp_path / "h.png", size=(400, 400), view="defect", legend=False, decorations=False)
    img = _pixels(tmp_path / "h.png")
    cork = np.array(hex_rgb(CORK), float)
    ratio = img / np.maximum(img.sum(axis=2, keepdims=True), 1)
    pit = _largest(np.abs(ratio - cork / cork.sum()).sum(axis=2) < 0.08)
    roundness, (cy, cx) = _roundness(pit)
    assert pit.sum() > 300  # about 26 mm2 seen at 0.22 mm a pixel
    assert roundness >= 0.8  # the square patch of the four cells at the hit measured 0.52
    r, g, b = img[int(round(cy)), int(round(cx))]
    assert r > g > b and abs(r / cork[0] - g / cork[1]) < 0.15  # corky brown in the middle, shaded


def test_a_drawn_pit_has_the_graded_area(hail_tomato):
    damaged, crater = hail_tomato
    grid = L.coloured_grid(damaged, round_marks=True)
    surface = L.coloured_surface(grid)
    centre = np.asarray(grid.center, float)
    (disc,) = M.mark_discs(surface, centre)
    assert disc.kind == "hail" and disc.healed
    drawn = M.draw_round_marks(surface, centre)
    mpu = damaged.meta["mm_per_unit"]
    area = M.mark_area(drawn, disc) * mpu**2
    assert area == pytest.approx(crater["area_mm2"], rel=0.1)  # measured 38.3 against 38.9 mm2
    assert drawn.n_cells > surface.n_cells  # the faces round the pit were subdivided


@pytest.mark.parametrize("levels, depth", [(2, 0.8), (2, 1.8), (1, 3.0)])
def test_a_pit_is_shaded_as_deep_as_it_was_dug(levels, depth):
    gm = build_fruit("round_tomato", volume_levels=levels)
    damaged, facts = apply_defects(gm, [_first_site(gm, HAIL.replace("depth_mm=0.8", f"depth_mm={depth}"))])
    grid = L.coloured_grid(damaged, round_marks=True)
    surface = L.coloured_surface(grid)
    centre = np.asarray(grid.center, float)
    (disc,) = M.mark_discs(surface, centre)
    mpu = damaged.meta["mm_per_unit"]
    dug = facts["defects"][0]["craters"][0]["actual_depth_mm"]
    assert disc.depth * mpu == pytest.approx(dug, rel=0.25)  # measured 0.91, 1.91 and 3.68 mm
    drawn = M.draw_round_marks(surface, centre)
    normals = np.asarray(drawn.point_data["Normals"])
    rel = np.asarray(drawn.points) - disc.centre
    across = rel - np.outer(rel @ disc.normal, disc.normal)
    r = np.linalg.norm(across, axis=1)
    wall = (r > 0.3 * disc.bowl) & (r < 0.7 * disc.bowl) & (np.abs(rel @ disc.normal) < disc.bowl)
    inward = -np.einsum("ij,ij->i", normals[wall], across[wall] / r[wall, None])
    assert wall.sum() > 50 and np.median(inward) > 0.5 * dug / mpu / disc.bowl  # the walls lean in


def test_a_fresh_pit_is_bruised_not_corky(tmp_path):
    gm = build_fruit("round_tomato", volume_levels=2)
    damaged, _ = apply_defects(gm, [_first_site(gm, HAIL.replace("healed=1", "healed=0"))])
    grid = L.coloured_grid(damaged, round_marks=True)
    (disc,) = M.mark_discs(L.coloured_surface(grid), np.asarray(grid.center, float))
    assert disc.kind == "hail" and not disc.healed


def test_a_rot_lesion_is_round_brown_with_a_soaked_rim_and_mould(tmp_path):
    pear = build_fruit("pear", volume_levels=1)
    rotten, _ = apply_defects(pear, ["rot:at=ring8/sector3"])
    grid = L.coloured_grid(rotten)
    facing = L.defect_direction(L.whole_marked(grid), np.asarray(grid.center, float))
    kw = {"size": (400, 400), "view": facing, "legend": False, "decorations": False}
    L.render_png(pear, tmp_path / "clean.png", **kw)
    L.render_png(rotten, tmp_path / "rot.png", **kw)
    clean, img = _pixels(tmp_path / "clean.png"), _pixels(tmp_path / "rot.png")
    lesion = _largest(np.abs(img - clean).sum(axis=2) > 60)
    roundness, (cy, cx) = _roundness(lesion)
    assert roundness >= 0.8  # the old patch of rot cells: a square
    ys, xs = np.nonzero(lesion)
    reach = np.hypot(ys - cy, xs - cx)
    radius = reach.max()
    lum = img[lesion].sum(axis=1)
    inner, rim = lum[reach < 0.35 * radius], lum[(reach > 0.6 * radius) & (reach < 0.8 * radius)]
    assert np.median(rim) < 0.85 * np.median(inner)  # the water-soaked rim is darker
    brown = np.array(hex_rgb(ROT["brown"]), float)
    centre = img[lesion][reach < 0.5 * radius]
    chroma = centre / centre.sum(axis=1, keepdims=True)
    assert np.median(np.abs(chroma - brown / brown.sum()).sum(axis=1)) < 0.12  # brown
    mould = np.array(hex_rgb(ROT["mould"]), float)
    grey = (np.abs(centre / centre.sum(axis=1, keepdims=True) - mould / mould.sum()).sum(axis=1) < 0.04) & (
        centre.sum(axis=1) > 0.7 * mould.sum()
    )
    assert grey.sum() > 20  # grey-white mould colonies


def test_round_mark_colours():
    skin = np.tile(np.array(hex_rgb("#c81e1e"), float), (4, 1))
    u = np.array([0.0, 0.5, 1.0, 3.0])
    assert mark_weight(u).tolist() == pytest.approx([1.0, 1.0, 0.5, 0.0])
    healed = round_mark_rgb(skin, "hail", u, healed=True)
    assert np.abs(healed[0] - hex_rgb(CORK)).max() < 20  # corky brown at the centre
    assert healed[3] == pytest.approx(skin[3])  # nothing far away
    fresh = round_mark_rgb(skin, "hail", u, healed=False)
    assert fresh[0].sum() < skin[0].sum() and fresh[0][1] < healed[0][1]  # darker, not corky
    with pytest.raises(Exception, match="hail or rot"):
        round_mark_rgb(skin, "crack", u)


def test_subdivision_keeps_the_surface_closed_and_its_area():
    import pyvista as pv

    sphere = pv.Sphere(theta_resolution=12, phi_resolution=8).triangulate().clean()
    tris = np.asarray(sphere.faces).reshape(-1, 4)[:, 1:]
    pts, fine, parent, normals = M.subdivide(sphere.points, tris, 2, np.asarray(sphere.point_normals))
    assert len(fine) == 16 * len(tris) and np.bincount(parent).tolist() == [16] * len(tris)
    edges = np.unique(np.sort(np.concatenate([fine[:, [0, 1]], fine[:, [1, 2]], fine[:, [2, 0]]]), axis=1), axis=0)
    assert len(pts) - len(edges) + len(fine) == 2  # Euler characteristic of a sphere: no cracks
    area = 0.5 * np.linalg.norm(np.cross(pts[fine[:, 1]] - pts[fine[:, 0]], pts[fine[:, 2]] - pts[fine[:, 0]]), axis=1).sum()
    assert area == pytest.approx(sphere.area, rel=1e-9)  # midpoints stay on the faces
    assert np.linalg.norm(normals, axis=1) == pytest.approx(np.ones(len(pts)))


def test_a_fruit_without_round_marks_is_left_as_it_is():
    gm = build_fruit("apple", volume_levels=1)
    damaged, _ = apply_defects(gm, ["crack:healed=1,rings=8-9,sector=2"])
    grid = L.coloured_grid(damaged, round_marks=True)
    surface = L.coloured_surface(grid)
    assert M.draw_round_marks(surface, np.asarray(grid.center, float)) is surface


def test_batch_masks_of_round_marks_are_the_drawn_discs():
    """``ramure fruit batch``: a hail pit's and a rot lesion's masks are the round marks the
    pictures show, not their cells' squares (whose corners are plain skin)."""
    from ramure.app import fruit_dataset as F
    from ramure.app.fruit_views import rle_decode

    recipe = F.random_recipe(F.fruit_rng(1, 0))
    hail = {"count": 2, "depth_mm": (2.0, 3.0), "stop": "mesocarp"}
    recipe.update(malform=None, defects=[("hail", hail), ("rot", {"rate": 0.3})])
    clean, damaged, labels = F.build_one(recipe)
    try:
        records, pictures, cleans, grid = F.render_views(0, 1, clean, damaged, labels, 65.0, 4, "plain", (256, 256))
    finally:
        F.close_plotter()  # no GL context left open in this process for a later batch's workers
    assert "rgb_plain" not in grid.cell_data  # the written grid is as before
    checked = set()
    for record, img, ref in zip(records, pictures, cleans):
        strong = np.abs(img.astype(int) - ref.astype(int)).max(axis=2) > 60
        for d in record["defects"]:
            mask = rle_decode(d["segmentation"])
            if mask.sum() < 100:
                continue
            px = img[mask].astype(float)
            if d["kind"] == "hail":  # a fresh pit: dark bruise; cell masks: 0.69 and 0.78 here
                assert strong[mask].mean() >= 0.95
            elif d["kind"] == "rot":  # brown, not red skin; cell masks: 0.78 and 0.83 here
                assert (px[:, 1] > 0.4 * px[:, 0]).mean() >= 0.95
            checked.add(d["kind"])
    assert checked == {"hail", "rot"}


def test_a_rot_lesion_on_a_curved_banana_is_found_and_drawn():
    """The banana's skin is far from radial: every outer face of an uncut, uncracked fruit is skin."""
    banana = build_fruit("banana", volume_levels=1, ripeness="yellow")
    rotten, _ = apply_defects(banana, ["rot:at=ring6/sector1"])
    grid = L.coloured_grid(rotten, round_marks=True)
    surface = L.coloured_surface(grid)
    centre = np.asarray(grid.center, float)
    (disc,) = M.mark_discs(surface, centre)  # none when skin had to face away from the centre
    skin = surface.compute_cell_sizes(length=False, volume=False)
    rot = np.asarray(surface.cell_data["rot"]) > 0
    assert np.pi * disc.radius**2 == pytest.approx(float(np.asarray(skin.cell_data["Area"])[rot].sum()))
    drawn = M.draw_round_marks(surface, centre)
    brown = np.array(hex_rgb(ROT["brown"]), float)
    mids = np.asarray(drawn.cell_centers().points)
    inner = np.linalg.norm(mids - disc.centre, axis=1) < 0.3 * disc.radius
    colours = np.asarray(drawn.cell_data["rgb"], float)[inner]
    assert inner.sum() > 100 and np.median(np.abs(colours - brown).max(axis=1)) < 40  # brown, not yellow
