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
        one = one.subdivide(1, "loop")
        return one, from_polydata(one)
    except GMapError as err:
        raise ValueRefused(f"the fruit's surface cannot carry lichen or cracks: {err}") from None


def diagonal(poly) -> float:
    """Length of the bounding-box diagonal of a pyvista dataset."""
    return float(np.linalg.norm(np.subtract(*np.reshape(poly.bounds, (3, 2)).T)))


def lichen_on_fruit(ex, clusters=5, particles=300, habit="crustose", seed=0):
    """Grow lichen on the selected fruit; returns a dict with surface, discs and facts."""
    from ramure.gmap.lichen import age_classes, grow_lichen, to_polydata

    poly, mesh = selected_fruit_surface(ex)
    if not 1 <= clusters <= particles:
        raise ValueRefused(f"need 1 <= clusters <= particles, not {clusters} clusters for {particles} particles")
    growth = grow_lichen(mesh, clusters=clusters, particles=particles, r=diagonal(poly) / 120, habit=habit,
                         seed=seed)
    discs = to_polydata(growth, mesh, lift=growth.r * 0.2)
    per_disc = discs.n_cells // max(growth.count, 1)
    discs.cell_data["rgb"] = np.repeat(AGE_RGB[age_classes(growth, 3)], per_disc, axis=0)
    return {"surface": poly, "discs": discs, "facts": {"triangles": len(mesh.triangles), "habit": habit,
                                                       **growth.facts()}}


def crack_on_fruit(ex, nodes=15, seed=0):
    """Carve a random crack pattern into the selected fruit from its top; dict with result and facts."""
    from ramure.gmap.cracks import carve, random_pattern

    poly, mesh = selected_fruit_surface(ex)
    if not 2 <= nodes <= 500:
        raise ValueRefused(f"a crack needs 2..500 nodes, not {nodes}")
    d = diagonal(poly)
    pattern = random_pattern(nodes, seed=seed, length=d / 25, width=d / 80, depth=d / 40)
    b = poly.bounds
    anchor = ((b[0] + b[1]) / 2, (b[2] + b[3]) / 2, b[5])
    crack = carve(mesh, pattern, anchor, (1.0, 0.0, 0.0))
    return {"surface": crack.result, "facts": crack.facts(), "points": crack.points}
