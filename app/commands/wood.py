"""``ramure wood``: grow volumetric wood (3G-map), cut it, print its facts, write a picture or a grid.

Examples::

    ramure wood --species pine --years 10 --json
    ramure wood --years 12 --cut z=1.0 -o slice.png
    ramure wood --years 12 --plank normal=x,offset=0.01,thickness=0.004 -o plank.png
    ramure wood --grammar grammars/wood/trunk.g3l --years 4 -o trunk.vtu
    ramure wood --from-plant grammars/abop_tree.lsys -n 6 --years 8 -o tree.glb

JSON keys: species, years, steps (half-years), seed, darts, volumes, tissues (volumes per tissue),
branches (``{"live": n, "dead": m}``: knots grown, alive and dead; ``--set branch_life=N`` kills a
branch N years after its birth), knots_by_order (``{"1": n1, "2": n2, ...}``: knots in the trunk, in
first-order branches, ...), left_out (with ``--from-plant``: the plant's branches not in the wood, by
reason: last_year, too_close, beyond_stub -- born after their host's stub of ``branch_levels`` levels
ended; ``--set branch_levels=0`` keeps whole branches --, host_dead, over_max, on_left_out),
bark_mm (the trunk's thickest and mean bark), bark_shed (shed bark cells), reaction (compression
and tension wood volumes), rings and knots (live_knots, dead_knots) at the cut or plank (when one is
asked for), chi, boundary_chi, valid, seconds (growth + checks), darts_per_second, output.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import time

import numpy as np
from numpy.typing import ArrayLike

from ramure.app.cli import UserError
from ramure.app.commands.plant import parse_size
from ramure.io import write_with
import os
from collections.abc import Callable, Iterable, Sequence
from typing import Any
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ramure.app.cli import Subparsers
    import pyvista as pv
    from ramure.gmap.lsystem.engine import G3LDerivation
    from ramure.gmap.organs.wood import Wood

SUFFIXES = (".vtu", ".png", ".glb", ".gltf", ".obj")
DEFAULT_YEARS = 10


def write_atomic(path: str | os.PathLike, writer: Callable[[str], object]) -> pathlib.Path:
    """Call ``writer(tmp_path)`` on a temporary file next to ``path``, fsync it, rename it to ``path``
    (:func:`ramure.io.write_with`; the folder is created first)."""
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_with(path, writer)


def render_wood(
    grid: pv.DataSet,
    path: str | os.PathLike,
    size: tuple[int, int] = (900, 900),
    look: ArrayLike | None = None,
    title: str | None = None,
    legend: Sequence[tuple[str, Any]] | None = None,
    background: str = "white",
) -> str | os.PathLike:
    """Render a wood grid (cell data ``rgb``) off-screen to PNG; ``look`` is the viewing direction."""
    from ramure.app.render import headless_setup

    headless_setup()
    import pyvista as pv

    plotter = pv.Plotter(off_screen=True, window_size=list(size))
    plotter.set_background(background)  # type: ignore[arg-type]  # pyvista stubs: decorated method
    add_wood_actors(plotter, grid, legend)
    b = np.asarray(grid.bounds, float).reshape(3, 2)
    centre = b.mean(axis=1)
    extent = float(np.max(b[:, 1] - b[:, 0])) or 1.0
    d = np.array([0.6, -0.7, 0.5]) if look is None else np.asarray(look, float)
    d = d / np.linalg.norm(d)
    up = (0.0, 0.0, 1.0) if abs(d[2]) < 0.95 else (0.0, 1.0, 0.0)
    plotter.camera_position = [tuple(centre + d * extent * 3.0), tuple(centre), up]
    plotter.reset_camera(bounds=tuple(b.ravel()))  # type: ignore[call-arg]  # pyvista stubs: decorated method
    plotter.camera.zoom(1.15)
    if title:
        plotter.add_text(title, font_size=10, color="black")
    plotter.screenshot(str(path))
    plotter.close()
    return path


def render_plank(
    part: pv.DataSet,
    path: str | os.PathLike,
    normal: ArrayLike,
    size: tuple[int, int] = (900, 900),
    title: str | None = None,
    legend: Sequence[tuple[str, Any]] | None = None,
    species: str | None = None,
) -> str | os.PathLike:
    """Render a length of plank face-on to PNG: the trunk axis across the picture, the board filling it.

    A parallel projection looks at the face nearer the pith (at the plank's
    offset), unlit so the colours are the tissues'; the length runs left to right.
    The board fills the picture but for the title's band and the legend's box
    (:func:`plank_view`): neither covers wood.
    With ``species`` (and the part's ``wood`` and ``season`` cell
    data) the face is drawn at one point a pixel with the species' pores,
    resin canals and rays (:func:`ramure.gmap.organs.wood_species.texture_face`).
    """
    from ramure.app.render import headless_setup

    headless_setup()
    import pyvista as pv

    w, h = size
    surface = part.extract_surface(algorithm="dataset_surface")
    (position, focal, up, scale), legend_at = plank_view(surface, normal, size, legend, title)
    plotter = pv.Plotter(off_screen=True, window_size=list(size))
    plotter.set_background("white")  # type: ignore[arg-type]  # pyvista stubs: decorated method
    plotter.add_mesh(surface, scalars="rgb", rgb=True, lighting=False, name="plank")
    if species is not None and all(k in part.cell_data for k in ("wood", "season")):
        from ramure.gmap.organs.wood import CODES
        from ramure.gmap.organs.wood_species import texture_face

        face = texture_face(part, normal, species, pixel=2.0 * scale / h, codes=CODES, up=up)
        if face.n_points:
            plotter.add_mesh(face, scalars="rgb", rgb=True, lighting=False, name="texture")
    plotter.enable_parallel_projection()  # type: ignore[call-arg]  # pyvista stubs: decorated method
    plotter.camera_position = [tuple(position), tuple(focal), tuple(up)]
    plotter.camera.parallel_scale = scale
    distance = float(np.linalg.norm(position - focal))
    plotter.camera.clipping_range = (distance * 0.5, distance * 1.5)
    if legend:
        add_legend_box(plotter, legend, legend_at)
    if title:
        plotter.add_text(title, font_size=10, color="black")
    plotter.screenshot(str(path))
    plotter.close()
    return path


TITLE_PX = 30
"""Pixels kept free at the top of a plank picture for its title (``add_text`` at font size 10 is 10 to 18 px
high from 300 to 1400 px pictures, from 5 px down)."""
EDGE = 0.02
"""The legend box's distance from the picture's right and bottom edges, a fraction of the picture."""


Camera = tuple[np.ndarray, np.ndarray, np.ndarray, float]
"""``(position, focal point, view up, parallel scale)``, as :func:`~ramure.gmap.organs.wood.plank_camera` gives."""


def plank_view(
    surface: pv.PolyData,
    normal: ArrayLike,
    size: tuple[int, int],
    legend: Sequence[tuple[str, Any]] | None = None,
    title: str | None = None,
) -> tuple[Camera, tuple[float, float] | None]:
    """The camera of a ``size`` picture of a plank's ``surface`` and where its legend's box goes (its lower
    left corner, fractions of the picture; ``None`` without a legend), so that neither the legend nor the
    title covers wood.

    The title keeps a band of :data:`TITLE_PX` at the top.  The legend's box
    (:func:`legend_box_size`) goes to the lower right with the board above it
    or beside it, or over an empty corner of the board's box (lower or upper
    right: a quarter-sawn board's branch rising from it leaves one), the board
    then smaller in steps of 5 % down to 70 % if needs be.  Of the places
    where the box, grown by :data:`EDGE`, meets none of the surface's
    triangles, the one that leaves the board largest wins (the first listed on
    a tie: below, beside, over).  Without a legend the board fills the
    picture under the title.
    """
    from ramure.gmap.organs.wood import plank_camera

    w, h = size
    top = 1.0 - TITLE_PX / h if title else 1.0
    if not legend:
        return plank_camera(surface.points, normal, w / h, (0.0, 0.0, 1.0, top)), None
    box_w, box_h = legend_box_size(legend)
    solid = surface.triangulate()
    triangles = np.asarray(solid.points)[solid.regular_faces]
    cameras = [(plank_camera(surface.points, normal, w / h, window), at) for window, at in legend_places(box_w, box_h, top)]
    for camera, at in sorted(cameras, key=lambda pair: pair[0][3]):  # the largest board first; ties as listed
        box = (at[0] - EDGE, at[1] - EDGE, at[0] + box_w + EDGE, at[1] + box_h + EDGE)
        if not hits_box(on_view(triangles, camera, w / h), box):
            return camera, at
    return cameras[0]  # below the board, whose window the box never meets


def legend_places(box_w: float, box_h: float, top: float) -> list[tuple[tuple[float, float, float, float], tuple[float, float]]]:
    """``(window, legend box's lower left corner)`` pairs to try, fractions of the picture: below the board,
    beside it, then over the lower or upper right corner of its window, shrunk from 1 to 0.7 in steps of
    0.05 away from the box.  ``top`` is the title band's lower edge."""
    lower, upper = (1.0 - box_w - EDGE, EDGE), (1.0 - box_w - EDGE, min(top, 1.0 - EDGE) - box_h)
    places = [((0.0, box_h + 2 * EDGE, 1.0, top), lower), ((0.0, 0.0, 1.0 - box_w - 2 * EDGE, top), lower)]
    for shrink in (1.0, 0.95, 0.9, 0.85, 0.8, 0.75, 0.7):
        places.append(((0.0, top * (1.0 - shrink), shrink, top), lower))
        places.append(((0.0, 0.0, shrink, top * shrink), upper))
    return places


def on_view(points: np.ndarray, camera: Camera, aspect: float) -> np.ndarray:
    """``points`` (..., 3) as ``(x, y)`` fractions of a parallel view from its lower left corner."""
    position, focal, up, scale = camera
    look = (focal - position) / np.linalg.norm(focal - position)
    right = np.cross(look, up)
    offset = points - focal
    return np.stack([0.5 + offset @ right / (2 * scale * aspect), 0.5 + offset @ up / (2 * scale)], axis=-1)


def hits_box(triangles: np.ndarray, box: tuple[float, float, float, float]) -> bool:
    """Whether any of the 2D ``triangles`` (n, 3, 2) meets the box ``(x0, y0, x1, y1)``: none of the box's
    axes nor the triangle's edge normals separates them."""
    x0, y0, x1, y1 = box
    lo, hi = triangles.min(axis=1), triangles.max(axis=1)
    near = triangles[(hi[:, 0] >= x0) & (lo[:, 0] <= x1) & (hi[:, 1] >= y0) & (lo[:, 1] <= y1)]
    edges = np.roll(near, -1, axis=1) - near
    normals = np.stack([-edges[..., 1], edges[..., 0]], axis=-1)  # (m, 3, 2)
    ends = np.einsum("mkd,mjd->mkj", normals, near)  # each normal's projections of the triangle's corners
    corners = np.einsum("mkd,cd->mkc", normals, [[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    apart = (ends.max(axis=2) < corners.min(axis=2)) | (ends.min(axis=2) > corners.max(axis=2))
    return bool((~apart.any(axis=1)).any())


def add_wood_actors(
    plotter: pv.Plotter, grid: pv.DataSet, legend: Sequence[tuple[str, Any]] | None = None, name: str = "wood"
) -> pv.PolyData:
    """Add a wood grid to a plotter, coloured by its ``rgb`` cell data, with faint cell edges."""
    surface = grid.extract_surface(algorithm="dataset_surface")
    plotter.add_mesh(
        surface, scalars="rgb", rgb=True, show_edges=False, name=name, smooth_shading=False, ambient=0.35, diffuse=0.75
    )
    if legend:
        add_legend_box(plotter, legend)
    return surface


def add_legend_box(plotter: pv.Plotter, legend: Sequence[tuple[str, Any]], at: tuple[float, float] | None = None) -> None:
    """A legend that reads: dark text on a light box, each name after a swatch of its colour.

    ``at`` is the box's lower left corner (fractions of the picture); by default
    the box sits in the lower right corner, :data:`EDGE` from the edges.

    (pyvista's legend writes each name in its own colour: pale sapwood vanished on grey.)
    """
    from pyvista import Color

    box = plotter.add_legend(
        [[label, color] for label, color in legend],  # type: ignore[arg-type]  # pyvista: a decorated method reads as unbound
        bcolor=(0.96, 0.96, 0.94),
        border=True,
        face="rectangle",
    )
    width, height = legend_box_size(legend)
    box.SetPosition(*(at or (1.0 - width - EDGE, EDGE)))  # text scales to the box: size it to the names
    box.SetPosition2(width, height)
    for i, (label, color) in enumerate(legend):
        box.SetEntry(i, swatch(Color(color).int_rgb), label, (0.08, 0.08, 0.08))
        box.SetEntrySymbol(i, None)
    box.GetEntryTextProperty().SetColor(0.08, 0.08, 0.08)


def legend_box_size(legend: Sequence[tuple[str, Any]]) -> tuple[float, float]:
    """``(width, height)`` of a legend's box, fractions of the picture: wide enough for the longest name
    (at most 0.6), 0.04 high a line (at most 0.4)."""
    longest = max(len(label) for label, _ in legend)
    return min(0.6, 0.018 * longest + 0.05), min(0.4, 0.04 * len(legend) + 0.01)


def swatch(rgb: Sequence[int], size: int = 8) -> Any:
    """A ``size`` x ``size`` vtkImageData of one colour, a legend entry's icon."""
    import pyvista as pv

    image = pv.ImageData(dimensions=(size, size, 1))
    image.point_data["rgb"] = np.tile(np.asarray(rgb, np.uint8), (size * size, 1))
    image.point_data.active_scalars_name = "rgb"
    return image


def legend_for(species: str) -> list[tuple[str, Any]]:
    """The picture legend of a wood species: ``(tissue name, colour)`` for pith, heartwood, sapwood, bark and
    knots.
    """
    from ramure.gmap.organs.wood import SPECIES

    c = SPECIES[species]["colors"]
    return [
        ("pith", c["pith"]),
        ("heartwood, earlywood", c["heartwood"][0]),
        ("heartwood, latewood", c["heartwood"][1]),
        ("sapwood, earlywood", c["sapwood"][0]),
        ("sapwood, latewood", c["sapwood"][1]),
        ("inner bark", c["bark"][0]),
        ("bark plates" if SPECIES[species].get("bark_pattern") == "plates" else "bark ridges", c["bark"][1]),
        ("bark fissures", c["bark"][2]),
        ("knot (branch wood)", c["knot"][1]),
        (
            "compression wood" if SPECIES[species].get("kind") == "softwood" else "tension wood",
            _reaction_hex(species),
        ),
    ]


def _reaction_hex(species: str) -> str:
    """The colour of a species' reaction wood in a knot's latewood, as the pictures draw it."""
    from ramure.gmap.organs.wood import SPECIES
    from ramure.gmap.organs.wood_species import COMPRESSION, TENSION, reaction_rgb

    late = SPECIES[species]["colors"]["knot"][1]
    rgb = np.array([[int(late[i : i + 2], 16) for i in (1, 3, 5)]], float)
    mark = COMPRESSION if SPECIES[species].get("kind") == "softwood" else TENSION
    r, g, b = reaction_rgb(rgb, np.array([mark]))[0].astype(int)
    return f"#{r:02x}{g:02x}{b:02x}"


def parse_sets(pairs: Iterable[str]) -> dict[str, str]:
    """``--set NAME=VALUE`` options as a dict of strings (the wood builder parses the values); a pair without
    ``=`` or a name is a :class:`~ramure.errors.UserError`.
    """
    out = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        if not sep or not name.strip():
            raise UserError(f"--set expects NAME=VALUE, got '{pair}'")
        out[name.strip()] = value.strip()
    return out


def grow_from_args(args: argparse.Namespace) -> tuple[Wood | G3LDerivation, str | None]:
    """The grown model: a :class:`Wood` (species or plant) or a :class:`G3LDerivation` (grammar)."""
    from ramure.gmap.organs import wood as W

    if args.grammar:
        from ramure.gmap.lsystem.engine import G3LSystem

        if args.set:
            raise UserError("--set changes species parameters; edit the grammar's #define lines instead")
        system = G3LSystem.from_file(args.grammar)
        steps = system.grammar.steps if args.years is None else 2 * W.check_years(args.years)  # the file's #steps
        steps = 2 * DEFAULT_YEARS if steps is None else steps
        return system.derive(steps, seed=args.seed, check_every_step=True), None
    if args.years is None:
        args.years = DEFAULT_YEARS
    params: dict[str, Any] = parse_sets(args.set)  # strings: resolve_params converts them
    unknown = sorted(set(params) - set(W.PARAMETERS))
    if unknown:  # not only a typo: 'seed' or 'species' would collide with the grower's own arguments
        raise UserError(f"--set: unknown wood parameter '{unknown[0]}'; known: {', '.join(sorted(W.PARAMETERS))}")
    if args.from_plant:
        from ramure.lsys import LSystem

        ls = LSystem.from_file(args.from_plant)
        if args.n is not None and args.n < 0:
            raise UserError(f"-n must be >= 0, not {args.n}")
        d = ls.derive(n=args.n, seed=args.seed)
        return W.from_skeleton(
            d.skeleton(),
            W.check_years(args.years),
            species=args.species,
            seed=args.seed,
            steps=d.n,
            leaf_steps=d.tree.step,
            **params,
        ), args.species
    return W.grow_wood(args.species, args.years, seed=args.seed, check_every_step=True, **params), args.species


def _grid(model, species, convex=False):
    """The model as a grid; ``convex`` (for a .vtu) splits polyhedra so VTK measures them right."""
    from ramure.gmap.organs import wood as W
    from ramure.gmap.kernel.pyvista import to_unstructured_grid

    if species is not None:  # pictures get round rings; a .vtu keeps the kernel's cells
        return W.to_grid(model, convex=convex) if convex else W.smooth_grid(model, W.to_grid(model))
    grid = to_unstructured_grid(model.gm, convex=convex)
    labels = np.asarray(grid.cell_data["label"])
    palette = np.array([[214, 170, 110], [160, 105, 60], [110, 70, 40], [235, 210, 160], [90, 60, 35]], np.uint8)
    codes = {lab: i for i, lab in enumerate(sorted(set(labels.tolist())))}
    grid.cell_data["rgb"] = palette[np.array([codes[x] % len(palette) for x in labels], np.int64)]
    for name in ("axis", "wood", "year"):
        grid.cell_data[name] = np.full(grid.n_cells, -1)
    return grid


def run_wood(args: argparse.Namespace) -> int:
    """``ramure wood``: grow wood as a 3-G-map (a ``--species`` with ``--set`` values, or a ``.g3l``
    ``--grammar``), cut it by ``--cut`` or saw a ``--plank``, print its counts per tissue and write ``-o``
    (VTU grid, PNG or glTF/OBJ scene); returns 0."""
    plane, plank, out = _wood_request(args)
    t0 = time.perf_counter()
    model, species = grow_from_args(args)
    gm = model.gm
    report = {"valid": gm.is_valid(), "chi": gm.euler_characteristic(), "boundary_chi": gm.boundary().euler_characteristic()}
    seconds = time.perf_counter() - t0
    record = _wood_record(model, species, args)
    shown, look = None, None
    if plane or plank or out is not None:
        shown, look = _cut_or_saw(model, species, args, plane, plank, out, record)
    if args.years is None:  # a grammar's #steps: years as the steps say
        record["years"] = record["steps"] / 2
    record.update(report)
    record["seconds"] = round(seconds, 6)
    record["darts_per_second"] = round(gm.n_darts / max(seconds, 1e-9))
    if out is not None:
        assert shown is not None  # grown above whenever there is an output
        _write_wood(out, shown, look, plank, species, args, record)
        record["output"] = str(out)
    _say_wood(record, seconds, out, as_json=args.json)
    return 0 if report["valid"] else 1


def _wood_request(args: argparse.Namespace) -> tuple[Any, Any, pathlib.Path | None]:
    """The ``--cut`` plane, the ``--plank`` and the ``-o`` path, checked before anything grows."""
    from ramure.gmap.organs import wood as W
    from ramure.gmap.kernel.cut import parse_plane

    if args.species not in W.SPECIES:
        raise UserError(f"--species: unknown species '{args.species}'; choose one of {', '.join(W.SPECIES)}")
    plane = parse_plane(args.cut) if args.cut else None
    plank = W.parse_plank(args.plank) if args.plank else None
    if plane and plank:
        raise UserError("give --cut or --plank, not both")
    if (args.length is not None or args.at is not None) and not plank:
        raise UserError("--length and --at choose the part of a --plank to draw; give --plank too")
    out = None
    if args.output:
        out = pathlib.Path(args.output)
        if out.suffix.lower() not in SUFFIXES or out.is_dir():
            raise UserError(f"-o: write a .vtu grid, a .png picture or a .glb/.gltf/.obj scene, not '{out.name}'")
    return plane, plank, out


def _wood_record(model: Any, species: str | None, args: argparse.Namespace) -> dict[str, Any]:
    """What was grown: species or grammar, years, steps, seed, darts, volumes and the tissue (or
    label) counts."""
    from ramure.gmap.organs import wood as W

    gm = model.gm
    record: dict[str, Any] = {
        "species": species,
        "grammar": args.grammar,
        "years": args.years,
        "steps": 2 * args.years if isinstance(model, W.Wood) else model.stage,  # half-years
        "seed": args.seed,
        "darts": gm.n_darts,
        "volumes": gm.n_volumes,
    }
    if isinstance(model, W.Wood):  # a species' wood (a grammar's has labels only)
        from ramure.gmap.organs.wood_species import bark_and_reaction_facts

        record["tissues"] = model.tissue_counts()
        record["branches"] = model.knot_counts()
        record["knots_by_order"] = model.knot_orders()
        if "left_out" in gm.meta:  # a plant's branches that are not in the wood, by reason
            record["left_out"] = dict(gm.meta["left_out"])
        vd = gm.volume_data
        record.update(bark_and_reaction_facts(vd, (vd["axis"] == 0) & (vd["wood"] == W.CODES["bark"])))
    else:
        labels = np.asarray(gm.volume_data["label"])
        record["labels"] = {str(k): int((labels == k).sum()) for k in sorted(set(labels.tolist()))}
    return record


def _cut_or_saw(
    model: Any, species: str | None, args: argparse.Namespace, plane: Any, plank: Any, out: pathlib.Path | None, record: dict
) -> tuple[Any, np.ndarray | None]:
    """The grid to show or write (cut by the plane or sawn to the plank) and the direction to look
    from; the cut face's or plank's rings and knots join ``record``."""
    from ramure.gmap.organs import wood as W
    from ramure.gmap.kernel.cut import plane_cut

    grid = _grid(model, species, convex=out is not None and out.suffix.lower() == ".vtu")
    shown, look = grid, None
    if plane:
        normal, origin = plane
        shown = plane_cut(grid, normal=normal, origin=origin)
        if shown.n_cells == 0:
            raise UserError(f"--cut {args.cut}: the plane leaves nothing of the wood")
        b = np.asarray(grid.bounds, float).reshape(3, 2)
        axis = int(np.argmax(np.abs(normal)))
        if not b[axis, 0] < origin[axis] < b[axis, 1]:
            raise UserError(
                f"--cut {args.cut}: the plane misses the wood (it spans {b[axis, 0]:.4g}..{b[axis, 1]:.4g} along {'xyz'[axis]})"
            )
        look = np.asarray(normal, float) + (np.array([0.25, -0.35, 0.0]) if abs(normal[2]) > 0.5 else 0.0)
    elif plank:
        across, offset, thickness = plank
        shown = W.plank(grid, across, offset, thickness)
        look = -np.asarray(across)
        if species is not None:
            record["plank_map"] = _plank_map_facts(model.gm, across, offset, thickness)
    if plane and species is not None:  # rings and knots on the cut face itself
        record.update(W.cut_facts(grid.slice(normal=tuple(plane[0]), origin=tuple(plane[1]))))
    elif plank and species is not None:
        record.update(W.cut_facts(shown))
    return shown, look


def _write_wood(
    out: pathlib.Path,
    shown: Any,
    look: np.ndarray | None,
    plank: Any,
    species: str | None,
    args: argparse.Namespace,
    record: dict,
) -> None:
    """Write ``shown`` to ``out``: a VTU grid, a PNG (of the plank's window when sawn) or a scene."""
    from ramure.gmap.organs import wood as W

    if out.suffix.lower() == ".vtu":
        write_atomic(out, lambda tmp: shown.save(tmp))
    elif out.suffix.lower() == ".png" and plank:
        part, at, length = W.plank_window(shown, args.length, args.at)
        record["plank_window"] = {"at": round(at, 6), "length": round(length, 6)}
        name = species or pathlib.Path(args.grammar).stem
        title = f"{name}, {record['years']:g} years: {length:.3g} m of plank around z = {at:.3g} m"
        legend = legend_for(species) if species else None
        write_atomic(out, lambda tmp: render_plank(part, tmp, plank[0], parse_size(args.size), title, legend, species))
    elif out.suffix.lower() == ".png":
        size = parse_size(args.size)
        title = f"{species or pathlib.Path(args.grammar).stem}, {record['years']:g} years"
        legend = legend_for(species) if species else None
        write_atomic(out, lambda tmp: render_wood(shown, tmp, size=size, look=look, title=title, legend=legend))
    else:
        export_glb(shown, out)


def _say_wood(record: dict, seconds: float, out: pathlib.Path | None, as_json: bool) -> None:
    """Print the record: one JSON line, or one sentence of counts."""
    if as_json:
        print(json.dumps(record))
        return
    tissues = ", ".join(f"{v} {k}" for k, v in record.get("tissues", {}).items() if v)
    knots = record.get("branches")
    knots_text = f"; knots: {knots['live']} live, {knots['dead']} dead" if knots else ""
    if knots:
        from ramure.gmap.organs.wood import orders_text

        knots_text += orders_text(record.get("knots_by_order", {}), record.get("left_out"))
    print(
        f"{record['darts']} darts, {record['volumes']} volumes ({tissues}){knots_text}; chi {record['chi']}, "
        f"boundary chi {record['boundary_chi']}, {'valid' if record['valid'] else 'INVALID'}, "
        f"{seconds:.2f} s" + (f"; wrote {out}" if out else "")
    )


def _plank_map_facts(gm, normal, offset, thickness):
    """Darts, volumes, validity, knots and seconds of the plank cut as a 3-G-map (kernel cut_map)."""
    from ramure.gmap.organs import wood as W
    from ramure.gmap.kernel.pyvista import to_unstructured_grid

    from ramure.errors import RamureError

    t0 = time.perf_counter()
    try:
        part = W.plank_map(gm, normal, offset, thickness)
    except RamureError as err:  # the picture plank still stands; say why the map one does not
        return {"error": str(err).splitlines()[0]}
    seconds = time.perf_counter() - t0
    return {
        "darts": part.n_darts,
        "volumes": part.n_volumes,
        "valid": part.is_valid(),
        "knots": W.knot_regions(to_unstructured_grid(part)),
        "seconds": round(seconds, 6),
    }


def export_glb(grid: pv.UnstructuredGrid, path: str | os.PathLike) -> pathlib.Path:
    """The wood's surface as binary glTF (or .gltf/.obj by suffix): one material per cell colour."""
    from ramure.app.export import export_colored

    return export_colored(grid.extract_surface(algorithm="dataset_surface"), path)


def register(sub: Subparsers) -> None:
    """Add ``wood`` (volumetric wood, its cuts and planks) to the CLI's subcommands."""
    p = sub.add_parser("wood", help="grow volumetric wood (rings, knots, bark); cut it; facts, PNG, VTU or GLB")
    p.add_argument("--species", default="pine", help="species preset: pine, larch, elm or oak (default pine)")
    p.add_argument(
        "--years",
        type=int,
        default=None,
        help=f"years of growth, two half-year steps each (default {DEFAULT_YEARS}; with --grammar, the file's #steps)",
    )
    p.add_argument("--seed", type=int, default=0, help="random seed (ring widths, branch sectors)")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="override a species parameter, e.g. branches=5 or reaction=0.4 (repeatable)",
    )
    p.add_argument(
        "--grammar",
        default=None,
        metavar="FILE.g3l",
        help="grow a 3Gmap L-system instead of the species model (its #steps half-years, unless --years)",
    )
    p.add_argument(
        "--from-plant",
        default=None,
        metavar="FILE.lsys",
        help="wood of a derived plant: its trunk and its branches of every order (stubs of branch_levels levels)",
    )
    p.add_argument("-n", type=int, default=None, help="with --from-plant: derivation steps")
    p.add_argument("--cut", default=None, metavar="AXIS=VALUE", help="keep what lies below the plane, e.g. z=1.0")
    p.add_argument(
        "--plank", default=None, metavar="normal=x,offset=O,thickness=T", help="a slab at distance O from the trunk axis, T thick"
    )
    p.add_argument(
        "--length", type=float, default=None, metavar="METRES", help="with --plank and a PNG: the length drawn (default 3 widths)"
    )
    p.add_argument(
        "--at", type=float, default=None, metavar="Z", help="with --plank and a PNG: centre height (default: the largest knot)"
    )
    p.add_argument("--size", default="900x900", help="PNG size WIDTHxHEIGHT")
    p.add_argument("--json", action="store_true", help="print the facts as one JSON object")
    p.add_argument("-o", "--output", default=None, help="write a .vtu grid, a .png picture or a .glb/.gltf/.obj scene")
    p.set_defaults(func=run_wood)
