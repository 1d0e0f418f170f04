"""How many of the field's own files Ramure reads (issue 36): MTG and cpfg collections.

The public collections are not copied into the repository; point this at local copies:

    python benchmarks/bench_field_files.py --mtg DIR --cpfg DIR      # one JSON line each
    RAMURE_FIELD_MTG=DIR RAMURE_FIELD_CPFG=DIR python benchmarks/run.py bench_field_files

``--mtg``: every ``*.mtg`` under DIR (e.g. openalea/mtg's ``test/data``, ``src/openalea/mtg/data``
and ``doc/user``).  A file *loads* when :mod:`ramure.lsys.architecture.mtg_graph` reads it and the plant
it makes (:mod:`ramure.lsys.architecture.mtg_plant`) derives and draws.
``--cpfg``: every cpfg ``*.l`` under DIR (e.g. AlgorithmicBotany/vlab's ``oofs/``), leaving out
panel files (``panel*.l``) and lpfg's C++ files (they ``#include <lpfgall.h>``).  A file
*loads* when it parses, derives its own ``derivation length`` (capped at
:data:`CPFG_MAX_STEPS`) and draws.
Refusals are counted by the first words of their message.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import pathlib
import re
import sys
import time

#: Steps derived per cpfg file at most (some run hundreds of steps of large plants).
CPFG_MAX_STEPS = 30


def _reason(exc: BaseException) -> str:
    text = str(exc).split("\n")[0]
    text = re.sub(r"^.*?(line \d+(, column \d+)?: )", "", text)
    text = re.sub(r"^\S*\.(l|mtg)[:,]\s*", "", text)
    return f"{type(exc).__name__}: {text[:70]}"


def count_mtg(folder: str | os.PathLike) -> dict:
    """Counts of the MTG files under ``folder`` that load, and why the others do not."""
    from ramure.lsys import LSystem
    from ramure.lsys.architecture.mtg_graph import read_mtg_graph

    files = sorted(pathlib.Path(folder).rglob("*.mtg"))
    reasons: collections.Counter = collections.Counter()
    loaded, vertices, t0 = 0, 0, time.perf_counter()
    for path in files:
        try:
            vertices += len(read_mtg_graph(path))
            LSystem.from_file(path).derive().skeleton()
            loaded += 1
        except Exception as exc:  # a report: every refusal is counted, none stops the count
            reasons[_reason(exc)] += 1
    return {
        "files": len(files),
        "loaded": loaded,
        "vertices": vertices,
        "refused": dict(reasons.most_common()),
        "seconds": round(time.perf_counter() - t0, 3),
    }


def cpfg_files(folder: str | os.PathLike) -> list[pathlib.Path]:
    """The cpfg L-systems under ``folder``: ``*.l`` without panels and lpfg C++ files."""
    out = []
    for path in sorted(pathlib.Path(folder).rglob("*.l")):
        text = path.read_bytes().decode("latin-1")
        if path.name.lower().startswith("panel") or "lpfg" in text or re.search(r"#include\s*<", text):
            continue
        out.append(path)
    return out


def count_cpfg(folder: str | os.PathLike) -> dict:
    """Counts of the cpfg files under ``folder`` that load, and why the others do not."""
    from ramure.lsys import LSystem

    files = cpfg_files(folder)
    reasons: collections.Counter = collections.Counter()
    parsed = loaded = 0
    t0 = time.perf_counter()
    for path in files:
        try:
            ls = LSystem.from_file(path)
            parsed += 1
            ls.derive(n=min(ls.grammar.n, CPFG_MAX_STEPS)).skeleton()
            loaded += 1
        except Exception as exc:  # a report: every refusal is counted, none stops the count
            reasons[_reason(exc)] += 1
    return {
        "files": len(files),
        "parsed": parsed,
        "loaded": loaded,
        "refused": dict(reasons.most_common()),
        "seconds": round(time.perf_counter() - t0, 3),
    }


def bench_field_mtg():
    folder = os.environ.get("RAMURE_FIELD_MTG")
    return count_mtg(folder) if folder else {"skipped": "set RAMURE_FIELD_MTG to a folder of .mtg files", "seconds": 0}


def bench_field_cpfg():
    folder = os.environ.get("RAMURE_FIELD_CPFG")
    return count_cpfg(folder) if folder else {"skipped": "set RAMURE_FIELD_CPFG to a folder of cpfg .l files", "seconds": 0}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--mtg", metavar="DIR", help="a folder of .mtg files")
    parser.add_argument("--cpfg", metavar="DIR", help="a folder of cpfg .l files")
    args = parser.parse_args(argv)
    if args.mtg:
        print(json.dumps({"benchmark": "field_files.mtg", "folder": args.mtg, **count_mtg(args.mtg)}))
    if args.cpfg:
        print(json.dumps({"benchmark": "field_files.cpfg", "folder": args.cpfg, **count_cpfg(args.cpfg)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
