"""``ramure crack``: carve a crack drawn from a skeleton and a profile into a closed surface.

ramure crack --on stone --nodes 63 --seed 0 --noise 12 --json -o cracked.png
ramure crack --on vase.stl --from-plant honda_sympodial -n 5 --t 0.8 -o vase_cracked.stl
ramure crack --on wood --nodes 12 --json -o board_check.png    # a 3-G-map: unsewn along its faces
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from ramure.app.cli import UserError
from ramure.app.commands.lichen import substrate
from ramure.app.commands.plant import output_file, parse_size
from ramure.io import save_mesh, write_with
from ramure.gmap.organs.cracks import add_noise, carve, pattern_from_skeleton, random_pattern, smooth, symmetric
from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ramure.app.cli import Subparsers
    import pathlib
    from ramure.gmap.organs.cracks import Crack
    from ramure.gmap.kernel.map3 import GMap3


def _vector(text, option):
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise UserError(f"{option} expects X,Y,Z, got '{text}'") from None
    if len(values) != 3:
        raise UserError(f"{option} expects X,Y,Z, got '{text}'")
    return values


#: Nodes of the random pattern when not given: a fruit takes a short growth crack (6 arcs of 8 units,
#: about a quarter of a 65 mm tomato's girth), stone and wood the long pattern.
NODES = {"fruit": 6}
DEFAULT_NODES = 63


def _pattern(args: argparse.Namespace):
    if args.nodes is None:
        args.nodes = NODES.get(args.on, DEFAULT_NODES)
    if args.nodes < 2:
        raise UserError(f"--nodes must be >= 2, not {args.nodes}")
    if args.from_plant:
        from ramure.lsys import LSystem

        skeleton = LSystem.from_file(args.from_plant).derive(n=args.n, seed=args.seed).skeleton()
        pattern = pattern_from_skeleton(skeleton, width=args.width, depth=args.depth, scale=args.length)
    else:
        shape = {"branching": 0.15, "spread": 12.0} if args.on == "wood" else {}  # end checks run straight
        pattern = random_pattern(args.nodes, seed=args.seed, length=args.length, width=args.width, depth=args.depth, **shape)
    if args.noise:
        pattern = add_noise(pattern, amount=args.noise, seed=args.seed)
    if args.smooth is not None:
        pattern = smooth(pattern, args.smooth)
    if args.symmetry > 1:
        pattern = symmetric(pattern, args.symmetry)
    return pattern.timing(speed=args.speed, tau=args.tau)


#: Pattern sizes per substrate when not given: (arc length, half-width, depth).
SIZES = {"stone": (0.15, 0.02, 0.04), "fruit": (8.0, 3.0, 8.0), "wood": (0.012, 0.004, 0.3)}
MAPS = ("fruit", "wood")


def _sizes(args: argparse.Namespace):
    length, width, depth = SIZES.get(args.on, SIZES["stone"])
    return (
        length if args.length is None else args.length,
        width if args.width is None else args.width,
        depth if args.depth is None else args.depth,
    )


def run_crack(args: argparse.Namespace) -> int:
    """``ramure crack``: carve a crack of the chosen pattern into a surface model (stone, bark...) or, for a
    volumetric substrate, split its G-map along its faces; print the crack's facts and write ``-o`` (PNG,
    STL, VTP or PLY); returns 0.
    """
    args.length, args.width, args.depth = _sizes(args)
    if args.on in MAPS:
        return run_map_crack(args)
    out = output_file(args.output, (".png", ".stl", ".vtp", ".ply")) if args.output else None
    size = parse_size(args.size)
    model = substrate(args.on)
    bounds = model.bounds
    anchor = (
        _vector(args.anchor, "--anchor") if args.anchor else ((bounds[0] + bounds[1]) / 2, (bounds[2] + bounds[3]) / 2, bounds[5])
    )
    pattern = _pattern(args)
    t0 = time.perf_counter()
    crack = carve(model, pattern, anchor, _vector(args.direction or "1,0,0", "--direction"), t0=args.t)
    facts = {"on": args.on, **crack.facts(), "seconds": round(time.perf_counter() - t0, 4)}
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        if out.suffix.lower() == ".png":
            render_crack(crack, anchor, out, size)
        else:
            save_mesh(crack.result, out)
        facts["output"] = str(out)
    print(
        json.dumps(facts)
        if args.json
        else f"{facts['nodes']} nodes, {facts['triangles_object']} -> {facts['triangles_result']} triangles"
    )
    return 0


def crack_model(
    on: str, years: int = 12, seed: int = 0
) -> tuple[GMap3, tuple[float, ...] | None, tuple[float, float, float], str | None]:
    """The 3-G-map to crack and where a crack starts by default: ``(map, anchor, direction,
    species)``.

    ``fruit``: a round tomato subdivided twice (8,000 cells; the crack cuts through them along
    its curve), the crack from the side (+x) towards the stem (+z).
    ``wood``: a board of a ``years``-year pine trunk (no branches): sawn through the pith, as
    thick as the trunk's radius, and cross-cut at mid-height (three kernel map cuts); the
    crack is an **end check**, from the pith on the board's end grain outwards (+y), the way
    boards split as they dry.
    """
    if on == "fruit":
        from ramure.gmap.organs.fruit import build_fruit

        fruit = build_fruit("round_tomato", volume_levels=2, seed=seed)
        _, pos = fruit.vertex_positions()
        return fruit, tuple(pos[np.argmax(pos[:, 0])]), (0.0, 0.0, 1.0), None
    from ramure.gmap.kernel.cut import cut_map
    from ramure.gmap.organs.wood import grow_wood, plank_map

    wood = grow_wood("pine", years=years, seed=seed, branches=0)
    _, pos = wood.gm.vertex_positions()
    middle = float(pos[:, 2].max()) / 2
    level = np.abs(pos[:, 2] - middle) < 0.05 * middle
    radius = float(np.linalg.norm(pos[level, :2], axis=1).max())
    board = cut_map(plank_map(wood.gm, (1.0, 0.0, 0.0), -radius / 2, radius), (0.0, 0.0, 1.0), (0.0, 0.0, middle))
    return board, (0.0, 0.0, middle), (0.0, 1.0, 0.0), wood.species


def run_map_crack(args: argparse.Namespace) -> int:
    """``--on fruit|wood``: the crack cut topologically into a 3-G-map (:mod:`ramure.gmap.organs.mapcracks`)."""
    from ramure.gmap.organs.mapcracks import crack_map
    from ramure.gmap.organs.edgecracks import crack_map_edges

    out = output_file(args.output, (".png", ".vtu", ".vtp")) if args.output else None
    size = parse_size(args.size)
    t0 = time.perf_counter()
    if not 1 <= args.years <= 40:
        raise UserError(f"--years must be 1..40, not {args.years}")
    gm, anchor, direction, species = crack_model(args.on, years=args.years, seed=args.seed)
    anchor = _vector(args.anchor, "--anchor") if args.anchor else anchor
    if anchor is None:  # crack_map's default: the highest vertex
        _, pos = gm.vertex_positions()
        anchor = tuple(pos[np.argmax(pos[:, 2])])
    direction = _vector(args.direction, "--direction") if args.direction else direction
    if args.ring is not None:
        cracked, facts = ring_crack(gm, args, anchor if args.anchor else None)
        anchor = facts.pop("anchor")
    else:
        # a board's end check runs along a ray: its grid's sector faces are radial planes
        crack = crack_map_edges if args.on == "wood" else crack_map
        cracked, facts = crack(gm, _pattern(args), anchor=anchor, direction=direction, t0=args.t)
    facts = {
        "on": args.on,
        "darts": int(cracked.n_darts),
        "volumes": int(cracked.n_volumes),
        **facts,
        "seconds": round(time.perf_counter() - t0, 4),
    }
    mpu = float(gm.meta.get("mm_per_unit", 0.0) or 0.0)
    if mpu > 0:  # a fruit knows its millimetres
        facts["length_mm"], facts["opening_mm"] = facts["length"] * mpu, facts["opening"] * mpu
        facts["volume_lost_mm3"] = facts["volume_lost"] * mpu**3
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        if out.suffix.lower() == ".png":
            render_map_crack(cracked, species, out, size, anchor, facts["length"])
        else:
            from ramure.gmap.kernel.pyvista import boundary_polydata, to_unstructured_grid

            save_mesh(to_unstructured_grid(cracked) if out.suffix.lower() == ".vtu" else boundary_polydata(cracked), out)
        facts["output"] = str(out)
    print(
        json.dumps(facts)
        if args.json
        else f"{facts['skin_edges_opened']} skin edges opened ({facts['length']:.4g} long), "
        f"{facts['faces_unsewn']} faces unsewn, chi {facts['euler_before']} -> {facts['euler_after']}"
    )
    return 0


#: A concentric crack's default height: this fraction of the fruit's height below its top.
RING_BELOW_TOP = 0.12


def ring_crack(gm: GMap3, args: argparse.Namespace, anchor: Sequence[float] | None) -> tuple[GMap3, dict]:
    """``--ring DEG``: a concentric crack round the fruit's vertical axis, the skin's section at
    the anchor's height (default :data:`RING_BELOW_TOP` of the height below the top, on the
    shoulders round the stem scar), over ``DEG`` degrees centred on the anchor's side (+x by
    default). The facts carry the anchor (the arc's middle) for the picture's camera."""
    from ramure.gmap.organs.crackcut import ring_curve
    from ramure.gmap.organs.mapcracks import Skin, crack_along
    from ramure.gmap.kernel.errors import GMapError

    if args.on != "fruit":
        raise UserError("--ring (a concentric crack round the stem) is for --on fruit")
    skin = Skin(gm)
    low, high = float(skin.pos[skin.used, 2].min()), float(skin.pos[skin.used, 2].max())
    height = high - RING_BELOW_TOP * (high - low) if anchor is None else float(anchor[2])
    middle = 0.0 if anchor is None else float(np.degrees(np.arctan2(anchor[1], anchor[0])))
    try:
        curve = ring_curve(skin.mesh, height, args.ring, middle - args.ring / 2, args.width, args.depth)
    except GMapError as err:
        raise UserError(str(err)) from None
    cracked, facts = crack_along(gm, [curve], skin=skin)
    mid = curve.points[len(curve.points) // 2]
    return cracked, {"ring_degrees": float(args.ring), "ring_height": height, **facts, "anchor": tuple(mid)}


def render_map_crack(
    gm: GMap3, species: str | None, path: pathlib.Path, size: tuple[int, int], anchor: Sequence[float], length: float
) -> None:
    """The cracked map's skin: tissue colours, the crack's walls (unsewn inner faces) dark,
    seen from outside, over the anchor, from twice the crack's length."""
    from ramure.app.render import headless_setup
    from ramure.gmap.organs.mapcracks import wall_faces
    from ramure.gmap.kernel.pyvista import boundary_polydata

    headless_setup()
    import pyvista as pv

    surface = boundary_polydata(gm)
    if species is not None:
        from ramure.gmap.organs.wood import cell_colors

        rgb = np.asarray(cell_colors(gm.volume_data, species))[np.asarray(surface.cell_data["volume"])]
    else:
        from ramure.gmap.organs.tissue import tissue_rgb

        rgb = tissue_rgb(np.asarray(surface.cell_data["tissue"]))
    wall = wall_faces(gm)  # the crack's walls: inner faces the crack unsewed
    rgb = np.array(rgb, np.uint8)
    rgb[wall] = (45, 30, 20)
    surface.cell_data["rgb"] = rgb
    plotter = pv.Plotter(off_screen=True, window_size=list(size))
    plotter.set_background("white", top="lightsteelblue")  # type: ignore[arg-type]  # pyvista stubs: decorated method
    plotter.add_mesh(surface, scalars="rgb", rgb=True, show_scalar_bar=False, smooth_shading=True, split_sharp_edges=True)
    cells = surface.cell_centers().points
    mouth = cells[~wall][np.argsort(np.linalg.norm(cells[~wall] - np.asarray(anchor), axis=1))[:12]]
    centre = mouth.mean(axis=0)
    span = max(min(2.0 * length, 0.9 * surface.length), 1e-6)  # never farther than the whole model
    normals = surface.compute_normals(
        cell_normals=True, point_normals=False, split_vertices=False, consistent_normals=True, auto_orient_normals=True
    ).cell_data["Normals"]
    near = np.argsort(np.linalg.norm(cells[~wall] - centre, axis=1))[:12]
    outward = np.asarray(normals)[~wall][near].mean(axis=0)
    outward /= max(np.linalg.norm(outward), 1e-9)
    up = np.array([0.0, 0.0, 1.0]) if abs(outward[2]) < 0.8 else np.array([0.0, 1.0, 0.0])
    up = up - (up @ outward) * outward
    up /= np.linalg.norm(up)
    side = np.cross(up, outward)
    plotter.camera_position = [tuple(centre + (outward * 1.6 + side * 0.5 + up * 0.5) * span), tuple(centre), tuple(up)]
    write_with(path, lambda tmp: plotter.screenshot(tmp))
    plotter.close()


def render_crack(crack: Crack, anchor: Sequence[float], path: pathlib.Path, size: tuple[int, int]) -> None:
    """Render the cracked ``crack.result`` off-screen to the PNG ``path`` (``size`` pixels), the camera looking at
    the crack from outside (``anchor``, where it started, is not drawn)."""
    import numpy as np

    from ramure.app.render import headless_setup

    headless_setup()
    import pyvista as pv

    plotter = pv.Plotter(off_screen=True, window_size=list(size))
    plotter.set_background("white", top="lightsteelblue")  # type: ignore[arg-type]  # pyvista stubs: decorated method
    plotter.add_mesh(crack.result, color=(0.75, 0.72, 0.68))
    centre = crack.points.mean(axis=0)
    span = max(float(np.ptp(crack.points, axis=0).max()), 1e-3)
    outward = centre / max(np.linalg.norm(centre), 1e-9)
    plotter.camera_position = [
        tuple(centre + outward * span * 2.4 + np.array([0.0, -0.5, 0.4]) * span),
        tuple(centre),
        (0.0, 0.0, 1.0),
    ]
    write_with(path, lambda tmp: plotter.screenshot(tmp))
    plotter.close()


def register(sub: Subparsers) -> None:
    """Add ``crack`` (cracks carved into a surface or a volumetric map) to the CLI's subcommands."""
    p = sub.add_parser("crack", help="carve a crack (skeleton + profile) into a closed surface; --json, -o PNG/STL")
    p.add_argument(
        "--on",
        default="stone",
        help="'stone' (default), a closed mesh file, or 'fruit' / 'wood': a 3-G-map (a tomato, a pine "
        "plank) cracked topologically along its own faces",
    )
    p.add_argument("--years", type=int, default=12, help="with --on wood: the pine's age (default 12)")
    p.add_argument("--nodes", type=int, default=None, help="nodes of the random pattern (default 63; 6 on fruit)")
    p.add_argument("--from-plant", metavar="GRAMMAR", help="take the pattern from a plant's branching instead")
    p.add_argument("-n", type=int, default=None, help="with --from-plant: derivation steps")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--length",
        type=float,
        default=None,
        help="arc length (or the plant's scale); default 0.15 on stone, 8 on fruit, 0.012 on wood",
    )
    p.add_argument("--width", type=float, default=None, help="profile half-width at the root (0.02, 3, 0.004)")
    p.add_argument("--depth", type=float, default=None, help="profile depth at the root (0.04, 8, 0.3)")
    p.add_argument("--noise", type=float, default=0.0, help="jitter turning angles by +-DEG (with inserted points)")
    p.add_argument("--smooth", type=float, default=None, help="bound the change of turning angles (degrees)")
    p.add_argument("--symmetry", type=int, default=1, help="copies around the root (a circular crack)")
    p.add_argument("--anchor", help="X,Y,Z near the surface (default: top centre of the model)")
    p.add_argument(
        "--ring",
        type=float,
        default=None,
        metavar="DEG",
        help="with --on fruit: a concentric crack round the stem over DEG degrees (<= 350), at the "
        "anchor's height and centred on its side (default: 12%% of the height below the top, +x)",
    )
    p.add_argument("--direction", default=None, help="initial direction X,Y,Z (default 1,0,0; 0,1,0 on wood)")
    p.add_argument("--t", type=float, default=None, help="the crack grown until this time (default: grown)")
    p.add_argument("--speed", type=float, default=1.0, help="growth speed v (t_j = t_i + delta / v)")
    p.add_argument("--tau", type=float, default=0.5, help="growth duration of a node")
    p.add_argument("--json", action="store_true", help="print nodes, triangles before/after, seconds")
    p.add_argument("-o", "--output", help="PNG picture, or the cracked mesh (.stl, .vtp, .ply; on a map .vtu grid or .vtp skin)")
    p.add_argument("--size", default="800x800", help="image size WIDTHxHEIGHT (default 800x800)")
    p.set_defaults(func=run_crack)
