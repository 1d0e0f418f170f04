"""How many of L-Py's own example models Ramure derives (issue 36).

The public collection is not copied into the repository; point this at a local copy of
openalea/lpy's ``share/``, ``models/`` and ``doc/_downloads`` (or any folder of ``.lpy`` files):

    python benchmarks/bench_lpy_files.py DIR [DIR ...]      # one JSON line

A file *derives with modules* when :mod:`ramure.lsys.readers.lpy` runs it, derives its own
``derivation length`` (capped at :data:`MAX_STEPS`, and stopped after :data:`SECONDS` seconds)
to a string of at least one module, and the turtle draws it.  Opening an ``.lpy`` file runs
its code: run this on files you trust.  ``bench_lpy_speed`` times the derivation itself (a
Python rule call and a history node per module, as L-Py calls Python per module).
Refusals are counted by the first words of their message.
"""

from __future__ import annotations

import collections
import json
import os
import pathlib
import re
import signal
import sys
import time

#: Steps derived per file at most (some run hundreds of steps of large plants).
MAX_STEPS = 30
#: Seconds a file may take (load, derive, draw) before it counts as not deriving.
SECONDS = 20


class _Timeout(Exception):
    pass


def _reason(exc: BaseException) -> str:
    text = str(exc).split("\n")[0]
    text = re.sub(r"^.*?(line \d+(, column \d+)?: )", "", text)
    text = re.sub(r"^\S*\.lpy[:,]\s*", "", text)
    return f"{type(exc).__name__}: {text[:80]}"


def _one(path: pathlib.Path) -> int:
    from ramure.lsys import LSystem

    ls = LSystem.from_file(path)
    derivation = ls.derive(n=min(ls.n, MAX_STEPS))
    derivation.skeleton()
    return len(derivation)


def count(folders: list[str]) -> dict:
    """Counts of the ``.lpy`` files under ``folders`` that derive with modules, and why the others do not."""
    files = sorted(p for folder in folders for p in pathlib.Path(folder).rglob("*.lpy"))
    reasons: collections.Counter = collections.Counter()
    derived, modules, t0, home = 0, 0, time.perf_counter(), os.getcwd()

    def stop(signum, frame):
        raise _Timeout(f"more than {SECONDS} s")

    old = signal.signal(signal.SIGALRM, stop)
    per_file = {}
    for path in files:
        signal.alarm(SECONDS)
        try:
            os.chdir(path.parent)  # models read their data files beside them
            count_ = _one(path.resolve())
            if count_ > 0:
                derived += 1
                modules += count_
            per_file[str(path)] = "ok"
        except BaseException as exc:  # a report: every refusal is counted, none stops the count
            if isinstance(exc, KeyboardInterrupt):
                raise
            reasons[_reason(exc)] += 1
            per_file[str(path)] = _reason(exc)
        finally:
            signal.alarm(0)
            os.chdir(home)
    signal.signal(signal.SIGALRM, old)
    return {
        "benchmark": "lpy_files.field_lpy",
        "files": len(files),
        "derived": derived,
        "modules": modules,
        "refused": dict(reasons.most_common()),
        "seconds": round(time.perf_counter() - t0, 3),
        "per_file": per_file if os.environ.get("RAMURE_LPY_PER_FILE") else None,
    }


#: A model whose every module is rewritten by a Python rule at every step (L-Py's multicore demo, smaller).
SPEED_MODEL = """\
Axiom:
  for i in range(100000): nproduce A B
derivation length: 2
production:
A : produce B
B : produce A
endlsystem
"""


def bench_lpy_speed():
    """Rule applications per second of the .lpy derivation (one Python call and one history node each)."""
    from benchtools import best

    from ramure.lsys.readers.lpy import LpyLSystem

    ls = LpyLSystem(SPEED_MODEL, "speed.lpy")
    seconds, derivation = best(ls.derive, repeats=2)
    written = derivation.tree.size
    rate = round(written / seconds)
    return {"modules": len(derivation), "history_nodes": written, "seconds": round(seconds, 3), "nodes_per_s": rate}


def bench_field_lpy():
    folders = [f for f in os.environ.get("RAMURE_FIELD_LPY", "").split(os.pathsep) if f]
    if not folders:
        return {"skipped": "set RAMURE_FIELD_LPY to folders of .lpy files (os.pathsep between)", "seconds": 0}
    return {k: v for k, v in count(folders).items() if k != "benchmark"}


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: python benchmarks/bench_lpy_files.py DIR [DIR ...]")
    print(json.dumps(count(sys.argv[1:])))
