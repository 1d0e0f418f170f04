"""``ramure amap``: the botanical architecture of a plant (axes, annual shoots, growth units,
internodes, events) from its ``#amap`` annotations, and its MTG file.

    ramure amap amap/rauh -n 7 --seed 0 --json --mtg rauh.mtg
    ramure amap amap/massart --at 3.5 --json      # what has grown after three and a half years
"""

from __future__ import annotations

import argparse
import json
import time

from ramure.app.cli import UserError
from ramure.app.commands.plant import add_grammar_options, load_and_derive, output_file
from ramure.lsys.architecture.amap import architecture, grown_by
from ramure.lsys.architecture.mtg import read_mtg, write_mtg
from ramure.lsys.architecture.mtg_graph import read_mtg_graph
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ramure.app.cli import Subparsers


def run_amap(args: argparse.Namespace) -> int:
    """``ramure amap``: derive the grammar, print its architecture tables (axes, annual shoots, growth units,
    internodes; JSON with ``--json``), replay the growth up to ``--at`` years and write the MTG file
    ``--mtg``; returns the exit code 0.
    """
    mtg = output_file(args.mtg, (".mtg",), "--mtg") if args.mtg else None
    _, derivation, derive_seconds = load_and_derive(args)
    t0 = time.perf_counter()
    arch = architecture(derivation)
    facts = {
        "file": args.file,
        "n": derivation.n,
        "seed": derivation.seed,
        **arch.to_dict(),
        "derive_seconds": round(derive_seconds, 6),
        "seconds": round(time.perf_counter() - t0, 6),
    }
    if args.at is not None:
        grown = grown_by(derivation, arch, args.at, seed=args.seed)
        facts["at"] = {"date": args.at, "internodes": len(grown["internodes"]), "events": grown["events"]}
    if mtg is not None:
        write_mtg(arch, mtg, derivation.skeleton())
        facts["mtg"] = str(mtg)
    if args.json:
        print(json.dumps(facts))
    else:
        print(
            f"{args.file}: {facts['axes']} axes {facts['axes_per_order']}, {facts['annual_shoots']} annual "
            f"shoots, {facts['growth_units']} growth units, {facts['internodes']} internodes"
        )
        if mtg is not None:
            print(f"wrote {mtg}")
    return 0


def run_mtg_check(args: argparse.Namespace) -> int:
    """Print the MTG's counts per scale, classes, features and edges by type; a file Ramure
    wrote (its ``# ramure-events:`` first line) adds its architecture tables."""
    graph = read_mtg_graph(args.file)
    facts = {"file": args.file, **graph.to_dict()}
    with open(args.file, "rb") as f:
        if f.readline().startswith(b"# ramure-events:"):
            facts.update(read_mtg(args.file).to_dict())
    print(json.dumps(facts))
    return 0


def register(sub: Subparsers) -> None:
    """Add ``amap`` (the architecture of a derived plant) and ``mtg`` (read any MTG file) to the CLI's
    subcommands.
    """
    p = sub.add_parser("amap", help="botanical architecture (AMAP) tables of a plant; --mtg writes an MTG file")
    add_grammar_options(p)
    p.add_argument(
        "--json",
        action="store_true",
        help="print counts per level, axes per order, events, the internodes-per-growth-unit histogram",
    )
    p.add_argument(
        "--mtg",
        metavar="FILE.mtg",
        help="write the plant as an MTG file (OpenAlea's format) with each internode's XX YY ZZ, "
        "TopDiameter, BottomDiameter and Length",
    )
    p.add_argument(
        "--at",
        type=float,
        metavar="YEARS",
        help="replay the growth through the event scheduler "
        "up to this date (one step = one year) and report what has grown by then",
    )
    p.set_defaults(func=run_amap)

    p = sub.add_parser(
        "mtg", help="read any MTG file (OpenAlea's format) and print its scales, classes, features and edges as JSON"
    )
    p.add_argument("file", help="an .mtg file")
    p.set_defaults(func=run_mtg_check)


__all__ = ["UserError", "register"]
