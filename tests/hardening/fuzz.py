"""Fuzz the whole core loop: parse -> derive -> turtle -> metrics -> regrow/undo -> JSON.

Run from the repository root::

    python -m tests.hardening.fuzz --inputs 100000            # the long campaign
    python -m tests.hardening.fuzz --inputs 500 --seed 3      # a slice

Each input is a grammar text from one of two generators: ``aware`` builds
grammars from the language's own pieces (parametric modules, expressions,
stochastic and context rules, conditions, directives, shipped grammars with
extreme values), ``random`` mutates shipped grammars character by character.
Every input goes through the whole loop at n <= 6; the outcome is one of
``ok``, ``refused:<RamureError subclass>``, ``crash:<exception type>`` (a
bug: anything but a RamureError), ``slow`` (over 5 s), ``hang`` (over 30 s,
stopped by an alarm).  The table printed at the end counts each outcome; the
first crashing inputs are kept in full (``--keep DIR`` writes them to files).
Goal: zero crashes, zero slow inputs.
"""

from __future__ import annotations

import argparse
import collections
import json
import pathlib
import signal
import sys
import time
import traceback

import numpy as np

from ramure.errors import RamureError
from ramure.lsys import LSystem
from ramure.lsys.regen import Session

GRAMMARS = sorted((pathlib.Path(__file__).resolve().parents[2] / "grammars").glob("*.lsys"))
TEXTS = [p.read_text(encoding="utf-8") for p in GRAMMARS]
SLOW_SECONDS = 5.0
HANG_SECONDS = 30
#: Module budget for one input: large plants are refused by the derivation's own limit.
MAX_N = 6

SYMBOLS = "FfABXYGL+-&^\\/|!$'"
EXTREMES = [
    "0",
    "-0",
    "1e308",
    "-1e308",
    "1e-320",
    "(1e308*10)",
    "(0/0)",
    "2^31",
    "2^63",
    "1/0",
    "0.5",
    "-1",
    "360",
    "3.14159",
    "1e9",
    "127",
    "128",
    "(2^1024)",
    "1e-308",
]
CHARS = "AFB[]()<>:->*.,0123456789+-/^&!|$'#\n wpn=;{}%?ωé\t\""


class Hang(Exception):
    pass


def _alarm(_signum, _frame):
    raise Hang()


# -- generators ---------------------------------------------------------------------------------
def _number(rng):
    if rng.random() < 0.15:
        return str(rng.choice(EXTREMES))
    return f"{rng.uniform(-100, 100):.3g}" if rng.random() < 0.5 else str(int(rng.integers(0, 90)))


def _module(rng, params, depth=0):
    sym = str(rng.choice(list(SYMBOLS)))
    if rng.random() < 0.4:
        k = int(rng.integers(1, 4 if rng.random() < 0.98 else 140))
        args = [_expr(rng, params, depth) for _ in range(k)]
        return f"{sym}({','.join(args)})"
    return sym


def _expr(rng, params, depth=0):
    r = rng.random()
    if params and r < 0.35:
        return str(rng.choice(params))
    if r < 0.75 or depth > 2:
        return _number(rng)
    op = str(rng.choice(["+", "-", "*", "/", "^", "%"]))
    fn = rng.random()
    if fn < 0.2:
        return f"{rng.choice(['sin', 'cos', 'sqrt', 'log', 'exp', 'abs', 'floor'])}({_expr(rng, params, depth + 1)})"
    return f"({_expr(rng, params, depth + 1)}{op}{_expr(rng, params, depth + 1)})"


def _string(rng, params, length):
    out, open_ = [], 0
    for _ in range(length):
        r = rng.random()
        if r < 0.12:
            out.append("[")
            open_ += 1
        elif r < 0.24 and open_:
            out.append("]")
            open_ -= 1
        else:
            out.append(_module(rng, params))
    out.extend("]" * open_ if rng.random() < 0.95 else "")
    return "".join(out)


