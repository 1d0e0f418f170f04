"""Lichen and cracks on the selected fruit, leaves by season: the work behind the Details panels.

Shared by the desktop's Details dock and the Jupyter Details tab (no Qt, no widgets): each
function takes a :class:`ramure.app.model.Explorer` and returns what the panel shows.

Sizes chosen here (the issue is silent): lichen particle radius = fruit diagonal / 120;
crack arcs = diagonal / 25 long, profiles diagonal / 80 wide and diagonal / 40 deep, carved
from the top of the fruit along +x.  The fruit's surface (from
:meth:`~ramure.app.model.Explorer.fruit_surface`, 122 quads for a round tomato) is split into
triangles and loop-subdivided once, so a crack has triangles to cut and lichen discs sit on a
rounder skin.
"""
from __future__ import annotations

import numpy as np

from ramure.errors import ValueRefused

AGE_RGB = np.array([[107, 128, 77], [153, 173, 92], [204, 209, 128]], np.uint8)  # old inside .. young rim


def season_at(season, step):
    """The :class:`~ramure.lsys.seasons.Season` as it was at ``step``: leaves fallen later are
    still attached (no landing point yet)."""
    from ramure.lsys.seasons import Season

    down = season.fallen & (season.fall_step <= step)
    ground = np.where(down[:, None], season.ground, np.nan)
    return Season(season.leaf_ids, season.states[:step + 1], down, np.where(down, season.fall_step, -1), ground,
                  season.motif)


def selected_fruit_surface(ex):
    """The first selected fruit's closed surface as (PolyData, TriMesh); refusals name the fix."""
    from ramure.gmap.errors import GMapError
    from ramure.gmap.trimesh import from_polydata

    fruit = ex.fruit_ids()
    if not fruit:
        raise ValueRefused("this plant has no fruit: lichen and cracks grow on a fruit's closed surface "
                           "(try grammars/fruit_tree.lsys)")
    chosen = [leaf for leaf in ex.selection if leaf in set(fruit)]
    if not chosen:
        raise ValueRefused("select a fruit first (click one): lichen and cracks grow on its closed surface")
    surface = ex.fruit_surface()
    cells = np.flatnonzero(np.asarray(surface.cell_data["leaf_id"]) == chosen[0])
    one = surface.extract_cells(cells).extract_surface(algorithm="dataset_surface").triangulate().clean()
    try:
        from_polydata(one)  # refuses an open or non-manifold surface before subdividing
        mesh = from_polydata(one.subdivide(1, "loop"))
    except GMapError as err:
        raise ValueRefused(f"the fruit's surface cannot carry lichen or cracks: {err}") from None
    import pyvista as pv

    faces = np.hstack([np.full((len(mesh.triangles), 1), 3), mesh.triangles]).ravel()
    return pv.PolyData(mesh.points.copy(), faces), mesh  # the same points: painted maps fit both


def diagonal(poly) -> float:
    """Length of the bounding-box diagonal of a pyvista dataset."""
    return float(np.linalg.norm(np.subtract(*np.reshape(poly.bounds, (3, 2)).T)))


def lichen_on_fruit(ex, clusters=5, particles=300, habit="crustose", seed=0, adhesion=None):
    """Grow lichen on the selected fruit; returns a dict with surface, discs and facts.

    ``adhesion`` (per vertex of the fruit's surface, [0, 1]; see :func:`paint_adhesion`) is
    where clusters may start: the painted probability of keeping a seed.
    """
    from ramure.gmap.lichen import age_classes, grow_lichen, to_polydata

    poly, mesh = selected_fruit_surface(ex)
    if not 1 <= clusters <= particles:
        raise ValueRefused(f"need 1 <= clusters <= particles, not {clusters} clusters for {particles} particles")
    if adhesion is not None and len(adhesion) != poly.n_points:
        raise ValueRefused(f"the painted adhesion has {len(adhesion)} values for a fruit of {poly.n_points} "
                           "vertices: paint this fruit again")
    growth = grow_lichen(mesh, clusters=clusters, particles=particles, r=diagonal(poly) / 120, habit=habit,
                         adhesion=adhesion, seed=seed)
    discs = to_polydata(growth, mesh, lift=growth.r * 0.2)
    per_disc = discs.n_cells // max(growth.count, 1)
    discs.cell_data["rgb"] = np.repeat(AGE_RGB[age_classes(growth, 3)], per_disc, axis=0)
    facts = {"triangles": len(mesh.triangles), "habit": habit, "painted": adhesion is not None, **growth.facts()}
    return {"surface": poly, "fruit": poly, "discs": discs, "facts": facts}


def crack_on_fruit(ex, nodes=15, seed=0, anchor=None):
    """Carve a random crack pattern into the selected fruit from ``anchor`` (default: its top);
    dict with the carved surface, the uncarved ``fruit`` and facts."""
    from ramure.gmap.cracks import carve, random_pattern

    poly, mesh = selected_fruit_surface(ex)
    if not 2 <= nodes <= 500:
        raise ValueRefused(f"a crack needs 2..500 nodes, not {nodes}")
    d = diagonal(poly)
    pattern = random_pattern(nodes, seed=seed, length=d / 25, width=d / 80, depth=d / 40)
    b = poly.bounds
    if anchor is None:
        anchor = ((b[0] + b[1]) / 2, (b[2] + b[3]) / 2, b[5])
    anchor = np.asarray(anchor, np.float64)
    if anchor.shape != (3,) or not np.isfinite(anchor).all():
        raise ValueRefused("the crack's anchor must be a point (x, y, z)")
    if np.linalg.norm(np.asarray(poly.points) - anchor, axis=1).min() > 0.05 * diagonal(poly):
        raise ValueRefused("the crack's anchor is off the fruit's surface: click on the fruit")
    crack = carve(mesh, pattern, anchor, (1.0, 0.0, 0.0))
    return {"surface": crack.result, "fruit": poly, "facts": crack.facts(), "points": crack.points}


def paint_adhesion(points, adhesion, centre, radius):
    """One brush dab: adhesion rises to 1 at ``centre`` and smoothly to 0 at ``radius`` (never lowered).

    ``adhesion`` is None (nothing painted yet: all 0) or an array per point; returns a new array.
    """
    points = np.asarray(points, np.float64)
    if not (np.isfinite(radius) and radius > 0):
        raise ValueRefused(f"the brush radius must be > 0, not {radius}")
    base = np.zeros(len(points)) if adhesion is None else np.asarray(adhesion, np.float64)
    d = np.linalg.norm(points - np.asarray(centre, np.float64), axis=1) / radius
    dab = np.where(d < 1, (1 - d**2) ** 2, 0.0)
    return np.maximum(base, dab)
