"""The ``.g3l`` text format: 3Gmap L-systems (Guimberteau 2008, chapter 3).

A 3Gmap L-system rewrites *labelled prisms*: every symbol is a volume of a
3-G-map, and a rule applies the thesis's three operators to it -- add a volume
on one of its faces, split it, identify two free faces that share an edge.
The file format follows the ``.lsys`` files::

    # comments start with # or //
    #define iT 3.0                        a constant
    #define B(4, 0, 0, 0, stage/3 + 5, 0.4, 1)   default parameters of symbol B
    #defunc F1(H) = H + 0.5                a function (``return H + 0.5;`` also works)
    axiom: A(16, 0, 0, 0, 5, 5, 5)
    (p1) A(O, x, y, z, H, L, W) -> A[A(O, 20, y, z, F1(H), L + 0.5, W + 0.5)]_E
    (p2) A : stage < 3 -> A[B]_{C2,C4}      condition after the predecessor
    (p3) B : B_C1 < B_C3 -> B_C1 | B_C3     identify (join) two free faces
    (p4) R1 -> R[S(4)]_E                    relabel R1 as R, add S on its E face
    (p5) K ->^O W K                          split K parallel to O: W at O, K beyond
    (p6) A -> A[B]_C1 : 0.3                  stochastic: probability after the successor

Parameters of a symbol are positional ``(O, x, y, z, H, L, W)``: prism order,
three turtle angles in degrees (roll, pitch, turn of the new volume's frame
about the support face's frame), height and the two base extents; missing
ones take the symbol's ``#define`` template, else ``(4, 0, 0, 0, 1, 1, 1)``.
Order 3 is the thesis's relabelled wedge with a quad base (decision 2 of the
spec): faces O (quad, the base), C1 (quad), C2 (triangle), E (quad), C4
(triangle).  Face specs: ``_E``, ``_O``, ``_C3``, ``_C*`` (all side faces),
``_C*-2`` (all but C2), ``_{C2,C4}``, ``_C(expr)`` (index computed, taken
modulo the order).  Names usable in expressions: the predecessor's
parameters, constants, ``stage``/``step`` (global half-year counter, from 0),
``season`` (0 spring, 1 summer; ``spring`` and ``summer`` are names too),
``age`` (steps since the volume was made), ``order`` (filiation order: the
axiom is 1, a volume on a side face has its parent's order + 1), ``pi``,
``alea(a, b)`` (seeded uniform draw between the smaller and the larger bound)
and the math functions of ``.lsys`` files.

Expressions are read and evaluated by the one evaluator of both grammar
languages, :mod:`ramure.lsys.expr`: floats only, ``^`` is the power
(``2^3 == 8``), ``&& || !`` the logic, and **trigonometry is in degrees**
(``sin(90) == 1``, ``atan2(1, 0) == 90``), like the volumes' angles.  A
``#define`` or a parameter-free expression that overflows (``10^400``) is
refused when the file is read; one that overflows for a volume stops the
derivation with the rule's line and column.  Python's ``**``, ``and``,
``or``, ``not``, strings, lists, subscripts, attributes and bit operators are
refused with a caret.  Context atoms
``X_F < Y_G`` (or ``>``) hold when the volume's free face F shares an edge with a
free face G of a ``Y`` volume; a join rule identifies that pair.

Consecutive rules with the same predecessor that all end in ``: p`` form one
stochastic group: each volume picks at most one of them (probabilities sum to
at most 1; the rest is "no rule").  Any other rule fires on every matching
volume (rule-major semantics, see :mod:`ramure.gmap.lsystem.engine`).

>>> g = parse_g3l("axiom: A(4)\\n(p1) A -> A[B]_E\\n")
>>> [r.name for r in g.rules], g.axiom.symbol
(['p1'], 'A')
"""

from __future__ import annotations

import dataclasses
import math
import os
import pathlib
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NoReturn

import numpy as np

from ramure.errors import GrammarError
from ramure.io import FileRefused, read_regular
from ramure.lsys.expr import (
    Expression,
    Node,
    Source,
    compile_expression,
    evaluate_constant,
    make_function,
    names_used,
    parse_expression,
    uses_random,
)

