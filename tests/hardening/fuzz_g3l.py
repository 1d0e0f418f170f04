"""Fuzz the ``.g3l`` reader and engine: parse -> derive -> embed -> check, on mutated wood grammars.

Run from the repository root::

    python -m tests.hardening.fuzz_g3l --inputs 20000          # a long campaign
    python -m tests.hardening.fuzz_g3l --inputs 300 --seed 3   # a slice

Each input is a shipped ``grammars/wood/*.g3l`` file with a few edits: random
characters (``random``), or a number, an operator or a face replaced by an
extreme or hostile piece of expression (``aware``: ``9^9^9``, ``10^400``,
``min([0]*10^10)``, ``{1: 2}``, a truncated face, ...).  Every input is parsed,
derived for at most :data:`MAX_STEPS` steps under a small dart budget, embedded
and checked.  The outcome is ``ok``, ``refused:<RamureError subclass>``,
``crash:<exception type>`` (a bug), ``slow`` (over 5 s) or ``hang`` (stopped after 30 s of CPU or 300 s of waiting).
Goal: zero crashes, zero slow inputs.
"""

from __future__ import annotations

import argparse
import collections
import pathlib
import re
import sys
import time
import traceback

import numpy as np

from ramure.errors import RamureError
from ramure.gmap.lsystem.engine import G3LSystem
from tests.hardening.watchdog import Hang, bounded

FOLDER = pathlib.Path(__file__).resolve().parents[2] / "grammars" / "wood"
TEXTS = [p.read_text(encoding="utf-8") for p in sorted(FOLDER.glob("*.g3l"))]
SLOW_SECONDS = 5.0
HANG_SECONDS = 30
MAX_STEPS = 4
MAX_DARTS = 200_000

HOSTILE = [
    "9^9^9",
    "9**9**9",
    "10^400",
    "-10^400",
    "(0/0)",
    "1/0",
    "2^3",
    "min([0]*10^10)",
    "{1: 2}",
    "[1, 2]",
    "'a'",
    "6 & 3",
    "1 << 4",
    "x.y",
    "H[0]",
    "open(1)",
    "alea(1e308, -1e308)",
    "normal(0, -1)",
    "sqrt(-1)",
    "log(0)",
    "1e308*10",
    "1e308",
    "1e200",
    "stage",
    "age",
    "order",
    "F1()",
    "F1(1, 2)",
    "0",
    "-1",
    "2",
    "3",
    "40000",
    "1e9",
    "1e-320",
    "not 1",
    "1 and 0",
]
FACES = ["_", "_E", "_O", "_C*", "_C*-2", "_C(stage)", "_C99", "_{C2,", "_C(1/0)", "_{}", "_C(alea(0, 99))"]
CHARS = "ABCFRS[]_(){},:->^|<*.0123456789+-/%!&=#CEO \n'\"ω"


def mutate(rng):
    """A shipped wood grammar with a few random character edits."""
    from tests.hardening.fuzz import edit_text

    return edit_text(rng, str(rng.choice(TEXTS)), CHARS, HOSTILE)


def aware(rng):
    """A shipped wood grammar with numbers, faces or arguments replaced by hostile pieces."""
    text = str(rng.choice(TEXTS))
    for _ in range(int(rng.integers(1, 4))):
        r = rng.random()
        if r < 0.6:
            spots = [m.span() for m in re.finditer(r"\d+\.?\d*", text)]
            piece = str(rng.choice(HOSTILE))
        else:
            spots = [m.span() for m in re.finditer(r"_(E|O|C\*|C\d+|\{[^}]*\}|C\([^)]*\))", text)]
            piece = str(rng.choice(FACES))
        if spots:
            a, b = spots[int(rng.integers(0, len(spots)))]
            text = text[:a] + piece + text[b:]
    return text


GENERATORS = {"aware": aware, "random": mutate}


def grow(text, seed=0, max_steps=MAX_STEPS, max_darts=MAX_DARTS):
    """Everything ``ramure wood --grammar`` does with one grammar, then a regrow; returns (darts, volumes)."""
    system = G3LSystem.from_text(text, "fuzz.g3l")
    steps = min(system.grammar.steps if system.grammar.steps is not None else 1, max_steps)
    d = system.derive(steps, seed=seed, max_darts=max_darts)
    d.check_topology()
    if not np.isfinite(d.gm.points).all():
        raise AssertionError("a derivation that was not refused has non-finite points")
    if d.gm.n_volumes > 1:
        d.regrow(d.gm.n_volumes - 1, seed + 1)
    return d.gm.n_darts, d.gm.n_volumes


def run_one(text, seed=0, **limits):
    """Outcome name and seconds for one input (exceptions other than RamureError are crashes)."""
    t0 = time.process_time()  # CPU seconds: the wall clock also counts the other jobs of a shared machine
    try:
        with bounded(HANG_SECONDS):
            grow(text, seed, **limits)
        outcome = "ok"
    except Hang:
        outcome = "hang"
    except RamureError as exc:
        outcome = f"refused:{type(exc).__name__}"
    except Exception as exc:  # noqa: BLE001 - the point is to count them
        outcome = f"crash:{type(exc).__name__}"
    seconds = time.process_time() - t0
    if (outcome == "ok" or outcome.startswith("refused")) and seconds > SLOW_SECONDS:
        outcome = "slow"
    return outcome, seconds


def campaign(inputs, seed=0, **limits):
    """Run ``inputs`` inputs; returns ``(Counter of (generator, outcome), list of (outcome, text, trace))``.

    ``limits`` (``max_steps``, ``max_darts``) bound each derivation.
    """
    rng = np.random.default_rng(seed)
    counts = collections.Counter()
    bad = []
    names = list(GENERATORS)
    for i in range(inputs):
        gen = names[i % len(names)]
        text = GENERATORS[gen](rng)
        outcome, seconds = run_one(text, i % 7, **limits)
        counts[(gen, outcome)] += 1
        if outcome.startswith(("crash", "slow", "hang")):
            trace = ""
            if outcome.startswith("crash"):
                try:
                    grow(text, i % 7, **limits)
                except Exception:  # noqa: BLE001
                    trace = traceback.format_exc(limit=-4)
            bad.append((outcome, text, trace, round(seconds, 2)))
    return counts, bad


def table(counts):
    """The outcome table: one row per outcome, one column per generator."""
    from tests.hardening.fuzz import table as outcome_table

    return outcome_table(counts, GENERATORS)


def main(argv=None):
    p = argparse.ArgumentParser(prog="python -m tests.hardening.fuzz_g3l", description=__doc__.split("\n")[0])
    p.add_argument("--inputs", type=int, default=1000)
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    t0 = time.perf_counter()
    counts, bad = campaign(args.inputs, args.seed)
    print(table(counts))
    print(f"{args.inputs} inputs in {time.perf_counter() - t0:.0f} s; {len(bad)} crash/slow/hang")
    for outcome, text, trace, seconds in bad[:20]:
        print(f"\n--- {outcome} ({seconds} s)\n{text}\n{trace}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
