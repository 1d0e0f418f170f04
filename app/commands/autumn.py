"""``ramure autumn``: leaves that age, change colour, fall and pile up (the Open Markov Chain).

ramure autumn fruit_tree --steps 16 --heat 0.6 --humidity 0.4 --wind 0.05,0 --json -o autumn.png
"""

from __future__ import annotations

import argparse
import json
import os
import time
from typing import TYPE_CHECKING

import numpy as np

from ramure.app.cli import UserError
from ramure.io import write_with
from ramure.app.commands.plant import add_grammar_options, load_and_derive, output_file, parse_size
from ramure.lsys.architecture.seasons import age_leaves, autumn_chain

if TYPE_CHECKING:
    from ramure.app.cli import Subparsers
    from ramure.lsys.architecture.seasons import LeafChain, Season
    from ramure.lsys.interpretation.turtle import Skeleton


def _unit(text, option):
    try:
        value = float(text)
    except ValueError:
        raise UserError(f"{option} expects a number in [0, 1], got '{text}'") from None
    if not 0 <= value <= 1:
        raise UserError(f"{option} must be in [0, 1], not {value:g}")
    return value


def _wind(text):
    try:
        parts = [float(v) for v in text.split(",")]
    except ValueError:
        raise UserError(f"--wind expects X,Y (or a strength), got '{text}'") from None
    if len(parts) not in (1, 2) or not all(np.isfinite(parts)):
        raise UserError(f"--wind expects X,Y (or a strength), got '{text}'")
    if len(parts) == 1 and parts[0] < 0:
        raise UserError(f"--wind: a strength must be >= 0, not {parts[0]:g}")
    return tuple(parts) if len(parts) == 2 else parts[0]


def run_autumn(args: argparse.Namespace) -> int:
    """``ramure autumn``: age the plant's leaves through the autumn chain for ``--steps`` steps under ``--heat``,
    ``--humidity`` and ``--wind``, print how many fell and the count per state, and render the season to
    ``-o`` (PNG); returns 0.
    """
    out = output_file(args.output, (".png",)) if args.output else None
    size = parse_size(args.size)
    heat, humidity, wind = _unit(args.heat, "--heat"), _unit(args.humidity, "--humidity"), _wind(args.wind)
    _, derivation, _ = load_and_derive(args)
    skeleton = derivation.skeleton()
    chain = autumn_chain()
    t0 = time.perf_counter()
    season = age_leaves(skeleton, chain, steps=args.steps, seed=args.seed, heat=heat, humidity=humidity, wind=wind)
    facts = {
        "file": args.file,
        "n": derivation.n,
        "seed": args.seed,
        **season.facts(chain),
        "seconds": round(time.perf_counter() - t0, 6),
    }
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        render_autumn(skeleton, season, chain, out, size)
        facts["output"] = str(out)
    if args.json:
        print(json.dumps(facts))
    else:
        print(
            f"{facts['leaves']} leaves, {facts['fallen_leaves']} fallen after {facts['steps']} steps: "
            + ", ".join(f"{v} {k}" for k, v in facts["states"].items())
        )
    return 0


def render_autumn(
    skeleton: Skeleton, season: Season, chain: LeafChain, path: str | os.PathLike, size: tuple[int, int] = (800, 800)
) -> str | os.PathLike:
    """The plant with attached leaves in their state's colour and fallen leaves on the ground,
    curled by the time they have lain there, on compacted piles (:func:`ramure.app.details.litter_polydata`)."""
    from ramure.app.render import frame_camera, headless_setup, plant_colors

    headless_setup()
    import pyvista as pv

    mesh = skeleton.to_polydata()
    leaf_colour = dict(zip(season.leaf_ids.tolist(), chain.colors[season.states[-1]].tolist()))
    fallen = set(season.leaf_ids[season.fallen].tolist())
    ids = np.asarray(mesh.cell_data["leaf_id"])
    keep = np.array([i not in fallen for i in ids.tolist()], bool)
    rgb = plant_colors(mesh).astype(np.float64) / 255
    for cell in np.flatnonzero(np.isin(ids, season.leaf_ids)):
        rgb[cell] = leaf_colour[int(ids[cell])]
    mesh.cell_data["rgb"] = (rgb * 255).astype(np.uint8)
    shown = mesh.extract_cells(np.flatnonzero(keep))  # type: ignore[arg-type]  # pyvista types index arrays as NDArray[int]
    plotter = pv.Plotter(off_screen=True, window_size=list(size))
    plotter.set_background("white", top="lightsteelblue")  # type: ignore[arg-type]  # pyvista stubs: decorated method
    plotter.add_mesh(shown, scalars="rgb", rgb=True, smooth_shading=True)
    bounds = np.asarray(mesh.bounds, float).reshape(3, 2)
    if season.fallen.any():
        ground = season.ground[season.fallen]
        bounds[:2, 0] = np.minimum(bounds[:2, 0], ground[:, :2].min(axis=0))
        bounds[:2, 1] = np.maximum(bounds[:2, 1], ground[:, :2].max(axis=0))
        from ramure.app.details import litter_polydata

        litter = litter_polydata(season, chain.colors, size=0.24)
        plotter.add_mesh(litter, scalars="rgb", rgb=True, smooth_shading=True, show_scalar_bar=False)
    span = bounds[:, 1] - bounds[:, 0]
    plane = pv.Plane(center=(*(bounds[:2].mean(axis=1)), 0.0), i_size=span[0] * 1.3 + 1, j_size=span[1] * 1.3 + 1)
    plotter.add_mesh(plane, color=(0.42, 0.52, 0.32))
    frame_camera(plotter, bounds.ravel(), "iso")
    write_with(path, lambda tmp: plotter.screenshot(tmp))
    plotter.close()
    return path


def register(sub: Subparsers) -> None:
    """Add ``autumn`` (leaves that change colour and fall) to the CLI's subcommands."""
    p = sub.add_parser("autumn", help="age the leaves (colours), let them fall and pile up; --json facts, -o PNG")
    add_grammar_options(p)
    p.add_argument("--steps", type=int, default=16, help="time steps (default 16)")
    p.add_argument("--heat", default="0.5", help="heat rate in [0, 1] (default 0.5)")
    p.add_argument("--humidity", default="0.5", help="humidity rate in [0, 1] (default 0.5)")
    p.add_argument("--wind", default="0", help="wind X,Y per step, or a strength along x (default 0)")
    p.add_argument("--json", action="store_true", help="print leaves, fallen leaves per step, states, tests")
    p.add_argument("-o", "--output", help="PNG picture of the plant and the ground")
    p.add_argument("--size", default="800x800", help="image size WIDTHxHEIGHT (default 800x800)")
    p.set_defaults(func=run_autumn)
