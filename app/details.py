"""Lichen and cracks on the selected fruit, lichen on the plant's or the wood's bark, leaves by
season: the work behind the Details panels and ``ramure lichen --on-plant / --on-wood``.

Shared by the desktop's Details dock and the Jupyter Details tab (no Qt, no widgets): each
function takes a :class:`ramure.app.model.Explorer` and returns what the panel shows.

Sizes chosen here (the issue is silent): lichen particle radius = fruit diagonal / 80 (at / 120
the default 300 particles covered 3 % of a fruit, too little to see: issue 40);
crack arcs = diagonal / 25 long, profiles diagonal / 80 wide and diagonal / 40 deep, carved
from the top of the fruit along +x.  The fruit's surface (from
:meth:`~ramure.app.model.Explorer.fruit_surface`, 122 quads for a round tomato) is split into
triangles and loop-subdivided once, so a crack has triangles to cut and lichen discs sit on a
rounder skin.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ramure.errors import ValueRefused

if TYPE_CHECKING:
    import pyvista as pv
    from ramure.app.model import Explorer
    from ramure.gmap.organs.lichen import Lichen
    from ramure.gmap.organs.trimesh import TriMesh
    from ramure.gmap.organs.wood import Wood
    from ramure.lsys.architecture.seasons import Season
    from ramure.lsys.interpretation.turtle import Skeleton

AGE_RGB = np.array([[107, 128, 77], [153, 173, 92], [204, 209, 128]], np.uint8)  # old inside .. young rim


def season_at(season: Season, step: int) -> Season:
    """The :class:`~ramure.lsys.architecture.seasons.Season` as it was at ``step``: leaves fallen later are
    still attached (no landing point yet)."""
    import dataclasses

    down = season.fallen & (season.fall_step <= step)
    ground = np.where(down[:, None], season.ground, np.nan)
    fall_step = np.where(down, season.fall_step, -1)
    return dataclasses.replace(season, states=season.states[: step + 1], fallen=down, fall_step=fall_step, ground=ground)


def selected_fruit_surface(ex: Explorer) -> tuple[pv.PolyData, TriMesh]:
    """The first selected fruit's closed surface as (PolyData, TriMesh); refusals name the fix."""
    from ramure.gmap.kernel.errors import GMapError
    from ramure.gmap.organs.trimesh import from_polydata

    fruit = ex.fruit_ids()
    if not fruit:
        raise ValueRefused(
            "this plant has no fruit: lichen and cracks grow on a fruit's closed surface (try grammars/fruit_tree.lsys)"
        )
    chosen = [leaf for leaf in ex.selection if leaf in set(fruit)]
    if not chosen:
        raise ValueRefused("select a fruit first (click one): lichen and cracks grow on its closed surface")
    surface = ex.fruit_surface()
    assert surface is not None  # the plant has fruit
    cells = np.flatnonzero(np.asarray(surface.cell_data["leaf_id"]) == chosen[0])
    part = surface.extract_cells(cells)  # type: ignore[arg-type]  # pyvista types index arrays as NDArray[int]
    one = part.extract_surface(algorithm="dataset_surface").triangulate().clean()
    try:
        from_polydata(one)  # refuses an open or non-manifold surface before subdividing
        mesh = from_polydata(one.subdivide(1, "loop"))
    except GMapError as err:
        raise ValueRefused(f"the fruit's surface cannot carry lichen or cracks: {err}") from None
    import pyvista as pv

    faces = np.hstack([np.full((len(mesh.triangles), 1), 3), mesh.triangles]).ravel()
    return pv.PolyData(mesh.points.copy(), faces), mesh  # the same points: painted maps fit both


def diagonal(poly: pv.DataSet) -> float:
    """Length of the bounding-box diagonal of a pyvista dataset."""
    return float(np.linalg.norm(np.subtract(*np.reshape(poly.bounds, (3, 2)).T)))