def aware(rng):
    """A grammar built from the language's pieces (mostly valid, sometimes extreme)."""
    if rng.random() < 0.25:  # a shipped grammar with one constant pushed to an extreme
        text = str(rng.choice(TEXTS))
        lines = text.split("\n")
        defines = [i for i, line in enumerate(lines) if line.startswith("#define")]
        if defines:
            i = int(rng.choice(defines))
            parts = lines[i].split()
            if len(parts) >= 3:
                parts[2] = _number(rng)
                lines[i] = " ".join(parts)
        return "\n".join(lines)
    lines = [f"n: {int(rng.integers(0, MAX_N + 1))}"]
    for c in range(int(rng.integers(0, 3))):
        lines.append(f"#define c{c} {_number(rng)}")
    if rng.random() < 0.1:
        lines.append(str(rng.choice(["#ignore: +-", "#tropism 0 0 -1 0.2", "#widthscale 0.01", "#tropism 0 1e308 0 1"])))
    lines.append(f"w: {_string(rng, [], int(rng.integers(1, 6)))}")
    lines.append("p:")
    arity = {}  # one arity per symbol, as the language asks
    for _ in range(int(rng.integers(1, 5))):
        sym = str(rng.choice(list("ABFXYG")))
        arity.setdefault(sym, int(rng.choice([0, 0, 1, 2])))
        params = ["x", "y"][: arity[sym]]
        pred = sym + (f"({','.join(params)})" if params else "")
        left = f"{rng.choice(list('ABF'))} < " if rng.random() < 0.1 else ""
        right = f" > {rng.choice(list('ABF'))}" if rng.random() < 0.1 else ""
        cond = f" : {params[0]} > {_number(rng)}" if params and rng.random() < 0.2 else ""
        prob = f"{rng.uniform(0, 1):.2f} " if rng.random() < 0.15 else ""
        succ = _string(rng, params, int(rng.integers(0, 6)))
        lines.append(f"  {prob}{left}{pred}{right}{cond} -> {succ}")
    return "\n".join(lines) + "\n"


def mutate(rng):
    """A shipped grammar with a few random character edits."""
    return edit_text(rng, str(rng.choice(TEXTS)), CHARS, EXTREMES)


def edit_text(rng, text, chars, extras):
    """``text`` with 1-4 random edits: cut a run, insert or replace ``chars``, truncate, or
    insert one of ``extras`` (the .g3l fuzzer calls it with its own alphabet and inputs)."""
    for _ in range(int(rng.integers(1, 5))):
        i = int(rng.integers(0, len(text) + 1))
        op = rng.random()
        if op < 0.3:
            text = text[:i] + text[i + int(rng.integers(1, 6)) :]
        elif op < 0.6:
            text = text[:i] + "".join(rng.choice(list(chars), int(rng.integers(1, 4)))) + text[i:]
        elif op < 0.8:
            text = text[:i] + str(rng.choice(list(chars))) + text[i + 1 :]
        elif op < 0.9:
            text = text[:i]
        else:
            text = text[:i] + str(rng.choice(extras)) + text[i:]
    return text


GENERATORS = {"aware": aware, "random": mutate}


# -- the loop -----------------------------------------------------------------------------------
def core_loop(text, rng):
    """Everything a user does with one grammar; returns the JSON it printed."""
    ls = LSystem.from_text(text)
    n = min(ls.n, MAX_N)
    session = Session(ls, n=n, seed=int(rng.integers(0, 1000)))
    d = session.derivation
    sk = d.skeleton()
    out = {"modules": len(d), "segments": int(len(sk.start))}
    if len(sk.start):
        from ramure.metrics import plant_metrics

        m = plant_metrics(sk)
        out["metrics"] = (
            {k: float(v) for k, v in vars(m).items() if isinstance(v, (int, float, np.floating))}
            if hasattr(m, "__dict__")
            else str(m)
        )
    leaves = session.tree.leaves
    before = (leaves.copy(), session.tree.symbol[leaves].copy())
    if len(leaves):
        k = int(rng.integers(1, min(len(leaves), 20) + 1))
        sel = rng.choice(leaves, k, replace=False).tolist()
        result = session.regrow(sel, rho=float(rng.choice([0.3, 0.5, 0.9, 1.0])), min_ascend=int(rng.choice([0, 1, 3, 10**9])))
        out["regen"] = result.to_dict()
        session.derivation.skeleton()
        session.undo()
        session.redo()
        session.undo()
        after = session.tree.leaves
        if not (np.array_equal(after, before[0]) and np.array_equal(session.tree.symbol[after], before[1])):
            raise AssertionError("undo did not restore the plant")
    return json.dumps(out, allow_nan=False)


