"""Fuzz the whole core loop: parse -> derive and draw -> metrics -> regrow/undo -> JSON.

Run from the repository root::

    python -m tests.hardening.fuzz --inputs 100000            # the long campaign
    python -m tests.hardening.fuzz --inputs 500 --seed 3      # a slice

Each input is a grammar text from one of three generators: ``aware`` builds
grammars from the language's own pieces (parametric modules, expressions,
stochastic and context rules, conditions, directives, shipped grammars with
extreme values), ``grammar`` mutates shipped grammars a token at a time (a
number, a module, a rule, ``n``: edits that keep the text a grammar), ``random``
mutates shipped grammars character by character.  Every input goes through the
whole loop at n <= 6, through the model the front ends use
(:class:`ramure.app.model.Explorer`): open, draw, measure, select leaves, regrow,
undo, redo, undo.  The outcome is one of ``ok``, ``refused:<RamureError
subclass>``, ``crash:<exception type>`` (a bug: anything but a RamureError),
``slow`` (over 5 s), ``hang`` (stopped after 30 s of CPU or 300 s of waiting); the stage is the
deepest one the input reached (:data:`STAGES`).  The tables printed at the end
count each outcome and each stage; the first crashing inputs are kept in full
(``--keep DIR`` writes them to files).  Goal: zero crashes, zero slow inputs,
at least half of the inputs through regrow and undo.
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import json
import pathlib
import re
import sys
import time
import traceback

import numpy as np

from ramure.errors import RamureError, ValueRefused
from ramure.lsys import LSystem
from tests.hardening.watchdog import Hang, bounded

GRAMMARS = sorted((pathlib.Path(__file__).resolve().parents[2] / "grammars").glob("*.lsys"))
TEXTS = [p.read_text(encoding="utf-8") for p in GRAMMARS]
SLOW_SECONDS = 5.0
HANG_SECONDS = 30
#: Derivation steps of one input (a grammar's larger ``n:`` is lowered to this).
MAX_N = 6
#: Module budget of one input: a larger plant is refused by the derivation's own limit
#: (``LSystem.max_modules``, 20 M for a user), as the 2.9 M modules of a Koch island given a
#: rule of 9 F were (7.3 s of CPU through the loop).  Large plants' speed is benchmarked
#: in benchmarks/bench_large_edits.py.
MAX_MODULES = 1_500_000

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


# -- generators ---------------------------------------------------------------------------------
def _number(rng):
    if rng.random() < 0.15:
        return str(rng.choice(EXTREMES))
    return f"{rng.uniform(-100, 100):.3g}" if rng.random() < 0.5 else str(int(rng.integers(0, 90)))


def _module(rng, params, depth=0, arity=None):
    """A module; with ``arity`` (symbol -> parameter count) mostly of the symbol's own count."""
    sym = str(rng.choice(list(SYMBOLS)))
    if arity is not None and rng.random() < 0.97:
        args = [_expr(rng, params, depth) for _ in range(arity[sym])]
        return f"{sym}({','.join(args)})" if args else sym
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


def _string(rng, params, length, arity=None):
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
            out.append(_module(rng, params, arity=arity))
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
    # one parameter count per symbol, as the language asks (a few inputs break it on purpose)
    arity = {sym: int(rng.choice([0, 0, 1, 2] if sym.isalpha() else [0, 0, 1])) for sym in SYMBOLS}
    lines.append(f"w: {_string(rng, [], int(rng.integers(1, 6)), arity)}")
    lines.append("p:")
    for sym in rng.permutation(list("ABFXYG"))[: int(rng.integers(1, 5))]:  # distinct predecessors
        params = ["x", "y"][: arity[str(sym)]]
        pred = str(sym) + (f"({','.join(params)})" if params else "")
        if rng.random() < 0.15:  # a stochastic pair: probabilities that sum to 1
            p = round(float(rng.uniform(0.05, 0.95)), 2)
            for prob in (p, round(1 - p, 2)):
                lines.append(f"  {prob} {pred} -> {_string(rng, params, int(rng.integers(0, 6)), arity)}")
            continue
        left = f"{rng.choice(list('ABF'))} < " if rng.random() < 0.1 else ""
        right = f" > {rng.choice(list('ABF'))}" if rng.random() < 0.1 else ""
        cond = f" : {params[0]} > {_number(rng)}" if params and rng.random() < 0.2 else ""
        succ = _string(rng, params, int(rng.integers(0, 6)), arity)
        lines.append(f"  {left}{pred}{right}{cond} -> {succ}")
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


NUMBER = re.compile(r"(?<![A-Za-z_\d.])\d+(?:\.\d+)?(?:e[-+]?\d+)?")
MODULE = re.compile(r"[A-Z+\-&^\\/|!$'](?:\([^()]*\))?")


def _rule_lines(lines):
    return [i for i, line in enumerate(lines) if "->" in line]


