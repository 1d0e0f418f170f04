"""``ramure fruit``: build a volumetric fruit, print its facts, write a PNG or a VTU.

Examples::

    ramure fruit --preset round_tomato --json
    ramure fruit --preset ribbed_tomato --set nbprotus=8 -o ribbed.png
    ramure fruit --subdivide volume:2 --cut z=0 -o tomato.png
    ramure fruit --subdivide volume:2 -o tomato.vtu
    ramure fruit --subdivide volume:2 --defect hail:count=5,depth_mm=2..6,stop=endocarp \
        --defect shrink:rate=0.1,steps=3 --size-mm 65 --json
    ramure fruit --malform rate=0.2 --seed 4 -o malformed.png
    ramure fruit --malform lopsided --json
    ramure fruit batch --count 100 --defects random --seed 0 -o dataset/
    ramure fruit batch --count 1000 --views 4 --scheduler tcp://10.0.0.5:8786 -o dataset/

JSON keys: preset, seed, darts, vertices, edges, faces (2-cells), faces_per_volume
(the thesis's count), volumes, tissues (volumes per tissue), valid, seconds
(build + validity check), and output when a file was written.  With ``--defect``
(see :func:`ramure.gmap.organs.defect_specs.apply_defects`): ``defects`` holds the per-defect
facts, the volume lost and the grade with its reasons.  With ``--malform`` (see
:mod:`ramure.gmap.organs.malform`): ``malformation`` holds the shape, the rate, the parameters
it changed and the measured flatness, lopsidedness and ribbing.

``ramure fruit batch`` writes a labelled dataset of defective fruit (several views per
fruit with exact defect masks, a cut picture, VTU, a label JSON per fruit, COCO files with a
train/val/test split and a dataset card; see :mod:`ramure.app.fruit_dataset`), on a process
pool or a Dask cluster (``--scheduler``).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import pathlib
import time
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

import ramure.io as atomic
from ramure.app.cli import UserError
from ramure.app.commands.plant import parse_size
from ramure.gmap.kernel.cut import parse_plane

if TYPE_CHECKING:
    import pyvista as pv
    from ramure.app.cli import Subparsers

SUBDIVISIONS = ("surface", "volume")


def parse_subdivide(specs: Iterable[str]) -> dict[str, int]:
    """``["volume:2", "surface:1"]`` -> ``{"volume_levels": 2, "surface_levels": 1}``."""
    levels = {"volume_levels": 0, "surface_levels": 0}
    for spec in specs:
        kind, sep, count = spec.partition(":")
        kind = kind.strip().lower()
        if kind not in SUBDIVISIONS:
            raise UserError(f"--subdivide expects surface:N or volume:N, got '{spec}'")
        try:
            n = int(count) if sep else 1
        except ValueError:
            raise UserError(f"--subdivide {kind}: '{count}' is not a whole number") from None
        if not 0 <= n <= 4:
            raise UserError(f"--subdivide {kind}: levels must be in 0..4, got {n}")
        levels[f"{kind}_levels"] += n
    return levels


def parse_region(text: str) -> dict[str, Any]:
    """``--region`` text as a fruit region: a label pattern, then the region's parameters.

    >>> parse_region("(5, C*, *) precision=20")
    {'path': '(5, C*, *)', 'params': {'precision': 20}}
    >>> parse_region("(5, C*, *) E(^b) largeur=75")
    {'faces': 'E(^b)', 'path': '(5, C*, *)', 'params': {'largeur': '75'}}
    """
    from ramure.app.fruit_regions import parse_params, split_pattern
    from ramure.gmap.organs.regions import check_region

    end = str(text).rfind(")")
    if end < 0 or not text[end + 1 :].strip():
        raise UserError(
            f"--region {text!r}: a label pattern and the region's parameters, e.g. '(5, C*, *) precision=20' "
            "or '(5, C*, *) largeur=75,creux=0.4'"
        )
    return check_region({**split_pattern(text[: end + 1]), "params": parse_params(text[end + 1 :])})


def parse_sets(pairs: Iterable[str]) -> dict[str, float | str]:
    """``["precision=12"]`` -> ``{"precision": "12"}`` (the fruit builder converts and checks)."""
    out = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        if not sep or not name.strip():
            raise UserError(f"--set expects NAME=VALUE, got '{pair}'")
        out[name.strip()] = _finite_or_text(name.strip(), value.strip())
    return out


#: Largest magnitude a numeric fruit setting may have (mm, degrees, counts): beyond is a typo.
MAX_FRUIT_VALUE = 1e6


def _finite_or_text(name, value):
    """Numbers must be finite and within +-MAX_FRUIT_VALUE (nan, inf, 1e308 are refused)."""
    try:
        number = float(value)
    except ValueError:
        return value  # a word (e.g. a preset name): the fruit builder checks it
    if not math.isfinite(number) or abs(number) > MAX_FRUIT_VALUE:
        raise UserError(f"--set {name}={value}: must be a finite number within +-{MAX_FRUIT_VALUE:g}")
    return value


def render_fruit(
    grid: pv.DataSet,
    path: str | os.PathLike,
    size: tuple[int, int] = (800, 800),
    cut_normal: ArrayLike | None = None,
    title: str | None = None,
) -> str | os.PathLike:
    """Render a fruit grid (cell data ``tissue``) off-screen to PNG, coloured by tissue."""
    from ramure.app.render import headless_setup
    from ramure.gmap.organs.tissue import COLORS, TISSUES, tissue_rgb

    headless_setup()
    import pyvista as pv

    plotter = pv.Plotter(off_screen=True, window_size=list(size))
    plotter.set_background("white")  # type: ignore[arg-type]  # pyvista stubs: decorated method
    shown = grid.copy(deep=False)
    if "rgb" not in shown.cell_data:  # a grid from ramure.app.fruit_look.coloured_grid keeps its colours
        shown.cell_data["rgb"] = tissue_rgb(shown.cell_data["tissue"])
    surface = shown.extract_surface(algorithm="dataset_surface")
    plotter.add_mesh(surface, scalars="rgb", rgb=True, show_edges=False, smooth_shading=True, split_sharp_edges=True)
    edges = surface.extract_feature_edges(feature_angle=25, boundary_edges=False, non_manifold_edges=False, manifold_edges=False)
    if edges.n_points:
        plotter.add_mesh(edges, color=(0.25, 0.1, 0.1), line_width=0.5, opacity=0.25)
    present = np.unique(np.asarray(grid.cell_data["tissue"]))
    plotter.add_legend(
        [[TISSUES[c], COLORS[TISSUES[c]]] for c in present],  # type: ignore[arg-type]  # pyvista stubs: decorated method
        bcolor=(0.6, 0.6, 0.6),
        face="rectangle",
        size=(0.2, 0.032 * len(present) + 0.01),
        loc="lower right",
    )
    b = np.asarray(grid.bounds, float).reshape(3, 2)
    centre = b.mean(axis=1)
    extent = float(np.max(b[:, 1] - b[:, 0])) or 1.0
    look = np.array([0.55, -0.75, 0.55]) if cut_normal is None else np.asarray(cut_normal, float) * 1.0
    if cut_normal is not None:
        side = np.cross(look, [0.0, 0.0, 1.0])
        if np.linalg.norm(side) < 1e-6:
            side = np.array([0.0, -1.0, 0.0])
        look = look + 0.8 * side / np.linalg.norm(side) + 0.3 * np.array([0.0, 0.0, 1.0])
    look = look / np.linalg.norm(look)
    up = (0.0, 0.0, 1.0) if abs(look[2]) < 0.9 else (0.0, 1.0, 0.0)
    plotter.camera_position = [tuple(centre + look * extent * 2.5), tuple(centre), up]
    plotter.reset_camera(bounds=tuple(b.ravel()))  # type: ignore[call-arg]  # pyvista stubs: decorated method
    if title:
        plotter.add_text(title, font_size=10, color="black")
    plotter.screenshot(str(path))
    plotter.close()
    return path


def run_fruit(args: argparse.Namespace) -> int:
    """``ramure fruit``: build a volumetric fruit from a preset and ``--set`` values, subdivide it, add the
    ``--defect`` and ``--malform`` deformations, cut it by ``--cut``, print its counts per tissue and
    write ``-o`` (picture or grid); returns 0.
    """
    from ramure.gmap.kernel.cut import plane_cut
    from ramure.gmap.organs.defect_specs import apply_defects, parse_defect
    from ramure.gmap.organs.fruit import build_fruit
    from ramure.gmap.organs.tissue import tissue_counts

    levels = parse_subdivide(args.subdivide)
    plane = parse_plane(args.cut) if args.cut else None  # checked even without -o
    size = parse_size(args.size)
    defects = [parse_defect(spec) for spec in args.defect]  # checked before building
    regions = [parse_region(text) for text in args.region]
    params: dict[str, Any] = dict(parse_sets(args.set))  # Any: mypy checks ** values against every keyword
    malformation = None
    if args.malform:
        from ramure.gmap.organs.malform import malform_params, parse_malform

        malformation = parse_malform(args.malform)
        params = malform_params(args.preset, seed=args.seed, **malformation, **params)
    t0 = time.perf_counter()
    gm = build_fruit(
        args.preset,
        seed=args.seed,
        volume_levels=levels["volume_levels"],
        surface_levels=levels["surface_levels"],
        ripeness=args.ripeness,
        size_mm=args.size_mm,
        regions=regions,
        **params,
    )
    if malformation is not None:
        from ramure.gmap.organs.malform import shape_facts

        malformation = {**malformation, "params": params, **shape_facts(gm)}
    defect_facts = None
    if defects:
        gm, defect_facts = apply_defects(gm, defects, seed=args.seed)  # the fruit's own millimetres
    valid = gm.is_valid()
    seconds = time.perf_counter() - t0
    out = None
    if args.output:
        out = pathlib.Path(args.output)
        if out.suffix.lower() not in (".png", ".vtu"):
            raise UserError(f"-o: write a .png picture or a .vtu grid, not '{out.name}'")
        out.parent.mkdir(parents=True, exist_ok=True)

        from ramure.app.fruit_look import coloured_grid, render_png

        grid = coloured_grid(gm)  # species colours, damage marks and per-tissue materials
        if plane:
            normal, origin = plane
            grid = plane_cut(grid, normal=normal, origin=origin, mode=args.cut_mode)
            if grid.n_cells == 0:
                raise UserError(f"--cut {args.cut}: the plane leaves nothing of the fruit")
        if out.suffix.lower() == ".vtu":
            atomic.save_mesh(grid, out)  # in memory first: a full disk is a clear error
        else:
            title = f"{args.preset.replace('_', ' ')}, {gm.meta['ripeness']}, {gm.meta['size_mm']:g} mm"
            atomic.write_with(out, lambda tmp: render_png(gm, tmp, size=size, cut=plane, title=title))
    if args.json:
        c = gm.counts()
        record = {
            "preset": args.preset,
            "species": gm.meta["species"],
            "ripeness": gm.meta["ripeness"],
            "size_mm": gm.meta["size_mm"],
            "seed": args.seed,
            **c,
            "tissues": tissue_counts(gm),
            "valid": bool(valid),
            "seconds": round(seconds, 6),
        }
        if defect_facts is not None:
            record["defects"] = defect_facts
        if malformation is not None:
            record["malformation"] = malformation
        if out is not None:
            record["output"] = str(out)
        print(json.dumps(record))
    elif out is not None:
        print(f"wrote {out}")
    else:
        c = gm.counts()
        print(
            f"{args.preset}: {c['darts']} darts, {c['vertices']} vertices, {c['volumes']} volumes, "
            f"{'valid' if valid else 'INVALID'}, {seconds * 1000:.1f} ms"
        )
        if defect_facts is not None:
            g = defect_facts["grade"]
            print(
                f"defects: {len(defects)}, volume lost {100 * defect_facts['volume_lost_fraction']:.1f} %, "
                f"{g['grade']}" + (f" ({'; '.join(g['reasons'])})" if g["reasons"] else "")
            )
    return 0 if valid else 1


def register(sub: Subparsers) -> None:
    """Add ``fruit`` (one volumetric fruit) and its action ``fruit batch`` (a labelled data set of fruit) to the
    CLI's subcommands."""
    from ramure.gmap.organs.fruit import PRESETS

    p = sub.add_parser("fruit", help="build a volumetric fruit (3G-map); facts, PNG or VTU")
    p.add_argument("--preset", default="round_tomato", choices=sorted(PRESETS), help="fruit preset (default round_tomato)")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="override a fruit parameter, e.g. precision=12 or carpels=4 (repeatable)",
    )
    p.add_argument(
        "--subdivide",
        action="append",
        default=[],
        metavar="KIND:N",
        help="surface:N or volume:N subdivisions (repeatable); volume:N also builds tissues",
    )
    p.add_argument("--seed", type=int, default=0, help="random seed (seed placement)")
    p.add_argument(
        "--region",
        action="append",
        default=[],
        metavar="PATTERN PARAMS",
        help="regrow a region alone (repeatable): a label pattern and its parameters, e.g. "
        "'(5, C*, *) largeur=75' (a local malformation) or '(5, C*, *) precision=20' (finer cells "
        "there: the fruit's precision times 2, 4 or 8); the rest of the fruit is not touched",
    )
    p.add_argument("--cut", default=None, metavar="AXIS=VALUE", help="show the inside: keep what lies behind the plane, e.g. z=0")
    p.add_argument(
        "--cut-mode",
        default="clip",
        choices=["clip", "cells"],
        help="clip cells flat (default) or drop whole cells in front of the plane",
    )
    p.add_argument("--size", default="800x800", help="PNG size WIDTHxHEIGHT (default 800x800)")
    p.add_argument(
        "--defect",
        action="append",
        default=[],
        metavar="KIND:NAME=VALUE,...",
        help="apply a defect in order (repeatable): shrink:rate=0.1,steps=3; "
        "rot:vertex=N,coefficients=2.5/2/1.5,rate=0.1; "
        "hail:count=5,depth_mm=2..6,stop=endocarp; "
        "crack:kind=longitudinal,sector=3,rings=3-6,depth=2,width_mm=1,healed=1 "
        "(hail and crack need --subdivide volume:N for tissues and layers)",
    )
    p.add_argument(
        "--malform",
        default=None,
        metavar="SHAPE|rate=R",
        help="malformed fruit: rate=R (0..1) varies the shape parameters within the thesis's "
        "Grammar 3.1 ranges (R=1: the whole range), and/or a shape: lopsided, flattened, "
        "ribbed, pointed; e.g. --malform ribbed,rate=0.1 (seeded by --seed)",
    )
    p.add_argument(
        "--size-mm",
        type=float,
        default=None,
        help="fruit size in millimetres for defect depths, the grade and the picture's scale "
        "(default the preset's real size: cherry tomato 25, round tomato 65, banana 180...)",
    )
    p.add_argument(
        "--ripeness",
        default=None,
        metavar="STAGE",
        help="ripeness stage for the colours, e.g. green, turning, red for tomatoes; yellow, flecked for "
        "bananas; green, yellow, red, bicolour for apples (default: ripe)",
    )
    p.add_argument("--json", action="store_true", help="print the facts as one JSON object")
    p.add_argument("-o", "--output", default=None, help="write a .png picture or a .vtu grid")
    p.set_defaults(func=run_fruit)
    actions = p.add_subparsers(dest="fruit_command", metavar="[batch]")
    b = actions.add_parser("batch", help="write a labelled dataset of defective fruit (pictures, VTU, labels)")
    b.add_argument("--count", type=int, default=100, help="number of fruit (default 100)")
    b.add_argument(
        "--defects",
        default="random",
        choices=["random", "none"],
        help="random malformations and defects per fruit (default), or none",
    )
    b.add_argument("--seed", type=int, default=0, help="dataset seed: fruit i draws from (seed, i)")
    b.add_argument("--preset", default="round_tomato", choices=sorted(PRESETS), help="fruit preset")
    b.add_argument(
        "--levels",
        type=int,
        default=1,
        choices=[1, 2],
        help="volume subdivisions: 1 (exocarp, mesocarp; fast, default) or 2 (+ endocarp, locules, seeds)",
    )
    b.add_argument(
        "--size-mm",
        type=float,
        default=None,
        help="fruit size in millimetres (default the preset's real size: cherry tomato 25, round tomato 65, banana 180...)",
    )
    b.add_argument("--workers", type=int, default=2, help="worker processes (default 2; with --scheduler local, Dask workers)")
    b.add_argument("--views", type=int, default=4, help="pictures per fruit, each with its own camera and light (default 4)")
    b.add_argument(
        "--stage",
        default="mixed",
        choices=["mixed", "plain", "conveyor", "cup"],
        help="what the fruit is seen on: a plain backdrop, a conveyor belt, a cup on the belt, or mixed per fruit (default)",
    )
    b.add_argument(
        "--coco-masks",
        default="rle",
        choices=["rle", "polygon"],
        help="masks in the COCO files: exact RLE (default) or polygons (outer boundaries; for ultralytics)",
    )
    b.add_argument("--clean-pictures", action="store_true", help="also write each view of the fruit without its defects")
    b.add_argument(
        "--scheduler",
        default=None,
        metavar="local|tcp://HOST:PORT",
        help="run on Dask (needs ramure[dask]): 'local' starts a LocalCluster of --workers processes; an address "
        "uses that cluster (files come back to this machine)",
    )
    b.add_argument("--size", default="256x256", help="picture size WIDTHxHEIGHT (default 256x256)")
    b.add_argument("--json", action="store_true", help="print the dataset summary as JSON")
    b.add_argument("-o", "--output", required=True, help="dataset folder (created; must be empty unless --resume/--overwrite)")
    b.add_argument("--resume", action="store_true", help="finish the dataset in the folder (same settings)")
    b.add_argument("--overwrite", action="store_true", help="remove the dataset files in the folder first")
    b.set_defaults(func=run_batch)


def run_batch(args: argparse.Namespace) -> int:
    """``ramure fruit batch``: make a data set of ``--count`` fruit with random defects (pictures, labels, a
    summary) in the ``-o`` folder, ``--resume`` continuing one left unfinished; returns 0.
    """
    from ramure.app.fruit_dataset import make_dataset

    size = parse_size(args.size)
    summary = make_dataset(
        args.output,
        count=args.count,
        seed=args.seed,
        defects=args.defects,
        preset=args.preset,
        levels=args.levels,
        size_mm=args.size_mm,
        workers=args.workers,
        picture=size,
        resume=args.resume,
        overwrite=args.overwrite,
        views=args.views,
        stage=args.stage,
        clean_pictures=args.clean_pictures,
        scheduler=args.scheduler,
        coco_masks=args.coco_masks,
    )
    if args.json:
        print(json.dumps({k: v for k, v in summary.items() if k != "fruit"}))
    else:
        print(
            f"wrote {summary['count']} fruit x {summary['views']} views to {args.output} ({summary['marketable']} marketable; "
            f"{summary['visible_defects']} of {summary['located_defects']} located defects visible) in {summary['seconds']:.1f} s"
        )
    return 0
