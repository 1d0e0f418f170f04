"""Run every ``benchmarks/bench_*.py`` and print one JSON line per benchmark.

A benchmark module defines functions named ``bench_<name>()``; each returns a
dict of figures (at least ``seconds``; targets as ``target_seconds`` and the
verdict as ``ok``).  Run one file with ``python benchmarks/run.py bench_lsys``.
"""
from __future__ import annotations

import importlib.util
import json
import pathlib
import sys
import traceback

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))


def _modules(names):
    files = sorted(HERE.glob("bench_*.py"))
    if names:
        files = [f for f in files if f.stem in names]
    for path in files:
        spec = importlib.util.spec_from_file_location(path.stem, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        yield path.stem, module


def main(argv=None):
    names = set(argv if argv is not None else sys.argv[1:])
    failed = 0
    for stem, module in _modules(names):
        for name in sorted(n for n in dir(module) if n.startswith("bench_")):
            try:
                record = {"benchmark": f"{stem}.{name[6:]}", **getattr(module, name)()}
            except Exception as exc:  # a broken benchmark is reported, the others still run
                failed += 1
                record = {"benchmark": f"{stem}.{name[6:]}", "error": repr(exc)}
                traceback.print_exc(file=sys.stderr)
            print(json.dumps(record), flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