#: The largest ``.g3l`` file read (a grammar is a few rules).
MAX_G3L_BYTES = 16 * 2**20
#: Positional parameter names of a volume symbol and their defaults.
PARAM_NAMES = ("O", "x", "y", "z", "H", "L", "W")
PARAM_DEFAULTS = (4.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0)
#: Names every expression may read besides the predecessor's parameters and the constants;
#: the engine supplies their values for each volume (``pi`` is the number, not an angle unit).
BUILTIN_NAMES = ("stage", "step", "season", "age", "order", "spring", "summer", "pi")

_SYMBOL = r"[A-Za-z][A-Za-z0-9']*"
_FACE = r"O|E|C[1-9]\d*"  # side faces count from C1
_FACE_ATOM = re.compile(rf"^({_SYMBOL})_({_FACE})$")
#: Python's words for the logical operators, refused with the operator to write instead.
_PYTHON_WORDS = re.compile(r"\b(and|or|not)\b")
_OPERATOR_FOR = {"and": "&&", "or": "||", "not": "!"}


@dataclass
class Expr:
    """An arithmetic or boolean expression, parsed and compiled once by :mod:`ramure.lsys.expr`.

    Calling it with ``(V, C, R, n)`` evaluates it for ``n`` volumes at once: ``V`` maps
    the predecessor's parameter names to arrays, ``C`` the constants and the built-in
    names (:data:`BUILTIN_NAMES`) to floats or arrays, ``R`` gives the seeded draws.
    """

    text: str
    parsed: Expression
    run: Callable
    line: int
    column: int
    random: bool

    def __call__(self, V: dict, C: dict, R: object, n: int) -> np.ndarray:
        return self.run(V, C, R, n)


@dataclass
class Call:
    """A symbol with argument expressions, e.g. ``B(4, 0, 0, 0, H * r2)``."""

    symbol: str
    args: list
    column: int


@dataclass
class FaceSpec:
    """Which faces a bracket adds on: kind 'O', 'E', 'C' (index expr), 'Call', 'Cexcept' or 'set'."""

    kind: str
    index: object = None  # Expr for 'C', list of FaceSpec for 'set', Expr for 'Cexcept'
    text: str = ""
    column: int = 0


@dataclass
class Rule:
    """One rule; ``op`` is 'add' (relabel + brackets), 'split' or 'join'."""

    name: str
    index: int
    pred: str
    pred_params: list
    op: str
    line: int
    source: str
    condition: Expr | None = None
    context: list = field(default_factory=list)  # [(face, other_symbol, other_face, column)]
    head: Call | None = None
    brackets: list = field(default_factory=list)  # [(Call, FaceSpec)]
    split_face: str = ""
    split_parts: tuple = ()
    join: tuple = ()  # (face_a, symbol_b, face_b)
    probability: Expr | None = None
    group: int = -1


@dataclass
class Grammar:
    """A parsed ``.g3l`` file."""

    constants: dict
    templates: dict
    functions: dict
    axiom: Call
    rules: list
    steps: int | None = None
    filename: str | None = None
    lines: list = field(default_factory=list)

    def error(self, message: str, line: int | None, column: int | None) -> GrammarError:
        """A :class:`GrammarError` pointing at ``line``/``column`` of this grammar."""
        src = self.lines[line - 1] if line and 0 < line <= len(self.lines) else None
        return GrammarError(message, line, column, src, self.filename)


