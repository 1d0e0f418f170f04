"""``ramure import``: an L-studio/cpfg ``.l`` file as a Ramure ``.lsys`` grammar.

``ramure check|derive|render`` read ``.l`` files directly (by their suffix);
``import`` writes the translated grammar so it can be edited in Ramure.
"""

from __future__ import annotations

import argparse
import math
import pathlib

from ramure.app.cli import UserError
from ramure.io import write_text
from ramure.lsys import LSystem
from ramure.lsys.language.cpfg import to_lsys
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ramure.app.cli import Subparsers


def run_import(args: argparse.Namespace) -> int:
    """``ramure import``: translate the L-studio/cpfg ``.l`` file into an ``.lsys`` grammar at ``-o``, after
    checking that the translation parses; a wrong suffix or an angle outside -360..360 is a
    :class:`~ramure.errors.UserError`; returns 0.
    """
    source = pathlib.Path(args.file)
    if source.suffix.lower() != ".l":
        raise UserError(f"{args.file}: an L-studio/cpfg file ends with .l")
    out = pathlib.Path(args.output)
    if out.is_dir() or out.suffix.lower() != ".lsys":
        raise UserError(f"-o {args.output}: give a file name ending with .lsys")
    if args.angle is not None and not (math.isfinite(args.angle) and abs(args.angle) <= 360):
        raise UserError(f"--angle {args.angle:g}: an angle in degrees from -360 to 360")
    text = source.read_text(encoding="utf-8-sig")
    lsys = to_lsys(text, filename=str(source), angle=args.angle)
    ls = LSystem.from_text(lsys, filename=str(out))  # the written grammar must parse (and derive)
    write_text(out, lsys)
    g = ls.grammar
    print(
        f"wrote {out}: {len(g.rules)} production(s), {len(g.interpretation)} interpretation and "
        f"{len(g.decomposition)} decomposition rule(s), n = {g.n}"
    )
    return 0


def register(sub: Subparsers) -> None:
    """Add ``import`` (an L-studio/cpfg file as a Ramure grammar) to the CLI's subcommands."""
    p = sub.add_parser("import", help="translate an L-studio/cpfg .l file into an .lsys grammar")
    p.add_argument("file", help="the .l file")
    p.add_argument("-o", "--output", required=True, help="the .lsys file to write")
    p.add_argument(
        "--angle", type=float, default=None, help="the turn angle in degrees (cpfg keeps it in the view file, which is not read)"
    )
    p.set_defaults(func=run_import)