def run_one(text, rng):
    """Outcome name and seconds for one input (exceptions other than RamureError are crashes)."""
    t0 = time.perf_counter()
    signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(HANG_SECONDS)
    try:
        core_loop(text, rng)
        outcome = "ok"
    except Hang:
        outcome = "hang"
    except RamureError as exc:
        outcome = f"refused:{type(exc).__name__}"
    except RecursionError:
        outcome = "crash:RecursionError"
    except Exception as exc:  # noqa: BLE001 - the point is to count them
        outcome = f"crash:{type(exc).__name__}"
    finally:
        signal.alarm(0)
    seconds = time.perf_counter() - t0
    if outcome in ("ok",) or outcome.startswith("refused"):
        if seconds > SLOW_SECONDS:
            outcome = "slow"
    return outcome, seconds


def campaign(inputs, seed=0, keep=None, report_every=0, stream=sys.stdout):
    """Run ``inputs`` inputs; returns ``(Counter of outcomes, list of (outcome, text, trace))``."""
    rng = np.random.default_rng(seed)
    counts = collections.Counter()
    bad = []
    names = list(GENERATORS)
    core_loop("n: 2\nw: A\np:\n  A -> F[+A][-A]FA\n", rng)  # compile/warm caches: not an input's time
    t_start = time.perf_counter()
    for i in range(inputs):
        gen = names[i % len(names)]
        text = GENERATORS[gen](rng)
        outcome, seconds = run_one(text, np.random.default_rng([seed, i]))
        counts[(gen, outcome)] += 1
        if outcome.startswith(("crash", "slow", "hang")):
            trace = ""
            if outcome.startswith("crash"):
                try:
                    core_loop(text, np.random.default_rng([seed, i]))
                except Exception:  # noqa: BLE001
                    trace = traceback.format_exc(limit=-4)
            bad.append((outcome, text, trace, round(seconds, 2)))
            if keep:
                folder = pathlib.Path(keep)
                folder.mkdir(parents=True, exist_ok=True)
                (folder / f"{i:07d}_{outcome.replace(':', '_')}.lsys").write_text(text, encoding="utf-8")
        if report_every and (i + 1) % report_every == 0:
            print(
                f"{i + 1} inputs, {time.perf_counter() - t_start:.0f} s, "
                f"{sum(v for (g, o), v in counts.items() if o.startswith(('crash', 'slow', 'hang')))} bad",
                file=stream,
                flush=True,
            )
    return counts, bad


def table(counts, generators=None):
    """The outcome table: one row per outcome, one column per generator (``generators``: their
    names, this fuzzer's by default; the .g3l fuzzer passes its own)."""
    names = list(GENERATORS if generators is None else generators)
    outcomes = sorted({o for _, o in counts}, key=lambda o: (not o.startswith("crash"), o))
    width = max([len(o) for o in outcomes] + [10])
    lines = [f"{'outcome':<{width}}  " + "  ".join(f"{g:>8}" for g in names) + f"  {'total':>8}"]
    for o in outcomes:
        row = [counts.get((g, o), 0) for g in names]
        lines.append(f"{o:<{width}}  " + "  ".join(f"{v:>8}" for v in row) + f"  {sum(row):>8}")
    return "\n".join(lines)


def main(argv=None):
    p = argparse.ArgumentParser(prog="python -m tests.hardening.fuzz", description=__doc__.split("\n")[0])
    p.add_argument("--inputs", type=int, default=1000)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--keep", help="write crashing/slow inputs to this folder")
    p.add_argument("--every", type=int, default=1000, help="progress line every N inputs")
    args = p.parse_args(argv)
    sys.setrecursionlimit(max(sys.getrecursionlimit(), 3000))
    t0 = time.perf_counter()
    counts, bad = campaign(args.inputs, args.seed, args.keep, args.every)
    print(table(counts))
    print(f"{args.inputs} inputs in {time.perf_counter() - t0:.0f} s; {len(bad)} crash/slow/hang")
    for outcome, text, trace, seconds in bad[:20]:
        print(f"\n--- {outcome} ({seconds} s)\n{text[:600]}\n{trace}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