class _Parser:
    def __init__(self, text, filename=None) -> None:
        self.filename = filename
        self.lines = text.splitlines()
        self.constants: dict = {}
        self.templates: dict = {}
        self.functions: dict = {}
        self.rules: list = []
        self.axiom: Call | None = None
        self.steps: int | None = None

    def fail(self, message: str, line: int, column: int) -> NoReturn:
        src = self.lines[line - 1] if 0 < line <= len(self.lines) else None
        raise GrammarError(message, line, column, src, self.filename)

    # -------------------------------------------------------------- expressions
    def names(self) -> list[str]:
        """Names an expression may read besides its rule's parameters: constants so far and the built-ins."""
        return [*self.constants, *BUILTIN_NAMES]

    def source(self, text, line, column):
        """``text`` (its first character at ``column``) as a :class:`Source` for the shared evaluator."""
        src = text.strip()
        col = column + (len(text) - len(text.lstrip()))
        if not src:
            self.fail("an expression is missing", line, col)
        if "**" in src:
            self.fail("'**' is not an operator: powers are written '^'", line, col + src.index("**"))
        word = _PYTHON_WORDS.search(src)
        if word:
            self.fail(f"'{word.group(1)}' is not an operator: write '{_OPERATOR_FOR[word.group(1)]}'", line, col + word.start())
        return src, Source(src, line, col, self.lines[line - 1] if 0 < line <= len(self.lines) else None)

    def parsed(self, text, line, column):
        """``text`` parsed by the shared evaluator's parser: (stripped text, Expression)."""
        src, source = self.source(text, line, column)
        try:
            return src, parse_expression(source, functions=self.functions)
        except GrammarError as err:
            self.fail(f"cannot read the expression {src!r}: {err.message}", line, err.column or source.column)

    def expr(self, text, line, column, extra=(), context=False):
        """A compiled :class:`Expr`; with ``context``, face atoms ``X_F < Y_G`` are read out.

        Returns the Expr, or ``(Expr, atoms)`` with ``context``: the atoms are checked on
        the map by the engine and stand for true in the compiled condition.
        """
        src, parsed = self.parsed(text, line, column)
        atoms: list = []
        if context:
            parsed = Expression(_strip_atoms(parsed.node, atoms, parsed.src.column), parsed.src)
        try:
            run = compile_expression(parsed, extra, self.names())
        except GrammarError as err:
            self.fail(err.message, line, err.column or column)
        e = Expr(src, parsed, run, line, parsed.src.column, uses_random(parsed))
        if not e.random and {name for name, _ in names_used(parsed)} <= set(self.constants):
            self.value(parsed, line, column)  # no per-volume value: 10^400 or 1/0 is refused now, not at step k
        return (e, atoms) if context else e

    def constant(self, text, line, column) -> float:
        """The value of a ``#define`` expression: finite, or a GrammarError (overflow, 0/0, unknown name)."""
        return self.value(self.parsed(text, line, column)[1], line, column)

    def value(self, parsed, line, column) -> float:
        values = {**self.constants, "pi": math.pi}
        try:
            return evaluate_constant(parsed, values)
        except GrammarError as err:
            self.fail(err.message, line, err.column or column)

    # -------------------------------------------------------------- lines
    def parse(self):
        for no, raw in enumerate(self.lines, 1):
            text = re.split(r"//|(?<![\w)])#(?!define|defunc|steps)", raw, maxsplit=1)[0]
            if raw.lstrip().startswith("#") and not re.match(r"\s*#(define|defunc|steps)\b", raw, re.I):
                continue
            if not text.strip():
                continue
            stripped = text.strip()
            col = len(text) - len(text.lstrip()) + 1
            low = stripped.lower()
            if low.startswith("#define"):
                self.define(text, no)
            elif low.startswith("#defunc"):
                self.defunc(text, no)
            elif low.startswith("#steps"):
                self.steps_line(text, no)
            elif low.startswith("axiom"):
                body = text[text.index(":") + 1 :] if ":" in text else self.fail("axiom needs ':'", no, col)
                self.axiom = self.call(body, no, text.index(":") + 2, params=())
            else:
                self.rule(text, no)
        if self.axiom is None:
            self.fail("the grammar has no 'axiom:' line", max(len(self.lines), 1), 1)
        self.group_stochastic()
        return Grammar(
            self.constants, self.templates, self.functions, self.axiom, self.rules, self.steps, self.filename, self.lines
        )

    def steps_line(self, text, no) -> None:
        m = re.match(r"\s*#steps\s+(\d+)\s*;?\s*$", text, re.I)
        if not m:
            self.fail("#steps expects a whole number", no, len(text) - len(text.lstrip()) + 1)
        self.steps = int(m.group(1))

    def define(self, text, no) -> None:
        start = text.lower().index("#define") + len("#define")
        body = text[start:].rstrip().rstrip(";")
        m = re.match(r"\s*([A-Za-z_]\w*)\s*(\(|=)?", body)
        if not m:
            self.fail("#define expects NAME value", no, start + 2)
        name = m.group(1)
        self.check_name(name, no, start + 1 + m.start(1))
        if m.group(2) == "(":  # a volume template B(4, ...)
            call = self.call(body, no, start + 1, params=())
            self.templates[name] = call
            return
        rest = body[m.end() :] if m.group(2) == "=" else body[m.end(1) :]
        # several "NAME = value ;" on one line (Table 3.3 style)
        pieces = [rest] if ";" not in rest else None
        if pieces is None:
            self.define_many(body, no, start + 1)
            return
        self.constants[name] = self.constant(rest, no, start + 1 + m.end(1) + (1 if m.group(2) else 0))

    def check_name(self, name, no, col) -> None:
        if name in BUILTIN_NAMES:
            self.fail(f"'{name}' is a built-in name ({', '.join(BUILTIN_NAMES)}): choose another", no, col)

    def define_many(self, body, no, col) -> None:
        for part in body.split(";"):
            if not part.strip():
                continue
            name, sep, value = part.partition("=")
            if not sep:
                self.fail("#define expects NAME = value", no, col)
            if not re.match(r"\s*[A-Za-z_]\w*\s*$", name):
                self.fail(f"#define expects NAME = value, got {name.strip()!r}", no, col + body.index(part))
            self.check_name(name.strip(), no, col + body.index(part))
            self.constants[name.strip()] = self.constant(value, no, col + body.index(part) + len(name) + 1)

    def defunc(self, text, no) -> None:
        start = text.lower().index("#defunc") + len("#defunc")
        lead = len(text[start:]) - len(text[start:].lstrip())
        body = text[start:].strip()
        m = re.match(r"([A-Za-z_]\w*)\s*\(([^)]*)\)\s*(\{)?\s*(=|return)?\s*(.*)$", body)
        if not m or not m.group(5).strip():
            self.fail("#defunc expects NAME(args) = expression", no, start + 2)
        name, args = m.group(1), [a.strip() for a in m.group(2).split(",") if a.strip()]
        if any(not re.match(r"[A-Za-z_]\w*$", a) for a in args) or len(set(args)) != len(args):
            self.fail(f"the parameters of {name} must be distinct names", no, start + lead + m.start(2) + 1)
        expr_text = m.group(5).rstrip().rstrip("}").rstrip().rstrip(";")
        at = start + lead + m.start(5)
        if expr_text.startswith("return"):
            expr_text, at = expr_text[len("return") :], at + len("return")
        _, source = self.source(expr_text, no, at + 1)
        try:
            self.functions[name] = make_function(name, args, source, self.functions, self.names())
        except GrammarError as err:
            self.fail(err.message, no, err.column or at + 1)

    # -------------------------------------------------------------- symbols
    def call(self, text, no, column, params):
        """``B(4, H*2)`` -> Call; column is the 1-based column of ``text[0]``."""
        s = text.strip()
        col = column + (len(text) - len(text.lstrip()))
        m = re.match(_SYMBOL, s)
        if not m:
            self.fail(f"expected a symbol, got {s[:12]!r}", no, col)
        sym = m.group(0)
        rest = s[m.end() :].strip()
        if not rest:
            return Call(sym, [], col)
        if rest.startswith("(") and _matching(rest, 0, "(", ")") < 0:
            self.fail("this '(' is not closed", no, col + s.index("("))
        if not rest.startswith("(") or not rest.endswith(")"):
            self.fail(f"unexpected text after {sym!r}", no, col + m.end())
        inner = rest[1:-1]
        args, off = [], col + s.index("(") + 1
        for piece in _split_top(inner, ","):
            args.append(self.expr(piece, no, off, extra=params) if piece.strip() else None)
            off += len(piece) + 1
        if len(args) > len(PARAM_NAMES):
            self.fail(f"{sym} takes at most {len(PARAM_NAMES)} parameters {PARAM_NAMES}", no, col)
        return Call(sym, args, col)

    def pred(self, text, no, col):
        s = text.strip()
        m = re.match(rf"({_SYMBOL})\s*(\(([^)]*)\))?\s*$", s)
        if not m:
            self.fail(f"cannot read the predecessor {s!r}", no, col)
        params = [p.strip() for p in (m.group(3) or "").split(",") if p.strip()]
        for p in params:
            if not re.match(r"^[A-Za-z_]\w*$", p):
                self.fail(f"predecessor parameters must be names, got {p!r}", no, col + s.index(p))
        if len(params) > len(PARAM_NAMES) or len(set(params)) != len(params):
            self.fail(f"a predecessor takes at most {len(PARAM_NAMES)} distinct parameter names {PARAM_NAMES}", no, col)
        return m.group(1), params

    def rule(self, text, no) -> None:
        m = re.match(r"\s*(\(\s*(\w+)\s*\)|(\w+)\s*:(?=.*(->|→)))?", text)
        name = (m.group(2) or m.group(3)) if m else None
        body_start = m.end() if m and m.group(1) else 0
        body = text[body_start:]
        arrow = re.search(r"->\^?|→\^?", body)
        if not arrow:
            self.fail("a rule needs '->'", no, body_start + len(body) - len(body.lstrip()) + 1)
        left, right = body[: arrow.start()], body[arrow.end() :]
        lcol = body_start + 1
        rcol = body_start + arrow.end() + 1
        pred_text, _, cond_text = left.partition(":")
        pred, params = self.pred(pred_text, no, lcol)
        rule = Rule(name or f"p{len(self.rules) + 1}", len(self.rules), pred, params, "add", no, text.strip())
        if cond_text.strip():
            ccol = lcol + len(pred_text) + 1
            rule.condition, rule.context = self.expr(cond_text, no, ccol, extra=params, context=True)
        succ, prob_text, pcol = _split_probability(right, rcol)
        if prob_text is not None:
            rule.probability = self.expr(prob_text, no, pcol, extra=params)
        if arrow.group(0).endswith("^"):
            self.split_rule(rule, succ, no, rcol)
        elif "|" in succ:
            self.join_rule(rule, succ, no, rcol)
        else:
            self.add_rule(rule, succ, no, rcol, params)
        self.rules.append(rule)

    def split_rule(self, rule, succ, no, col) -> None:
        m = re.match(rf"\s*({_FACE})\s+({_SYMBOL})\s+({_SYMBOL})\s*$", succ)
        if not m:
            self.fail("a split is written 'A ->^F B C' (F = O, E or Ck)", no, col)
        rule.op, rule.split_face, rule.split_parts = "split", m.group(1), (m.group(2), m.group(3))

    def join_rule(self, rule, succ, no, col) -> None:
        m = re.match(rf"\s*({_SYMBOL})_({_FACE})\s*\|\s*({_SYMBOL})_({_FACE})\s*$", succ)
        if not m:
            self.fail("an identification is written 'X_F | Y_G'", no, col)
        if m.group(1) != rule.pred:
            self.fail(f"the left face of '|' must belong to the predecessor {rule.pred}", no, col)
        rule.op, rule.join = "join", (m.group(2), m.group(3), m.group(4))

    def add_rule(self, rule, succ, no, col, params) -> None:
        s = succ
        head_end = _find_bracket(s)
        rule.head = self.call(s[:head_end], no, col, params)
        pos = head_end
        while pos < len(s) and s[pos:].strip():
            while s[pos].isspace():
                pos += 1
            if s[pos] != "[":
                self.fail("expected '[' starting an added volume", no, col + pos)
            close = _matching(s, pos, "[", "]")
            if close < 0:
                self.fail("this '[' is not closed", no, col + pos)
            child = self.call(s[pos + 1 : close], no, col + pos + 1, params)
            pos = close + 1
            if not s[pos:].startswith("_"):
                self.fail("an added volume needs a face: ']_E', ']_C*', ...", no, col + pos)
            spec, pos = self.face_spec(s, pos + 1, no, col, params)
            rule.brackets.append((child, spec))

    def face_spec(self, s, pos, no, col, params):
        start = pos
        if pos >= len(s):
            self.fail("an added volume needs a face after '_': O, E, Ck, C*, C*-k or {...}", no, col + pos - 1)
        if s[pos] == "{":
            close = _matching(s, pos, "{", "}")
            if close < 0:
                self.fail("this '{' is not closed", no, col + pos)
            parts, off = [], pos + 1
            for piece in _split_top(s[pos + 1 : close], ","):
                lead = len(piece) - len(piece.lstrip())
                sub, _ = self.face_spec(piece.strip() + " ", 0, no, col + off + lead, params)
                parts.append(sub)
                off += len(piece) + 1
            return FaceSpec("set", parts, s[start : close + 1], col + start), close + 1
        if s.startswith("C(", pos):
            close = _matching(s, pos + 1, "(", ")")
            if close < 0:
                self.fail("this '(' is not closed", no, col + pos + 1)
            e = self.expr(s[pos + 2 : close], no, col + pos + 2, extra=params)
            return FaceSpec("C", e, s[pos : close + 1], col + pos), close + 1
        m = re.match(r"(O|E)\b|C\*-\s*(\w+|\([^)]*\))|C\*|C(\d+)|C([A-Za-z_]\w*)", s[pos:])
        if not m:
            self.fail(f"unknown face {s[pos : pos + 6].strip()!r}: expected O, E, Ck, C*, C*-k or {{...}}", no, col + pos)
        text, end = m.group(0), pos + m.end()
        if m.group(1):
            return FaceSpec(m.group(1), None, text, col + pos), end
        if m.group(2):
            e = self.expr(m.group(2).strip("()"), no, col + pos + 3, extra=params)
            return FaceSpec("Cexcept", e, text, col + pos), end
        if text == "C*":
            return FaceSpec("Call", None, text, col + pos), end
        if m.group(3) and int(m.group(3)) == 0:
            self.fail("side faces count from C1", no, col + pos)
        expr_text = m.group(3) or m.group(4)
        e = self.expr(expr_text, no, col + pos + 1, extra=params)
        return FaceSpec("C", e, text, col + pos), end

    def group_stochastic(self) -> None:
        group = 0
        i = 0
        while i < len(self.rules):
            r = self.rules[i]
            if r.probability is None:
                i += 1
                continue
            j = i
            while j < len(self.rules) and self.rules[j].pred == r.pred and self.rules[j].probability is not None:
                self.rules[j].group = group
                j += 1
            group += 1
            i = j


