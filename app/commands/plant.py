"""``ramure check | derive | render``: grammars, derived strings and pictures."""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import sys
import time

from ramure.app.cli import UserError
from ramure.lsys import LSystem
from ramure.lsys.interpretation.turtle import NOT_DRAWN, undrawn_symbols
import os
from collections.abc import Collection, Iterable, Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ramure.app.cli import Subparsers
    from ramure.lsys.engine.derive import Derivation


def add_grammar_options(parser: argparse.ArgumentParser, derive: bool = True, file_optional: bool = False) -> None:
    """The options every plant command shares: FILE (optional with ``file_optional``), -n, --seed, --set."""
    parser.add_argument("file", nargs="?" if file_optional else None, help="an .lsys grammar file")
    if derive:
        parser.add_argument("-n", type=int, default=None, help="derivation steps (default: the grammar's n:)")
        parser.add_argument("--seed", type=int, default=0, help="random seed (stochastic grammars)")
        parser.add_argument(
            "--set", action="append", default=[], metavar="NAME=VALUE", help="override a #define constant (repeatable)"
        )


def parse_sets(pairs: Iterable[str], known: Collection[str]) -> dict[str, float]:
    """``["r1=0.8"]`` -> ``{"r1": 0.8}``; unknown names and bad numbers are refused."""
    out = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        name = name.strip()
        if not sep:
            raise UserError(f"--set expects NAME=VALUE, got '{pair}'")
        if name not in known:
            raise UserError(f"--set {name}: the grammar has no constant '{name}' (it defines: {', '.join(known) or 'none'})")
        try:
            out[name] = float(value)
        except ValueError:
            raise UserError(f"--set {name}: '{value}' is not a number") from None
        if not math.isfinite(out[name]):
            raise UserError(f"--set {name}: '{value}' is not a finite number")
    return out


def parse_size(text: str, option: str = "--size", largest: int = 10_000) -> tuple[int, int]:
    """``"800x600"`` -> ``(800, 600)``; each side must be in 1..``largest`` pixels."""
    w, _, h = text.partition("x")
    try:
        size = (int(w), int(h or w))
    except ValueError:
        raise UserError(f"{option} expects WIDTHxHEIGHT, got '{text}'") from None
    if not all(1 <= side <= largest for side in size):
        raise UserError(f"{option} {text}: width and height must be in 1..{largest} pixels")
    need, free = size[0] * size[1] * RENDER_BYTES_PER_PIXEL, available_memory()
    if free is not None and need > 0.8 * free:
        raise UserError(
            f"{option} {text}: a picture this large needs about {need / 2**30:.1f} GB to render, "
            f"and {free / 2**30:.1f} GB of memory is available; ask for a smaller size"
        )
    return size


#: Memory a render takes per pixel (off-screen buffers, the picture, its copies): a
#: 10,000 x 10,000 render took 6.8 GB.
RENDER_BYTES_PER_PIXEL = 68


