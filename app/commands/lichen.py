"""``ramure lichen``: grow lichen on a closed surface by Open-DLA and draw it.

ramure lichen --on stone --clusters 26 --particles 2000 --habit foliose --json -o lichen.png
ramure lichen --on trunk.stl --r 0.01 -o trunk_lichen.png
ramure lichen --on-plant fruit_tree -n 5 -o tree_lichen.png
ramure lichen --on-wood --years 10 -o bark_lichen.png
"""

from __future__ import annotations

import argparse
import json
import pathlib
import time

import numpy as np

from ramure.app.cli import UserError
from ramure.app.commands.plant import output_file, parse_size
from ramure.gmap.organs.lichen import HABITS, age_classes, grow_lichen, to_polydata
from ramure.gmap.organs.trimesh import from_polydata
from ramure.io import save_mesh, write_with
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ramure.app.cli import Subparsers
    import pyvista as pv
    from ramure.gmap.organs.lichen import Lichen
    from ramure.gmap.organs.trimesh import TriMesh

AGE_COLOURS = np.array([[0.42, 0.5, 0.3], [0.6, 0.68, 0.36], [0.8, 0.82, 0.5]])  # old inside .. young rim


def stone(seed: int = 0) -> pv.PolyData:
    """A closed, lumpy stone (about 8,000 triangles): a sphere displaced by smooth noise."""
    import pyvista as pv

    sphere = pv.Icosphere(radius=3.0, nsub=5)
    rng = np.random.default_rng(seed)
    waves = rng.normal(size=(6, 3))
    bumps = sum(0.08 * np.sin(sphere.points @ w + k) for k, w in enumerate(waves))
    normals = sphere.points / np.linalg.norm(sphere.points, axis=1, keepdims=True)
    sphere.points = sphere.points + normals * bumps[:, None]
    return sphere


def substrate(text: str) -> pv.DataSet:
    """The surface to grow on: the lumpy test stone, or a mesh file read with pyvista."""
    if text == "stone":
        return stone()
    path = pathlib.Path(text)
    if not path.is_file():
        raise UserError(f"--on {text}: no such mesh file (or use 'stone')")
    import pyvista as pv

    try:
        return pv.read(path)
    except Exception as exc:  # noqa: BLE001 - VTK's readers raise many kinds
        raise UserError(f"--on {text}: cannot read this mesh ({exc})") from None


def bark(args: argparse.Namespace) -> tuple[str, pv.DataSet, TriMesh, float]:
    """``(what, PolyData, TriMesh, default r)``: the stone or mesh file, a plant's welded bark
    (``--on-plant``) or a pine's skin (``--on-wood``)."""
    from ramure.app.details import cover_radius, plant_bark, wood_bark

    if args.on_plant and args.on_wood:
        raise UserError("give --on-plant or --on-wood, not both")
    if args.on_plant:
        from ramure.lsys import LSystem

        skeleton = LSystem.from_file(args.on_plant).derive(n=args.n, seed=args.seed).skeleton()
        poly, mesh = plant_bark(skeleton, args.thinnest)
        return args.on_plant, poly, mesh, cover_radius(mesh, args.particles)
    if args.on_wood:
        from ramure.gmap.organs.wood import grow_wood

        if not 1 <= args.years <= 40:
            raise UserError(f"--years must be 1..40, not {args.years}")
        poly, mesh = wood_bark(grow_wood(args.species, years=args.years, seed=args.seed))
        return f"wood:{args.species}", poly, mesh, cover_radius(mesh, args.particles)
    surface = substrate(args.on)
    mesh = from_polydata(surface)
    return args.on, surface, mesh, 0.02


def seeding_map(mesh: TriMesh, args: argparse.Namespace) -> np.ndarray | None:
    """The seed probability per vertex for ``--seeding``: None (anywhere), the habit's light and
    humidity response (``light``), or that times an accessibility band around ``--accessibility``
    (``accessibility``, the spec's mode: about 0.45 for crustose lichen on stone)."""
    from ramure.gmap.organs.lichen import seed_map

    if args.seeding == "anywhere":
        return None
    if not 0 <= args.accessibility <= 1:
        raise UserError(f"--accessibility must be in [0, 1], not {args.accessibility:g}")
    target = args.accessibility if args.seeding == "accessibility" else None
    return seed_map(mesh, args.habit, target=target)


