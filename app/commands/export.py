"""``ramure export``: derive a grammar and write the plant as glTF, OBJ, VTK, PLY or STL.

Examples::

    ramure export grammars/abop/plant_1_26.lsys -o plant.glb
    ramure export fruit_tree -n 5 -o tree.obj --yup      # tree.obj + tree.XXXXXXXX.mtl, Y up for Blender

The format follows the suffix (see :mod:`ramure.app.export`); a suffix
Ramure does not write is refused before anything is derived.
"""

from __future__ import annotations

import argparse
import json
import time

from ramure.app.cli import UserError
from ramure.app.commands.plant import add_grammar_options, load_and_derive, output_file
from ramure.app.export import EXPORT_SUFFIXES
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ramure.app.cli import Subparsers


def run_export(args: argparse.Namespace) -> int:
    """``ramure export``: derive the plant and write its mesh (``--sides`` per tube) in the format of ``-o``'s
    suffix (glTF, OBJ, VTK, PLY or STL), Y up with ``--yup``; returns 0.
    """
    from ramure.app.export import export_mesh

    out = output_file(args.output, EXPORT_SUFFIXES)
    if not 3 <= args.sides <= 64:
        raise UserError(f"--sides must be in 3..64, not {args.sides}")
    _, d, seconds = load_and_derive(args)
    t0 = time.perf_counter()
    mesh = d.skeleton().to_polydata(sides=args.sides)
    export_mesh(mesh, out, yup=args.yup)
    record = {
        "output": str(out),
        "cells": mesh.n_cells,
        "points": mesh.n_points,
        "derive_seconds": round(seconds, 6),
        "export_seconds": round(time.perf_counter() - t0, 6),
    }
    print(json.dumps(record) if args.json else f"wrote {out} ({mesh.n_cells} cells)")
    return 0


def register(sub: Subparsers) -> None:
    """Add ``export`` (the plant as a mesh file) to the CLI's subcommands."""
    p = sub.add_parser("export", help="write the plant as .glb/.gltf, .obj (+.mtl), .vtp/.vtk, .ply or .stl")
    add_grammar_options(p)
    p.add_argument("-o", "--output", required=True, help="file to write; the suffix picks the format")
    p.add_argument("--sides", type=int, default=8, help="sides of each branch tube (default 8)")
    p.add_argument("--yup", action="store_true", help="Y up instead of Z up (Blender, Unity, glTF viewers)")
    p.add_argument("--json", action="store_true", help="print cells, points and seconds as JSON")
    p.set_defaults(func=run_export)