def available_memory() -> int | None:
    """Bytes of memory available now (Linux: ``MemAvailable``), or None where it is not known."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def output_file(text: str | os.PathLike, suffixes: Sequence[str], option: str = "-o") -> pathlib.Path:
    """The output path, refused when it is a directory or has the wrong suffix."""
    out = pathlib.Path(text)
    if out.is_dir():
        raise UserError(f"{option} {text}: is a directory; give a file name")
    if suffixes and out.suffix.lower() not in suffixes:
        raise UserError(f"{option} {text}: the file name must end with {' or '.join(suffixes)}")
    return out


def load_and_derive(args: argparse.Namespace) -> tuple[LSystem, Derivation, float]:
    """Parse ``args.file``, apply ``--set``, derive; returns (lsystem, derivation, seconds)."""
    ls = LSystem.from_file(args.file)
    ls.constants.update(parse_sets(args.set, ls.constants))
    if args.n is not None and args.n < 0:
        raise UserError(f"-n must be >= 0, not {args.n}")
    t0 = time.perf_counter()
    d = ls.derive(n=args.n, seed=args.seed)
    seconds = time.perf_counter() - t0
    sys.stderr.write("".join(d.printed))  # a cpfg file's printf output, as cpfg shows it
    return ls, d, seconds


def run_check_g3l(args: argparse.Namespace) -> int:
    """``ramure check FILE.g3l``: parse a 3Gmap L-system and report its rules (errors: line, column, caret)."""
    from ramure.gmap.lsystem.g3l import load_g3l

    g = load_g3l(args.file)
    ops: dict[str, int] = {}
    for r in g.rules:
        ops[r.op] = ops.get(r.op, 0) + 1
    kinds = ", ".join(f"{v} {k}" for k, v in sorted(ops.items()))
    print(
        f"{args.file}: ok — {len(g.rules)} rule(s) ({kinds}), {len(g.constants)} constant(s), "
        f"{len(g.functions)} function(s), axiom {g.axiom.symbol}"
    )
    return 0


def run_check(args: argparse.Namespace) -> int:
    """``ramure check``: parse the grammar (an ``.lsys``, ``.l`` or ``.g3l`` file) and print its rules,
    constants, n, seed and axiom, with a note on symbols nothing draws; a grammar error exits 2; returns
    0.
    """
    if str(args.file).endswith(".g3l"):  # 3Gmap L-systems (wood)
        return run_check_g3l(args)
    ls = LSystem.from_file(args.file)
    g = ls.grammar
    counts = ls.rule_counts()
    others = ", ".join(f"{v} {k}" for k, v in counts.items() if k != "production" and v)
    axiom = "".join(str(m) for m in g.axiom) or getattr(ls, "axiom_text", "")
    print(
        f"{args.file}: ok — {counts['production']} rule(s){f' (and {others})' if others else ''}, "
        f"{len(ls.constants)} constant(s), n = {g.n}, seed = {ls.seed}, axiom {axiom}"
    )
    undrawn = undrawn_symbols(g)
    for symbol in [s for s in undrawn if s in NOT_DRAWN]:
        print(f"note: {symbol} is read but not drawn: {NOT_DRAWN[symbol]}")
    undrawn = [s for s in undrawn if s not in NOT_DRAWN]
    if undrawn:
        print(f"note: nothing draws {', '.join(undrawn)} (no turtle meaning, and no rule rewrites or interprets it)")
    return 0


def run_derive(args: argparse.Namespace) -> int:
    """``ramure derive``: derive the grammar and print the string, or with ``--json`` its counts (modules, tree
    nodes, segments, bounds) and timings; returns 0.
    """
    ls, d, seconds = load_and_derive(args)
    if not args.json:
        print(d.to_string())
        return 0
    t0 = time.perf_counter()
    sk = d.skeleton()
    lo, hi = sk.bounds()
    record = {
        "file": args.file,
        "n": d.n,
        "seed": d.seed,
        "modules": len(d),
        "tree_nodes": len(d.tree),
        "segments": len(sk),
        "organs": len(sk.organs),
        "organ_kinds": {k: int((sk.organs.kind == k).sum()) for k in sorted(set(sk.organs.kind))},
        "bounding_box": {"min": lo.round(6).tolist(), "max": hi.round(6).tolist()},
        "constants": d.constants,
        "seconds": round(seconds + time.perf_counter() - t0, 6),
    }
    if args.string:
        record["string"] = d.to_string()
    print(json.dumps(record))
    return 0


def run_render(args: argparse.Namespace) -> int:
    """``ramure render``: derive the grammar and render the plant off-screen to the PNG ``-o`` from ``--view``;
    returns 0.
    """
    from ramure.app.render import render_plant

    out = output_file(args.output, (".png",))
    size = parse_size(args.size)
    _, d, _ = load_and_derive(args)
    out.parent.mkdir(parents=True, exist_ok=True)
    render_plant(d.skeleton(), out, size=size, view=args.view)
    print(f"wrote {out}")
    return 0


def register(sub: Subparsers) -> None:
    """Add ``check``, ``derive`` and ``render`` to the CLI's subcommands."""
    p = sub.add_parser("check", help="parse a grammar and report problems with line and column")
    add_grammar_options(p, derive=False)
    p.set_defaults(func=run_check)

    p = sub.add_parser("derive", help="derive a grammar and print the string (or --json facts)")
    add_grammar_options(p)
    p.add_argument("--json", action="store_true", help="print modules, segments, organs, box, seconds")
    p.add_argument("--string", action="store_true", help="with --json: include the derived string")
    p.set_defaults(func=run_derive)

    p = sub.add_parser("render", help="render the plant off-screen to a PNG")
    add_grammar_options(p)
    p.add_argument("-o", "--output", required=True, help="PNG file to write")
    p.add_argument("--size", default="800x800", help="image size WIDTHxHEIGHT (default 800x800)")
    p.add_argument("--view", default="front", choices=["front", "side", "top", "iso"])
    p.set_defaults(func=run_render)