def lichen_on_fruit(
    ex: Explorer,
    clusters: int = 5,
    particles: int = 300,
    habit: str = "crustose",
    seed: int = 0,
    adhesion: np.ndarray | None = None,
) -> dict:
    """Grow lichen on the selected fruit; returns a dict with surface, discs and facts.

    ``adhesion`` (per vertex of the fruit's surface, [0, 1]; see :func:`paint_adhesion`) is
    where clusters may start: the painted probability of keeping a seed.
    """
    from ramure.gmap.organs.lichen import age_classes, grow_lichen, to_polydata

    poly, mesh = selected_fruit_surface(ex)
    if not 1 <= clusters <= particles:
        raise ValueRefused(f"need 1 <= clusters <= particles, not {clusters} clusters for {particles} particles")
    if adhesion is not None and len(adhesion) != poly.n_points:
        raise ValueRefused(
            f"the painted adhesion has {len(adhesion)} values for a fruit of {poly.n_points} vertices: paint this fruit again"
        )
    growth = grow_lichen(
        mesh, clusters=clusters, particles=particles, r=diagonal(poly) / 80, habit=habit, adhesion=adhesion, seed=seed
    )
    discs = to_polydata(growth, mesh, lift=growth.r * 0.2)
    per_disc = discs.n_cells // max(growth.count, 1)
    discs.cell_data["rgb"] = np.repeat(AGE_RGB[age_classes(growth, 3)], per_disc, axis=0)
    facts = {"triangles": len(mesh.triangles), "habit": habit, "painted": adhesion is not None, **growth.facts()}
    return {"surface": poly, "fruit": poly, "discs": discs, "facts": facts, "growth": growth, "mesh": mesh}


def plant_bark(skeleton: Skeleton, thinnest: float = 0.1) -> tuple[pv.PolyData, TriMesh]:
    """A derived plant's bark as one closed surface (PolyData, TriMesh) for lichen.

    The plant's own tubes are open rings, so the segments are welded into a closed surface
    (:func:`ramure.gmap.organs.trimesh.tubes_surface`). Twigs thinner than ``thinnest`` times the
    thickest segment's radius are left out (lichen grows on older wood; welding a thousand
    twigs costs seconds and triangles for no lichen).
    """
    from ramure.gmap.organs.trimesh import tubes_surface

    if not 0 <= thinnest < 1:
        raise ValueRefused(f"thinnest must be a fraction in [0, 1), not {thinnest}")
    if len(skeleton) == 0:
        raise ValueRefused("this plant has no branch segment: no bark for lichen to grow on")
    radius = np.maximum(skeleton.base_radius, skeleton.top_radius)
    keep = np.flatnonzero(radius >= thinnest * radius.max())
    remap = np.full(len(radius), -1, np.int64)
    remap[keep] = np.arange(len(keep))
    parent = np.asarray(skeleton.parent, np.int64)[keep]
    parent = np.where(parent >= 0, remap[np.maximum(parent, 0)], -1)
    mesh = tubes_surface(skeleton.start[keep], skeleton.end[keep], skeleton.base_radius[keep], skeleton.top_radius[keep], parent)
    return _poly(mesh), mesh


def wood_bark(wood: Wood) -> tuple[pv.PolyData, TriMesh]:
    """A volumetric wood's skin (bark and cut ends) as (PolyData, TriMesh), over the map's
    own vertices (:class:`ramure.gmap.organs.mapcracks.Skin`)."""
    from ramure.gmap.organs.mapcracks import Skin

    mesh = Skin(wood.gm).mesh
    return _poly(mesh), mesh


def _poly(mesh):
    import pyvista as pv

    faces = np.hstack([np.full((len(mesh.triangles), 1), 3), mesh.triangles]).ravel()
    return pv.PolyData(mesh.points.copy(), faces)


def cover_radius(mesh: TriMesh, particles: int, cover: float = 0.1) -> float:
    """The particle radius at which ``particles`` discs would cover ``cover`` of the surface.

    On bark the size of the model says little (a tall thin trunk, a plant of thin branches):
    sized by area, the lichen never runs out of room, where every emitter would burn its
    tokens on walks that cannot join (the growth then slows down a hundredfold).
    """
    return float(np.sqrt(cover * mesh.area() / (np.pi * max(int(particles), 1))))