def _edit_rule(rng, line):
    """One token edit in the successor of a rule line."""
    head, _, succ = line.partition("->")
    modules = list(MODULE.finditer(succ))
    op = rng.random()
    if modules and op < 0.3:  # drop one module
        m = modules[int(rng.integers(len(modules)))]
        succ = succ[: m.start()] + succ[m.end() :]
    elif modules and op < 0.55:  # another symbol, same arguments
        m = modules[int(rng.integers(len(modules)))]
        succ = succ[: m.start()] + str(rng.choice(list(SYMBOLS))) + succ[m.start() + 1 :]
    elif op < 0.8:  # insert a module, or a branch of one
        at = modules[int(rng.integers(len(modules)))].end() if modules else len(succ)
        piece = _module(rng, [])
        succ = succ[:at] + (f"[{piece}]" if rng.random() < 0.4 else piece) + succ[at:]
    else:  # a number of the successor changed
        numbers = list(NUMBER.finditer(succ))
        if numbers:
            m = numbers[int(rng.integers(len(numbers)))]
            succ = succ[: m.start()] + _number(rng) + succ[m.end() :]
    return f"{head}->{succ}"


def grammar_mutation(rng):
    """A shipped grammar with 1-3 edits that keep it a grammar: a number, a module of a
    successor, a rule repeated with a probability, ``n`` (at most :data:`MAX_N`)."""
    lines = str(rng.choice(TEXTS)).split("\n")
    for _ in range(int(rng.integers(1, 4))):
        rules = _rule_lines(lines)
        op = rng.random()
        if rules and op < 0.55:
            i = int(rng.choice(rules))
            lines[i] = _edit_rule(rng, lines[i])
        elif op < 0.7:
            defines = [i for i, line in enumerate(lines) if line.startswith("#define") and len(line.split()) >= 3]
            if defines:
                i = int(rng.choice(defines))
                parts = lines[i].split()
                parts[2] = _number(rng)
                lines[i] = " ".join(parts)
        elif rules and op < 0.85:  # a rule repeated: a choice between two, or a second match
            i = int(rng.choice(rules))
            lines.insert(i + 1, _edit_rule(rng, lines[i]))
        else:
            lines = [f"n: {int(rng.integers(0, MAX_N + 1))}" if line.startswith("n:") else line for line in lines]
    return "\n".join(lines)


GENERATORS = {"aware": aware, "grammar": grammar_mutation, "random": mutate}
#: The stages of the loop, in order; an input's stage is the deepest one it finished.
STAGES = ("none", "parse", "draw", "metrics", "regrow", "undo", "json")


# -- the loop -----------------------------------------------------------------------------------
def core_loop(text, rng, reached=None):
    """Everything a user does with one grammar, through the front ends' model; returns the JSON
    it printed.  ``reached`` (a list) gets the name of each stage as it finishes."""
    reached = [] if reached is None else reached
    with module_budget():
        return _core_loop(text, rng, reached)


@contextlib.contextmanager
def module_budget(limit: int = MAX_MODULES):
    """Lower ``LSystem.max_modules`` to ``limit`` for the block (the fuzzer's budget)."""
    old = LSystem.max_modules
    LSystem.max_modules = min(limit, old)
    try:
        yield
    finally:
        LSystem.max_modules = old


def _core_loop(text, rng, reached):
    from ramure.app.model import Explorer
    from ramure.metrics import plant_metrics

    n = min(LSystem.from_text(text).n, MAX_N)
    reached.append("parse")
    ex = Explorer(text, n=n, seed=int(rng.integers(0, 1000)))  # derived and drawn, or refused
    sk = ex.skeleton
    reached.append("draw")
    out = {"modules": len(ex.derivation), "segments": int(len(sk.start))}
    if len(sk.start):
        m = plant_metrics(sk)
        fields = vars(m) if hasattr(m, "__dict__") else {}
        out["metrics"] = {k: float(v) for k, v in fields.items() if isinstance(v, (int, float, np.floating))} or str(m)
    reached.append("metrics")
    leaves = ex.session.tree.leaves
    if len(leaves):
        before = (leaves.copy(), ex.session.tree.symbol[leaves].copy())
        k = int(rng.integers(1, min(len(leaves), 20) + 1))
        ex.select(rng.choice(leaves, k, replace=False))
        ex.set_rho(float(rng.choice([0.3, 0.5, 0.9, 1.0])))
        try:
            out["regen"] = ex.regrow().to_dict()
        except ValueRefused:  # "nothing regrows": the user regrows the whole plant instead
            ex.clear_selection()
            out["regen"] = ex.regrow().to_dict()
        out["segments_after"] = int(len(ex.skeleton.start))  # the regrown plant is drawn
        reached.append("regrow")
        ex.undo()
        ex.redo()
        ex.undo()
        after = ex.session.tree.leaves
        if not (np.array_equal(after, before[0]) and np.array_equal(ex.session.tree.symbol[after], before[1])):
            raise AssertionError("undo did not restore the plant")
        reached.append("undo")
    text = json.dumps(out, allow_nan=False)
    reached.append("json")
    return text


