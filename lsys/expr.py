"""Arithmetic and logical expressions of the grammar language, compiled to numpy.

An expression is parsed once (a small Pratt parser) and compiled to a Python
function that evaluates it for *all* modules matched by a rule at once: formal
parameters are numpy arrays, constants are looked up at call time (so editing
``LSystem.constants`` needs no re-parse).

Precedence, lowest first: C's ``c ? a : b`` (right-associative); ``||``; ``&&``; ``== != =``; ``< > <= >=``;
``+ -``; ``* / %``; unary ``- + !``; ``^`` (right-associative, so
``-2^2 == -4``).  ``=`` is equality, as in ABOP conditions.

Functions: ``sin cos tan asin acos atan atan2 sqrt exp log abs min max floor
ceil round int`` (``int`` truncates toward zero, ``round`` halves to even) and
the seeded random draws ``uniform(a, b)``, ``alea(a, b)`` (uniform between the
smaller and the larger of ``a`` and ``b``) and ``normal(mean, sd)``.
**Trigonometry is in degrees** (``sin(90) == 1``, ``atan(1) == 45``,
``atan2(1, 0) == 90``), like turtle angles.

Every value is a float: there are no strings, lists, attributes or bit
operators, and a power that overflows gives ``inf`` (no big integers, so no
hang).  This one evaluator serves both grammar languages, ``.lsys`` and the
3Gmap L-systems of ``.g3l`` files (:mod:`ramure.gmap.lsystem.g3l`).

>>> e = parse_expression("x * r1 + 1")
>>> import numpy as np
>>> compile_expression(e, params=["x"], constants={"r1": 2.0})(
...     {"x": np.array([1.0, 2.0])}, {"r1": 2.0}, None, 2).tolist()
[3.0, 5.0]
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from .errors import GrammarError
from collections.abc import Callable, Iterable, Mapping

FUNCTIONS = {
    # name: (arity, numpy source template); trig works in degrees.
    "sin": (1, "np.sin(np.radians({0}))"),
    "cos": (1, "np.cos(np.radians({0}))"),
    "tan": (1, "np.tan(np.radians({0}))"),
    "asin": (1, "np.degrees(np.arcsin({0}))"),
    "acos": (1, "np.degrees(np.arccos({0}))"),
    "atan": (1, "np.degrees(np.arctan({0}))"),
    "atan2": (2, "np.degrees(np.arctan2({0}, {1}))"),
    "sqrt": (1, "np.sqrt({0})"),
    "exp": (1, "np.exp({0})"),
    "log": (1, "np.log({0})"),
    "abs": (1, "np.abs({0})"),
    "floor": (1, "np.floor({0})"),
    "ceil": (1, "np.ceil({0})"),
    "round": (1, "np.round({0})"),
    "int": (1, "np.trunc({0})"),
    "min": (2, "np.minimum({0}, {1})"),
    "max": (2, "np.maximum({0}, {1})"),
    "uniform": (2, "R.uniform({0}, {1}, n)"),
    "normal": (2, "R.normal({0}, {1}, n)"),
    "alea": (2, "_alea(R, {0}, {1}, n)"),
}
RANDOM_FUNCTIONS = {"uniform", "normal", "alea"}

_BINARY = {
    # Comparisons and logic give 1.0 / 0.0 (not booleans), so -(x < 1) and
    # (a < b) - (c < d) are ordinary arithmetic.
    "||": (1, "_f(np.logical_or({0}, {1}))"),
    "&&": (2, "_f(np.logical_and({0}, {1}))"),
    "==": (3, "_f({0} == {1})"),
    "=": (3, "_f({0} == {1})"),
    "!=": (3, "_f({0} != {1})"),
    "<": (4, "_f({0} < {1})"),
    ">": (4, "_f({0} > {1})"),
    "<=": (4, "_f({0} <= {1})"),
    ">=": (4, "_f({0} >= {1})"),
    "+": (5, "({0} + {1})"),
    "-": (5, "({0} - {1})"),
    "*": (6, "({0} * {1})"),
    "/": (6, "({0} / {1})"),
    "%": (6, "np.mod({0}, {1})"),
    "^": (8, "np.power({0}, {1})"),
}
_UNARY_PRECEDENCE = 7
#: Deepest expression tree accepted: the compiled Python code nests one or two
#: parentheses per level and Python refuses more than 200.
MAX_DEPTH = 64
#: Deepest nesting of parentheses, unary signs and right-associative powers the
#: (recursive) parser follows before refusing.
MAX_NESTING = 100
#: Most operations an expression may expand to once user functions are inlined.
MAX_NODES = 10_000
_OPERATORS = sorted(_BINARY, key=len, reverse=True) + ["!"]


@dataclass(frozen=True)
class Token:
    kind: str  # 'num', 'name', 'op', '(', ')', ',', 'end'
    text: str
    offset: int


@dataclass(frozen=True)
class Node:
    """One expression node: ``kind`` is num, name, call, unary or binary."""

    kind: str  # num, name, const (a constant named in a user function), call, unary, binary
    value: object
    args: tuple = ()
    offset: int = 0
    depth: int = 1
    size: int = 1


@dataclass(frozen=True)
class Function:
    """A user function (``#function f(x, y) = expr``): parameter names and body, inlined where called."""

    name: str
    params: tuple
    body: Node


@dataclass(frozen=True)
class Tables:
    """Functions of one variable given as values at evenly spaced x in [0, 1], called as
    ``func(id, x)`` (cpfg's user functions, ids from 1; :mod:`ramure.lsys.language.cpfg_functions`):
    linear between the values, ``x`` clamped to [0, 1].  Put in a parser's ``functions``
    under the name ``func``."""

    values: tuple  # one tuple of floats per function


class Source:
    """A piece of grammar text with its position, to point errors at the right column."""

    def __init__(self, text: str, line: int | None = None, column: int = 1, source_line: str | None = None) -> None:
        self.text = text
        self.line = line
        self.column = column
        self.source_line = source_line if source_line is not None else text

    def error(self, message: str, offset: int = 0, cls: type[GrammarError] = GrammarError) -> GrammarError:
        return cls(message, self.line, self.column + offset, self.source_line)


def tokenize(src: Source) -> list[Token]:
    text, i, tokens = src.text, 0, []
    while i < len(text):
        ch = text[i]
        if ch.isspace():
            i += 1
            continue
        if ch.isdigit() or (ch == "." and i + 1 < len(text) and text[i + 1].isdigit()):
            j = i
            while j < len(text) and (text[j].isdigit() or text[j] == "."):
                j += 1
            if j < len(text) and text[j] in "eE":
                k = j + 1
                if k < len(text) and text[k] in "+-":
                    k += 1
                if k < len(text) and text[k].isdigit():
                    j = k
                    while j < len(text) and text[j].isdigit():
                        j += 1
            try:
                value = float(text[i:j])
            except ValueError:
                raise src.error(f"bad number '{text[i:j]}'", i) from None
            if not math.isfinite(value):
                raise src.error(f"number '{text[i:j]}' is too large", i)
            tokens.append(Token("num", text[i:j], i))
            i = j
        elif ch.isalpha() or ch == "_":
            j = i
            while j < len(text) and (text[j].isalnum() or text[j] == "_"):
                j += 1
            tokens.append(Token("name", text[i:j], i))
            i = j
        elif ch in "(),?:":
            tokens.append(Token(ch, ch, i))
            i += 1
        else:
            for op in _OPERATORS:
                if text.startswith(op, i):
                    tokens.append(Token("op", op, i))
                    i += len(op)
                    break
            else:
                raise src.error(f"unexpected character '{ch}' in expression", i)
    tokens.append(Token("end", "", len(text)))
    return tokens


class _Parser:
    def __init__(self, src: Source, functions=None, defining=None) -> None:
        self.src = src
        self.tokens = tokenize(src)
        self.pos = 0
        self.nesting = 0
        self.functions = functions or {}
        self.defining = defining  # the name of the #function being defined (recursion is refused)

    def node(self, kind, value, args, offset):
        """A new node; refuses trees deeper than :data:`MAX_DEPTH` or larger than :data:`MAX_NODES`."""
        depth = 1 + max((a.depth for a in args), default=0)
        if depth > MAX_DEPTH:
            raise self.src.error(
                f"expression is too deeply nested (more than {MAX_DEPTH} levels of "
                "operators and calls); split it with #define constants",
                offset,
            )
        size = 1 + sum(a.size for a in args)
        if size > MAX_NODES:
            raise self.src.error(f"expression expands to more than {MAX_NODES:,} operations (user functions are inlined)", offset)
        return Node(kind, value, args, offset, depth, size)

    def peek(self):
        return self.tokens[self.pos]

    def take(self):
        tok = self.tokens[self.pos]
        self.pos += 1
        return tok

    def expect(self, kind, what):
        tok = self.take()
        if tok.kind != kind:
            found = f"'{tok.text}'" if tok.text else "the end"
            raise self.src.error(f"expected {what}, found {found}", tok.offset)
        return tok

    def parse(self):
        if self.peek().kind == "end":
            raise self.src.error("empty expression", 0)
        node = self.expression(0)
        tok = self.peek()
        if tok.kind != "end":
            raise self.src.error(f"unexpected '{tok.text}' after expression", tok.offset)
        return node

    def expression(self, min_prec):
        self.nesting += 1
        if self.nesting > MAX_NESTING:
            raise self.src.error(f"expression is too deeply nested (more than {MAX_NESTING} levels)", self.peek().offset)
        try:
            return self._expression(min_prec)
        finally:
            self.nesting -= 1

    def _expression(self, min_prec):
        left = self.unary()
        while True:
            tok = self.peek()
            if tok.kind == "?" and min_prec == 0:  # C's c ? a : b, below every operator
                self.take()
                chosen = self.expression(0)
                self.expect(":", "':' of 'condition ? value : other value'")
                other = self.expression(0)
                return self.node("choice", "?", (left, chosen, other), tok.offset)
            if tok.kind != "op" or tok.text not in _BINARY:
                return left
            prec = _BINARY[tok.text][0]
            if prec < min_prec:
                return left
            self.take()
            right_min = prec if tok.text == "^" else prec + 1
            right = self.expression(right_min)
            left = self.node("binary", tok.text, (left, right), tok.offset)

    def unary(self):
        tok = self.peek()
        if tok.kind == "op" and tok.text in ("-", "+", "!"):
            self.take()
            operand = self.expression(_UNARY_PRECEDENCE)
            return self.node("unary", tok.text, (operand,), tok.offset)
        return self.primary()

    def primary(self):
        tok = self.take()
        if tok.kind == "num":
            return Node("num", float(tok.text), (), tok.offset)
        if tok.kind == "(":
            node = self.expression(0)
            self.expect(")", "')'")
            return node
        if tok.kind == "name":
            if self.peek().kind == "(":
                return self.call(tok)
            return Node("name", tok.text, (), tok.offset)
        found = f"'{tok.text}'" if tok.text else "the end of the expression"
        raise self.src.error(f"expected a number, name or '(', found {found}", tok.offset)

    def call(self, name_tok):
        self.take()  # '('
        args = []
        if self.peek().kind != ")":
            args.append(self.expression(0))
            while self.peek().kind == ",":
                self.take()
                args.append(self.expression(0))
        self.expect(")", "')' closing the call")
        name = name_tok.text
        if isinstance(self.functions.get(name), Tables):
            if len(args) != 2:
                raise self.src.error(f"{name}() takes 2 arguments (id, x), got {len(args)}", name_tok.offset)
            return self.node("tables", self.functions[name], tuple(args), name_tok.offset)
        if name == self.defining:
            raise self.src.error(f"function '{name}' calls itself: recursive functions are not allowed", name_tok.offset)
        if name in self.functions:
            return self.inline(self.functions[name], args, name_tok.offset)
        if name not in FUNCTIONS:
            raise self.src.error(f"unknown function '{name}'", name_tok.offset)
        arity = FUNCTIONS[name][0]
        if len(args) != arity:
            raise self.src.error(
                f"{name}() takes {arity} argument{'s' if arity > 1 else ''}, got {len(args)}",
                name_tok.offset,
            )
        return self.node("call", name, tuple(args), name_tok.offset)

    def inline(self, function, args, offset):
        """The body of a user function with its parameters replaced by the call's arguments."""
        if len(args) != len(function.params):
            raise self.src.error(f"{function.name}() takes {len(function.params)} argument(s), got {len(args)}", offset)
        bound = dict(zip(function.params, args))

        def substitute(node):
            if node.kind == "name":
                return bound[node.value]
            if not node.args:
                return Node(node.kind, node.value, (), offset)
            return self.node(node.kind, node.value, tuple(substitute(a) for a in node.args), offset)

        return substitute(function.body)


def define_function(
    text: str | Source,
    line: int | None = None,
    column: int = 1,
    source_line: str | None = None,
    functions: Mapping[str, Function] | None = None,
    constants: Iterable[str] = (),
) -> Function:
    """Parse ``f(x, y) = expr`` (the text of a ``#function`` directive) into a :class:`Function`.

    The body may use its parameters, ``#define`` constants and earlier functions; a call
    to itself is refused (no recursion), so every function is a pure, finite expression.

    >>> f = define_function("sq(x) = x * x")
    >>> e = parse_expression("sq(a + 1)", functions={"sq": f})
    >>> compile_expression(e, ["a"], {})({"a": np.array([1.0, 2.0])}, {}, None, 2).tolist()
    [4.0, 9.0]
    """
    src = text if isinstance(text, Source) else Source(text, line, column, source_line)
    head, eq, body = src.text.partition("=")
    m = re.match(r"\s*([A-Za-z_]\w*)\s*\(([^()]*)\)\s*$", head)
    if not eq or not m:
        raise src.error("#function takes 'name(x, y) = expression'", 0)
    name, params = m.group(1), tuple(p.strip() for p in m.group(2).split(",") if p.strip())
    if name in FUNCTIONS:
        raise src.error(f"'{name}' is a built-in function", m.start(1))
    bad = [p for p in params if not re.match(r"[A-Za-z_]\w*$", p)]
    if bad or len(set(params)) != len(params):
        raise src.error(f"the parameters of {name} must be distinct names", m.start(2))
    body_src = Source(body, src.line, src.column + len(head) + 1, src.source_line)
    return make_function(name, params, body_src, functions, constants)


def make_function(
    name: str,
    params: Iterable[str],
    body: Source,
    functions: Mapping[str, Function] | None = None,
    constants: Iterable[str] = (),
) -> Function:
    """A :class:`Function` from its name, parameter names and body text (errors point into ``body``).

    The body sees its parameters, the names in ``constants`` (read when the function is
    evaluated, never captured by a caller's parameter of the same name) and earlier
    ``functions``; it may not call itself.

    >>> f = make_function("half", ["x"], Source("x / k"), constants=["k"])
    >>> compile_expression(parse_expression("half(4)", functions={"half": f}), [], ["k"])({}, {"k": 2.0}, None, 1).tolist()
    [2.0]
    """
    params = tuple(params)
    node = _Parser(body, functions, defining=name).parse()
    known = set(constants)
    for used, at in names_used(node):
        if used not in params and used not in known:
            raise body.error(
                f"unknown name '{used}' in function {name}: a function sees its parameters and #define constants", at
            )
    return Function(name, params, _constants_fixed(node, set(params)))


def _constants_fixed(node, params):
    """Mark a function body's constant names as constants, so a rule's formal of the same name cannot capture them."""
    if node.kind == "name" and node.value not in params:
        return Node("const", node.value, (), node.offset, node.depth, node.size)
    if not node.args:
        return node
    return Node(node.kind, node.value, tuple(_constants_fixed(a, params) for a in node.args), node.offset, node.depth, node.size)


@dataclass(frozen=True)
class Expression:
    """A parsed expression: its tree and the source it came from (for errors)."""

    node: Node
    src: Source

    @property
    def text(self) -> str:
        return self.src.text


def parse_expression(
    text: str | Source,
    line: int | None = None,
    column: int = 1,
    source_line: str | None = None,
    functions: Mapping[str, Function] | None = None,
) -> Expression:
    """Parse ``text`` into an :class:`Expression`; errors point at line and column.

    ``functions`` maps names to user :class:`Function` s, inlined where called.
    """
    src = text if isinstance(text, Source) else Source(text, line, column, source_line)
    return Expression(_Parser(src, functions).parse(), src)


def names_used(node: Node | Expression) -> list[tuple[str, int]]:
    """All variable names an expression reads, with their offsets."""
    tree: Node = node.node if isinstance(node, Expression) else node
    if tree.kind in ("name", "const"):
        return [(str(tree.value), tree.offset)]
    out: list[tuple[str, int]] = []
    for arg in tree.args:
        out.extend(names_used(arg))
    return out


def uses_random(node: Node | Expression) -> bool:
    tree: Node = node.node if isinstance(node, Expression) else node
    if tree.kind == "call" and tree.value in RANDOM_FUNCTIONS:
        return True
    return any(uses_random(a) for a in tree.args)


def _source(node, params, constants, src, lift=None):
    if node.kind == "num":
        if lift and node.offset in lift:  # a hidden constant (ramure.lsys.language.hidden): overridable
            return f"C.get({lift[node.offset]!r}, {node.value!r})"
        return repr(node.value)
    if node.kind == "name":
        if node.value in params:
            return f"V[{node.value!r}]"
        if node.value in constants:
            return f"C[{node.value!r}]"
        raise src.error(f"unknown name '{node.value}'", node.offset)
    if node.kind == "const":
        if node.value not in constants:
            raise src.error(f"unknown constant '{node.value}'", node.offset)
        return f"C[{node.value!r}]"
    parts = [_source(a, params, constants, src, lift) for a in node.args]
    if node.kind == "unary":
        return {"-": "(-{0})", "+": "(+{0})", "!": "_f(np.logical_not({0}))"}[node.value].format(*parts)
    if node.kind == "binary":
        return _BINARY[node.value][1].format(*parts)
    if node.kind == "choice":
        return f"_pick({parts[0]}, lambda: {parts[1]}, lambda: {parts[2]})"
    if node.kind == "tables":
        return f"_tables({parts[0]}, {parts[1]}, {node.value.values!r})"
    return FUNCTIONS[node.value][1].format(*parts)


def compile_expression(
    expr: Expression, params: Iterable[str], constants: Iterable[str], lift: Mapping[int, str] | None = None
) -> Callable[[dict, dict, np.random.Generator, int], np.ndarray]:
    """Compile an expression tree to ``f(V, C, R, n) -> float array of length n``.

    ``V`` maps formal parameter names to arrays, ``C`` constant names to
    floats, ``R`` is a :class:`numpy.random.Generator` (only read by
    ``uniform``/``normal``), ``n`` the number of modules evaluated.
    Unknown names raise :class:`GrammarError` here, at compile time.  ``lift``
    (``{offset: key}``) makes the literals at those offsets read ``C[key]`` when ``C``
    has it (:mod:`ramure.lsys.language.hidden`).
    """
    body = _source(expr.node, set(params), set(constants), expr.src, lift)
    code = f"lambda V, C, R, n: _out({body}, n)"
    names = {"np": np, "_out": _broadcast, "_f": _as_float, "_alea": _alea, "_tables": _tables, "_pick": _pick}
    return eval(code, names)  # noqa: S307 - generated from our own AST


def _alea(R, a, b, n):
    """``alea(a, b)``: a uniform draw between the smaller and the larger bound (each argument evaluated once)."""
    return R.uniform(np.minimum(a, b), np.maximum(a, b), n)


def _pick(condition, chosen, other):
    """``condition ? chosen : other`` over arrays: both branches are computed (numpy), the one a
    module does not take may fail (``x > 0 ? 1/x : 0``) without error; the taken one must be finite."""
    with np.errstate(all="ignore"):
        a, b = np.asarray(chosen(), float), np.asarray(other(), float)
    out = np.where(np.asarray(condition) != 0, a, b)
    if not np.all(np.isfinite(out)):
        raise FloatingPointError("invalid value in the branch a '? :' takes")
    return out


def _tables(ident, x, values):
    """``func(id, x)`` over arrays: function ``id`` (1, 2, ...) of ``values`` at ``x`` in [0, 1]."""
    ident, x = np.broadcast_arrays(np.asarray(ident, float), np.clip(np.asarray(x, float), 0.0, 1.0))
    out = np.full(x.shape, np.nan)
    for k, ys in enumerate(values, start=1):
        mask = ident == k
        if mask.any():
            out[mask] = np.interp(x[mask], np.linspace(0.0, 1.0, len(ys)), ys)
    if np.isnan(out).any():
        bad = float(ident[np.isnan(out)].flat[0])
        raise ValueError(f"func({bad:g}, x): the view file names {len(values)} function(s), ids 1 to {len(values)}")
    return out


def _as_float(value):
    return np.multiply(value, 1.0)


def _broadcast(value, n):
    arr = np.asarray(value, dtype=float)
    if arr.shape == (n,):
        return arr
    return np.broadcast_to(arr, (n,)).astype(float)


class SeededGenerator:
    """``numpy.random.default_rng(seed)``, made when first drawn from (its attributes are the
    generator's): a grammar that draws nothing never imports ``numpy.random``, about 9 ms of a
    new process.  Drawing from it gives what drawing from ``default_rng(seed)`` gives.

    >>> SeededGenerator(7).random(2).tolist() == np.random.default_rng(7).random(2).tolist()
    True
    """

    def __init__(self, seed: Any) -> None:
        self._seed = seed
        self._generator: np.random.Generator | None = None

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__") or name in ("_seed", "_generator"):  # copy, pickle: not the generator's
            raise AttributeError(name)
        if self._generator is None:
            self._generator = np.random.default_rng(self._seed)
        return getattr(self._generator, name)


def seeded_generator(seed: Any) -> np.random.Generator:
    """A :class:`SeededGenerator`, typed as the generator it stands for."""
    return cast("np.random.Generator", SeededGenerator(seed))


def evaluate_constant(expr: Expression, constants: dict[str, float]) -> float:
    """Evaluate a parameter-free expression (a ``#define`` value) to a float."""
    fn = compile_expression(expr, (), constants)
    with np.errstate(all="raise"):
        try:
            value = float(fn({}, constants, seeded_generator(0), 1)[0])
        except (FloatingPointError, ZeroDivisionError, ValueError, OverflowError) as exc:
            raise expr.src.error(f"cannot evaluate: {_explain(exc)}", 0) from None
    if not math.isfinite(value):
        raise expr.src.error("value is not a finite number", 0)
    return value


def _explain(exc):
    text = str(exc)
    if isinstance(exc, (ValueError, OverflowError)):  # e.g. normal(0, -1): "scale < 0"
        return f"invalid arguments ({text})"
    if "divide" in text or isinstance(exc, ZeroDivisionError):
        return "division by zero"
    if "invalid" in text:
        return "invalid operation (e.g. sqrt or log of a negative number)"
    if "overflow" in text:
        return "overflow"
    return text