def _strip_atoms(node: Node, atoms: list, column: int) -> Node:
    """``node`` with each context atom ``X_F < Y_G`` (or ``>``) replaced by 1 (true), listed in ``atoms``."""
    if node.kind == "binary" and node.value in ("<", ">") and all(a.kind == "name" for a in node.args):
        a, b = (_FACE_ATOM.match(str(arg.value)) for arg in node.args)
        if a and b:
            atoms.append((a.group(2), b.group(1), b.group(2), column + node.args[0].offset))
            return Node("num", 1.0, (), node.offset)
    if not node.args:
        return node
    return dataclasses.replace(node, args=tuple(_strip_atoms(arg, atoms, column) for arg in node.args))


def _split_top(text, sep):
    """Split on ``sep`` outside parentheses and braces."""
    out: list[str] = []
    cur: list[str] = []
    depth = 0
    for ch in text:
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        if ch == sep and depth == 0:
            out.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    out.append("".join(cur))
    return out


def _matching(s, pos, open_, close):
    depth = 0
    for i in range(pos, len(s)):
        if s[i] == open_:
            depth += 1
        elif s[i] == close:
            depth -= 1
            if depth == 0:
                return i
    return -1


def _find_bracket(s):
    depth = 0
    for i, ch in enumerate(s):
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
        elif ch == "[" and depth == 0:
            return i
    return len(s)