def run_lichen(args: argparse.Namespace) -> int:
    """``ramure lichen``: grow lichen clusters by diffusion-limited aggregation on a closed surface (a stone, a
    mesh file, a plant's bark ``--on-plant`` or a pine's ``--on-wood``), print their facts and write ``-o``
    (PNG or VTP); returns 0."""
    out = output_file(args.output, (".png", ".vtp")) if args.output else None
    size = parse_size(args.size)
    what, _, mesh, default_r = bark(args)
    t0 = time.perf_counter()
    growth = grow_lichen(
        mesh,
        clusters=args.clusters,
        particles=args.particles,
        r=default_r if args.r is None else args.r,
        habit=args.habit,
        adhesion=seeding_map(mesh, args),
        seed=args.seed,
    )
    facts = {
        "on": what,
        "triangles": len(mesh.triangles),
        "habit": args.habit,
        "seeding": args.seeding,
        "r": growth.r,
        **growth.facts(),
        "seconds": round(time.perf_counter() - t0, 4),
    }
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        discs = to_polydata(growth, mesh, lift=growth.r * 0.2)
        if out.suffix.lower() == ".vtp":
            save_mesh(discs, out)
        else:
            render_lichen(mesh, growth, discs, out, size, close=bool(args.on_plant or args.on_wood))
        facts["output"] = str(out)
    print(
        json.dumps(facts)
        if args.json
        else f"{facts['particles']} particles in {facts['clusters']} clusters on {facts['triangles']} triangles"
    )
    return 0


def render_lichen(
    mesh: TriMesh, growth: Lichen, discs: pv.PolyData, path: pathlib.Path, size: tuple[int, int], close: bool = False
) -> None:
    """Render the bark ``mesh`` with the lichen ``discs`` coloured by age to the PNG ``path`` (``size`` pixels);
    ``close`` frames the lichen rather than the whole bark; otherwise the whole surface is seen
    from the side where the lichen grows (:func:`ramure.app.details.facing`).
    """
    from ramure.app.render import headless_setup

    headless_setup()
    import pyvista as pv

    faces = np.hstack([np.full((len(mesh.triangles), 1), 3), mesh.triangles]).ravel()
    surface = pv.PolyData(mesh.points, faces)
    classes = age_classes(growth, 3)
    per_disc = discs.n_cells // max(growth.count, 1)
    discs.cell_data["rgb"] = (np.repeat(AGE_COLOURS[classes], per_disc, axis=0) * 255).astype(np.uint8)
    plotter = pv.Plotter(off_screen=True, window_size=list(size))
    plotter.set_background("white", top="lightsteelblue")  # type: ignore[arg-type]  # pyvista stubs: decorated method
    plotter.add_mesh(surface, color=(0.62, 0.6, 0.57), smooth_shading=True)
    plotter.add_mesh(discs, scalars="rgb", rgb=True)
    from ramure.app.details import close_up, facing

    plotter.camera_position = close_up(growth, mesh) if close else facing(growth, mesh)
    write_with(path, lambda tmp: plotter.screenshot(tmp))
    plotter.close()


def register(sub: Subparsers) -> None:
    """Add ``lichen`` (lichen grown on bark) to the CLI's subcommands."""
    p = sub.add_parser("lichen", help="grow lichen on a closed surface (Open-DLA); --json facts, -o PNG or VTP")
    p.add_argument("--on", default="stone", help="'stone' (default) or a closed mesh file (.vtp, .stl, .ply, .obj)")
    p.add_argument("--clusters", type=int, default=26, help="number of lichen clusters (default 26)")
    p.add_argument("--particles", type=int, default=2000, help="particles in all (default 2000)")
    p.add_argument(
        "--on-plant", metavar="GRAMMAR", help="grow on a derived plant's bark (its branches welded into one closed surface)"
    )
    p.add_argument("-n", type=int, default=None, help="with --on-plant: derivation steps")
    p.add_argument(
        "--thinnest",
        type=float,
        default=0.1,
        help="with --on-plant: leave out twigs thinner than this fraction of the trunk (default 0.1)",
    )
    p.add_argument("--on-wood", action="store_true", help="grow on a volumetric pine's bark (its 3-G-map skin)")
    p.add_argument("--species", default="pine", help="with --on-wood: pine or oak")
    p.add_argument("--years", type=int, default=10, help="with --on-wood: years of growth (default 10)")
    p.add_argument(
        "--r",
        type=float,
        default=None,
        help="particle radius in the mesh's units (default 0.02 on stone; on bark: the radius at which "
        "the particles would cover a tenth of it)",
    )
    p.add_argument("--habit", default="crustose", choices=sorted(HABITS))
    p.add_argument(
        "--seeding",
        default="anywhere",
        choices=("anywhere", "light", "accessibility"),
        help="where clusters start: anywhere (default), where the habit's light and humidity suit it, "
        "or that and near an accessibility (Miller's tangent sphere; see --accessibility)",
    )
    p.add_argument(
        "--accessibility", type=float, default=0.45, help="with --seeding accessibility: the target in [0, 1] (default 0.45)"
    )
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", action="store_true", help="print clusters, particles, intersection tests, seconds")
    p.add_argument("-o", "--output", help="PNG picture or VTP of the lichen discs")
    p.add_argument("--size", default="800x800", help="image size WIDTHxHEIGHT (default 800x800)")
    p.set_defaults(func=run_lichen)
