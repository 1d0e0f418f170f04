"""``ramure leaves | regen``: choose history leaves, regrow what the min-cut selects."""

from __future__ import annotations

import argparse
import json
import time


from ramure.app import ids
from ramure.app.cli import UserError
from ramure.errors import ValueRefused
from ramure.app.commands.plant import add_grammar_options, output_file, parse_sets
from ramure.lsys import LSystem
from ramure.lsys.regeneration.regen import Session
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ramure.app.cli import Subparsers


def parse_ids(text: str) -> list[int]:
    """``"12,15,20-23"`` -> ``[12, 15, 20, 21, 22, 23]``: the front ends' parser
    (:func:`ramure.app.ids.parse_ids`), its refusals as ``--select`` errors."""
    try:
        return ids.parse_ids(text)
    except ValueRefused as exc:
        raise UserError(f"--select: {exc}") from None


def select_leaves(text: str, session: Session) -> list[int]:
    """The leaves ``--select`` names in ``session``'s plant, read as the front ends read it
    (:func:`ramure.app.ids.resolve_ids`): a range means the leaves inside it, so it is
    measured against the plant before a single id is listed."""
    try:
        chosen = ids.resolve_ids(text, session.derivation.tree.leaves)
    except ValueRefused as exc:
        raise UserError(f"--select: {exc}") from None
    if not chosen:
        raise UserError("--select needs at least one leaf id (see 'ramure leaves FILE')")
    return chosen


def run_leaves(args: argparse.Namespace) -> int:
    """``ramure leaves``: derive the plant and list its history leaves with the segment or organ each draws (JSON
    with ``--json``): the ids ``ramure regen --select`` takes; returns 0.
    """
    ls = LSystem.from_file(args.file)
    ls.constants.update(parse_sets(args.set, ls.constants))
    d = ls.derive(n=args.n, seed=args.seed)
    sk = d.skeleton()
    if args.json:
        record = {
            "leaves": len(d),
            "segments": [
                {"leaf": int(leaf), "start": s.round(6).tolist(), "end": e.round(6).tolist(), "order": int(o)}
                for leaf, s, e, o in zip(sk.leaf_id, sk.start, sk.end, sk.order)
            ],
            "organs": [
                {"leaf": int(leaf), "kind": str(k), "position": p.round(6).tolist()}
                for leaf, k, p in zip(sk.organs.leaf_id, sk.organs.kind, sk.organs.position)
            ],
        }
        print(json.dumps(record))
    else:
        for leaf, s, e in zip(sk.leaf_id, sk.start, sk.end):
            print(f"{leaf}\t{s[0]:.4g} {s[1]:.4g} {s[2]:.4g}\t{e[0]:.4g} {e[1]:.4g} {e[2]:.4g}")
    return 0


def run_regen(args: argparse.Namespace) -> int:
    """``ramure regen``: regrow (or ``--prune``) the cut of the ``--select``-ed leaves with ``--rho``,
    ``--regen-seed`` and ``--set`` constants, print what changed and save the session to ``-o``; returns 0.
    """
    t0 = time.perf_counter()
    if args.min_ascend < 0:
        raise UserError(f"--min-ascend must be >= 0, not {args.min_ascend}")
    if args.output:
        output_file(args.output, ())
    ls = LSystem.from_file(args.file)
    session = Session(ls, n=args.n, seed=args.seed, filename=args.file)
    selection = select_leaves(args.select, session)
    constants = parse_sets(args.set, ls.constants)
    rho = args.rho / 100.0 if args.rho > 1 else args.rho
    op = session.prune if args.prune else session.regrow
    kwargs = dict(rho=rho, min_ascend=args.min_ascend)
    if not args.prune:
        kwargs.update(seed=args.regen_seed, constants=constants)
    result = op(selection, **kwargs)
    if args.output:
        session.save(args.output)
    record = {
        **result.to_dict(),
        "selection": selection,  # the leaves --select named (a range: those inside it)
        "modules": len(session.derivation),
        "seconds": round(time.perf_counter() - t0, 6),
        "regen_seconds": round(result.seconds, 6),
    }
    if args.output:
        record["session"] = args.output
    if args.json:
        print(json.dumps(record))
    else:
        print(
            f"roots {record['roots']} (cut {record['cut_roots']}, minimum ascension "
            f"{record['min_roots']}); removed {result.removed} modules, added {result.added}; "
            f"cut value {result.cut_value:g}"
        )
        if result.warning:
            print(result.warning)
    return 0


def register(sub: Subparsers) -> None:
    """Add ``leaves`` and ``regen`` (select and regrow from the command line) to the CLI's subcommands."""
    p = sub.add_parser("leaves", help="list history-leaf ids with their segment end points")
    add_grammar_options(p)
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=run_leaves)

    p = sub.add_parser("regen", help="regrow (or prune) the subtrees a selection's min-cut chooses")
    add_grammar_options(p)
    p.add_argument("--select", required=True, metavar="LEAF_IDS", help="leaf ids, e.g. 12,15,20-23")
    p.add_argument(
        "--rho", type=float, default=0.5, help="fraction of siblings that must be selected to climb, in (0, 1] (or 0-100)"
    )
    p.add_argument("--regen-seed", type=int, default=None, help="seed for the regrown part (default: a new one)")
    p.add_argument("--min-ascend", type=int, default=1)
    p.add_argument("--prune", action="store_true", help="delete the cut subtrees instead of regrowing")
    p.add_argument("--json", action="store_true")
    p.add_argument("-o", "--output", help="save the session (JSON) here")
    p.set_defaults(func=run_regen)