def run_one(text, rng):
    """Outcome name, seconds and the deepest stage reached for one input (exceptions other
    than RamureError are crashes)."""
    t0 = time.process_time()  # CPU seconds: the wall clock also counts the other jobs of a shared machine
    reached = ["none"]
    try:
        with bounded(HANG_SECONDS):
            core_loop(text, rng, reached)
        outcome = "ok"
    except Hang:
        outcome = "hang"
    except RamureError as exc:
        outcome = f"refused:{type(exc).__name__}"
    except RecursionError:
        outcome = "crash:RecursionError"
    except Exception as exc:  # noqa: BLE001 - the point is to count them
        outcome = f"crash:{type(exc).__name__}"
    seconds = time.process_time() - t0
    if outcome in ("ok",) or outcome.startswith("refused"):
        if seconds > SLOW_SECONDS:
            outcome = "slow"
    return outcome, seconds, reached[-1]


def campaign(inputs, seed=0, keep=None, report_every=0, stream=sys.stdout, stages=None):
    """Run ``inputs`` inputs; returns ``(Counter of outcomes, list of (outcome, text, trace))``.
    ``stages`` (a Counter) gets ``(generator, stage)`` for each input: the deepest stage reached."""
    rng = np.random.default_rng(seed)
    counts = collections.Counter()
    stages = collections.Counter() if stages is None else stages
    bad = []
    names = list(GENERATORS)
    core_loop("n: 2\nw: A\np:\n  A -> F[+A][-A]FA\n", rng)  # compile/warm caches: not an input's time
    t_start = time.perf_counter()
    for i in range(inputs):
        gen = names[i % len(names)]
        text = GENERATORS[gen](rng)
        outcome, seconds, stage = run_one(text, np.random.default_rng([seed, i]))
        counts[(gen, outcome)] += 1
        stages[(gen, stage)] += 1
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


def reader_campaign_main(campaign, doc: str, argv: list[str] | None = None) -> int:
    """The command line of a reader fuzzer (studies, files): ``--inputs``, ``--seed``; prints the
    counts per (reader, outcome) and a JSON summary; 1 if any input was neither ok nor refused."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--inputs", type=int, default=3000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    start = time.perf_counter()
    counts = campaign(args.inputs, args.seed)
    for (kind, outcome), n in sorted(counts.items()):
        print(f"{kind:12s} {outcome:24s} {n}")
    bad = sum(n for (_, outcome), n in counts.items() if outcome not in ("ok", "refused"))
    print(json.dumps(dict(inputs=args.inputs, seconds=round(time.perf_counter() - start, 1), bad=bad)))
    return 1 if bad else 0


def stage_table(stages, generators=None):
    """Inputs per deepest stage reached (rows in loop order), one column per generator, and the
    share that got through regrow and undo."""
    names = list(GENERATORS if generators is None else generators)
    lines = [f"{'stage':<8}  " + "  ".join(f"{g:>8}" for g in names) + f"  {'total':>8}"]
    for stage in STAGES:
        row = [stages.get((g, stage), 0) for g in names]
        lines.append(f"{stage:<8}  " + "  ".join(f"{v:>8}" for v in row) + f"  {sum(row):>8}")
    lines.append(f"through regrow and undo: {deep_share(stages):.1%}")
    return "\n".join(lines)


def deep_share(stages):
    """The share of inputs that got through regrow and undo."""
    total = sum(stages.values())
    deep = sum(v for (_, stage), v in stages.items() if STAGES.index(stage) >= STAGES.index("undo"))
    return deep / total if total else 0.0


def main(argv=None):
    p = argparse.ArgumentParser(prog="python -m tests.hardening.fuzz", description=__doc__.split("\n")[0])
    p.add_argument("--inputs", type=int, default=1000)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--keep", help="write crashing/slow inputs to this folder")
    p.add_argument("--every", type=int, default=1000, help="progress line every N inputs")
    args = p.parse_args(argv)
    sys.setrecursionlimit(max(sys.getrecursionlimit(), 3000))
    t0 = time.perf_counter()
    stages = collections.Counter()
    counts, bad = campaign(args.inputs, args.seed, args.keep, args.every, stages=stages)
    print(table(counts))
    print(stage_table(stages))
    print(f"{args.inputs} inputs in {time.perf_counter() - t0:.0f} s; {len(bad)} crash/slow/hang")
    for outcome, text, trace, seconds in bad[:20]:
        print(f"\n--- {outcome} ({seconds} s)\n{text[:600]}\n{trace}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