def _split_probability(right, col):
    """``succ : prob`` -> (succ, prob_text or None, prob column); ':' outside brackets."""
    depth = 0
    for i, ch in enumerate(right):
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        elif ch == ":" and depth == 0:
            return right[:i], right[i + 1 :], col + i + 1
    return right, None, col


def parse_g3l(text: str, filename: str | None = None) -> Grammar:
    """Parse the text of a ``.g3l`` grammar; :class:`GrammarError` with line, column and caret."""
    return _Parser(text, filename).parse()


def load_g3l(path: str | os.PathLike) -> Grammar:
    """Parse a ``.g3l`` file (a path, or the name of a shipped grammar such as ``"wood/spiral"``)."""
    p = pathlib.Path(path)
    if not p.exists():
        from ramure import grammars

        name = str(path).replace("\\", "/")
        name = name[len("grammars/") :] if name.startswith("grammars/") else name
        cand = grammars.FOLDER / (name if name.endswith(".g3l") else f"{name}.g3l")
        if ".." not in pathlib.PurePosixPath(name).parts and cand.is_file():
            p = cand
    try:
        raw = read_regular(p, MAX_G3L_BYTES, ".g3l grammar")
    except FileRefused as err:
        raise GrammarError(f"cannot read {path}: {err.reason}", filename=str(path)) from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        line = raw[: err.start].count(b"\n") + 1
        raise GrammarError("the file is not UTF-8 text", line, 1, None, str(path)) from None
    return parse_g3l(text, str(p))