def lichen_on_surface(
    poly: pv.PolyData,
    mesh: TriMesh,
    clusters: int = 26,
    particles: int = 2000,
    habit: str = "crustose",
    seed: int = 0,
    r: float | None = None,
    adhesion: np.ndarray | None = None,
) -> dict:
    """Grow lichen on a closed surface; dict with surface, discs (coloured by age class) and facts.

    ``r`` defaults to :func:`cover_radius` (a tenth of the surface covered).
    """
    from ramure.gmap.organs.lichen import age_classes, grow_lichen, to_polydata

    if not 1 <= clusters <= particles:
        raise ValueRefused(f"need 1 <= clusters <= particles, not {clusters} clusters for {particles} particles")
    r = cover_radius(mesh, particles) if r is None else r
    growth = grow_lichen(mesh, clusters=clusters, particles=particles, r=r, habit=habit, adhesion=adhesion, seed=seed)
    discs = to_polydata(growth, mesh, lift=growth.r * 0.2)
    per_disc = discs.n_cells // max(growth.count, 1)
    discs.cell_data["rgb"] = np.repeat(AGE_RGB[age_classes(growth, 3)], per_disc, axis=0)
    facts = {"triangles": len(mesh.triangles), "habit": habit, "r": float(r), **growth.facts()}
    return {"surface": poly, "discs": discs, "facts": facts, "growth": growth, "mesh": mesh}


def close_up(growth: Lichen, mesh: TriMesh) -> list:
    """A camera position looking at the largest lichen cluster from outside, its extent about a
    third of the picture (on bark the lichen is small against the whole plant)."""
    biggest = np.bincount(growth.cluster).argmax()
    members = growth.cluster == biggest
    centre = growth.position[members].mean(axis=0)
    extent = max(float(np.ptp(growth.position[members], axis=0).max()), 10 * growth.r)
    outward, up = _looking_out(mesh, growth.triangle[members])
    return [tuple(centre + outward * extent * 3.2 + up * extent * 0.6), tuple(centre), tuple(up)]


def litter_polydata(season: Season, colors: np.ndarray, step: int = -1, size: float = 0.12) -> pv.PolyData:
    """The fallen leaves at ``step`` as curled blades on compacted piles
    (:func:`ramure.lsys.architecture.seasons.litter`), each triangle coloured by its leaf's state then
    (``colors``, the chain's RGB in [0, 1], as ``rgb`` cell data) and carrying its ``leaf_id``."""
    import pyvista as pv

    from ramure.lsys.architecture.seasons import litter

    step = len(season.states) - 1 if step < 0 else step
    points, triangles, leaf = litter(season, step, size)
    faces = np.column_stack([np.full(len(triangles), 3), triangles]).ravel()
    mesh = pv.PolyData(points, faces)
    mesh.cell_data["rgb"] = np.round(colors[season.states[step][leaf]] * 255).astype(np.uint8)
    mesh.cell_data["leaf_id"] = season.leaf_ids[leaf]
    return mesh


def facing(growth: Lichen, mesh: TriMesh) -> list:
    """A camera that shows the whole surface from the side where its lichen grows: along the
    particles' mean outward normal, far enough for the surface to fill about two thirds of the
    picture.  A fixed camera sees the far side of the fruit half the time, and the lichen with it."""
    outward, up = _looking_out(mesh, growth.triangle)
    lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
    centre, radius = (lo + hi) / 2, float(np.linalg.norm(hi - lo)) / 2
    side = np.cross(outward, up)
    eye = centre + (outward + 0.25 * side + 0.2 * up) * radius * 2.6
    return [tuple(eye), tuple(centre), tuple(up)]


def _looking_out(mesh: TriMesh, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The unit mean outward normal of ``triangles`` and an up vector not along it (z, else y)."""
    outward = mesh.normals[triangles].mean(axis=0)
    outward /= max(np.linalg.norm(outward), 1e-12)
    up = np.array([0.0, 0.0, 1.0]) if abs(outward[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    return outward, up


def crack_on_fruit(ex: Explorer, nodes: int = 15, seed: int = 0, anchor: Any = None) -> dict:
    """Carve a random crack pattern into the selected fruit from ``anchor`` (default: its top);
    dict with the carved surface, the uncarved ``fruit`` and facts."""
    from ramure.gmap.organs.cracks import carve, random_pattern

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


def paint_adhesion(points: ArrayLike, adhesion: ArrayLike | None, centre: ArrayLike, radius: float) -> np.ndarray:
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
