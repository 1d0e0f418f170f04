"""cpfg's C-like statement language: the ``Start:``/``StartEach:``/``EndEach:``/``End:`` and
``Define:`` blocks of L-studio files, run without Python's ``eval`` of user text.

Statements: ``{ ... }`` blocks; ``if (c) s [else s]``; ``while (c) s``; ``do s while (c);``;
``for (init; c; step) s`` (``init`` and ``step`` may list several statements with commas);
assignments ``x = e``, ``x += e`` (``-= *= /=``), ``x++``, ``x--``, ``++x``, ``--x``;
arrays ``array a[10];`` or ``array a[3] = {1, 2, 3};`` read and written as ``a[i]``;
declarations ``int x;`` / ``float x = 2;``; ``printf("...", e, ...)``; ``srand(e)``.

Expressions are Ramure's own (:mod:`ramure.lsys.expr`): every value is a float, a comparison
gives 1 or 0, ``^`` is the power, trigonometry is in degrees as in the rest of the cpfg
reader; cpfg's ``ran(x)`` (uniform in [0, x)), ``nran(m, s)`` (normal) and ``fabs`` are
understood.  Variables live in one dictionary (the grammar's constants, so the rules see
the globals the blocks set), arrays in another.

>>> program = parse_program("{ s = 0; for (i = 1; i <= 4; i++) s += i*i; if (s > 20) big = 1; else big = 0; }")
>>> scope = Scope({})
>>> program.run(scope)
>>> scope.variables["s"], scope.variables["big"]
(30.0, 1.0)
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import DerivationError, GrammarError
from ..expr import Expression, compile_expression, names_used, parse_expression, seeded_generator
from ..expr import Source

#: Statements one run of a block may execute before it is stopped (a loop that never ends).
MAX_STATEMENTS = 1_000_000
#: The largest array a block may declare.
MAX_ARRAY = 1_000_000
#: cpfg's function names -> Ramure's.
RENAMED = (
    (re.compile(r"\bnran\s*\("), "normal("),
    (re.compile(r"\bran\s*\("), "uniform(0,"),
    (re.compile(r"\bfabs\s*\("), "abs("),
)
_NAME = re.compile(r"[A-Za-z_]\w*")
_ASSIGN = re.compile(r"(\+=|-=|\*=|/=|=(?!=))")
_PRINTF_SPEC = re.compile(r"%[-+ #0]*\d*(?:\.\d+)?[diouxXeEfFgGcs%]")


@dataclass
class Scope:
    """What the blocks of one derivation share: variables (floats), arrays, the random draws
    (``srand`` reseeds them) and what ``printf`` printed (``printed``, one string a call;
    ``echo`` is called with each too)."""

    variables: dict[str, float]
    arrays: dict[str, np.ndarray] = field(default_factory=dict)
    rng: Any = None
    printed: list[str] = field(default_factory=list)
    echo: Callable[[str], None] | None = None
    budget: int = MAX_STATEMENTS

    def __post_init__(self) -> None:
        if self.rng is None:
            self.rng = seeded_generator(0)


class _Expr:
    """An expression of a block, its array reads ``a[i]`` replaced by placeholders."""

    def __init__(self, text: str, line: int | None, column: int, source_line: str | None, functions: dict | None = None) -> None:
        self.reads: list[tuple[str, _Expr, str]] = []  # (array, index, placeholder)
        self.functions = functions
        text = self._arrays(text, line, column, source_line)
        for pattern, new in RENAMED:
            text = pattern.sub(new, text)
        self.source = Source(text, line, column, source_line)
        self.expr: Expression = parse_expression(self.source, functions=functions)
        self.names = sorted({name for name, _ in names_used(self.expr)})
        self.fn = compile_expression(self.expr, self.names, ())

    def _arrays(self, text, line, column, source_line):
        out, at = [], 0
        for m in re.finditer(r"([A-Za-z_]\w*)\s*\[", text):
            if m.start() < at:
                continue
            close = _matching(text, m.end() - 1, "[", "]")
            if close < 0:
                raise GrammarError("a '[' is never closed", line, column + m.end() - 1, source_line)
            placeholder = f"__array{len(self.reads)}"
            index = _Expr(text[m.end() : close], line, column + m.end(), source_line, self.functions)
            self.reads.append((m.group(1), index, placeholder))
            out.append(text[at : m.start()] + placeholder)
            at = close + 1
        return "".join(out) + text[at:]

    def value(self, scope: Scope) -> float:
        values = {}
        for array, index, placeholder in self.reads:
            values[placeholder] = np.array([_element(scope, array, index.value(scope), self.source)])
        for name in self.names:
            if name in values:
                continue
            if name not in scope.variables:
                raise _runtime(self.source, f"variable '{name}' is used before it is given a value")
            values[name] = np.array([float(scope.variables[name])])
        with np.errstate(all="ignore"):
            return float(self.fn(values, {}, scope.rng, 1)[0])


def _element(scope, array, index, source):
    if array not in scope.arrays:
        raise _runtime(source, f"'{array}' is not an array (declare it: array {array}[n];)")
    data = scope.arrays[array]
    if not (0 <= index < len(data)) or index != int(index):
        raise _runtime(source, f"index {index:g} is outside array {array}[{len(data)}]")
    return data[int(index)]


def _runtime(source, message):
    return DerivationError(message, source.line, source.column, source.source_line)


class Statement:
    """One statement; :meth:`run` executes it in a :class:`Scope`."""

    line: int | None = None

    def run(self, scope: Scope) -> None:
        raise NotImplementedError

    def tick(self, scope: Scope, source: Source | None = None) -> None:
        scope.budget -= 1
        if scope.budget < 0:
            raise DerivationError(f"a block ran more than {MAX_STATEMENTS:,} statements (a loop that never ends?)", self.line)


@dataclass
class Block(Statement):
    body: list[Statement]

    def run(self, scope: Scope) -> None:
        for statement in self.body:
            statement.run(scope)


@dataclass
class Assign(Statement):
    name: str
    index: _Expr | None
    operator: str
    value: _Expr | None  # None for ++ and --
    line: int | None = None

    def run(self, scope: Scope) -> None:
        self.tick(scope)
        step = self.value.value(scope) if self.value is not None else 1.0
        if self.operator == "=":
            new = step
        else:
            old = self._old(scope)
            new = {"+": old + step, "-": old - step, "*": old * step, "/": _divide(old, step)}[self.operator[0]]
        if self.index is None:
            scope.variables[self.name] = new
        else:
            source = self.index.source
            i = self.index.value(scope)
            _element(scope, self.name, i, source)
            scope.arrays[self.name][int(i)] = new

    def _old(self, scope):
        if self.index is not None:
            return float(_element(scope, self.name, self.index.value(scope), self.index.source))
        if self.name not in scope.variables:
            raise DerivationError(f"variable '{self.name}' is changed before it is given a value", self.line)
        return float(scope.variables[self.name])


def _divide(a, b):
    with np.errstate(all="ignore"):
        return float(np.float64(a) / np.float64(b))


@dataclass
class If(Statement):
    condition: _Expr
    then: Statement
    otherwise: Statement | None

    def run(self, scope: Scope) -> None:
        self.tick(scope)
        if self.condition.value(scope) != 0:
            self.then.run(scope)
        elif self.otherwise is not None:
            self.otherwise.run(scope)


@dataclass
class Loop(Statement):
    """``while``, ``do``-``while`` and ``for`` loops (``init`` and ``step`` run as statements)."""

    condition: _Expr | None
    body: Statement
    init: list[Statement] = field(default_factory=list)
    step: list[Statement] = field(default_factory=list)
    test_first: bool = True

    def run(self, scope: Scope) -> None:
        for statement in self.init:
            statement.run(scope)
        first = True
        while True:
            self.tick(scope)
            if (self.test_first or not first) and self.condition is not None and self.condition.value(scope) == 0:
                return
            first = False
            self.body.run(scope)
            for statement in self.step:
                statement.run(scope)


@dataclass
class Printf(Statement):
    format: str
    args: list[_Expr]
    line: int | None = None

    def run(self, scope: Scope) -> None:
        self.tick(scope)
        values = [a.value(scope) for a in self.args]
        pieces, k = [], 0
        for m in _PRINTF_SPEC.finditer(self.format):
            pieces.append((m.start(), m.end(), m.group()))
        out, at = [], 0
        for start, end, spec in pieces:
            out.append(self.format[at:start])
            if spec == "%%":
                out.append("%")
            else:
                if k >= len(values):
                    raise DerivationError(f"printf has fewer values than '%' fields in {self.format!r}", self.line)
                value = values[k]
                k += 1
                spec = spec[:-1] + "g" if spec[-1] in "cs" else spec
                out.append(spec % (int(value) if spec[-1] in "diouxX" else value))
            at = end
        out.append(self.format[at:])
        text = "".join(out)
        scope.printed.append(text)
        if scope.echo is not None:
            scope.echo(text)


@dataclass
class Seed(Statement):
    value: _Expr

    def run(self, scope: Scope) -> None:
        self.tick(scope)
        scope.rng = seeded_generator(int(self.value.value(scope)) % 2**32)


@dataclass
class Declare(Statement):
    """``array a[n] [= {...}]`` or ``int|float x [= e]``."""

    name: str
    size: _Expr | None
    values: list[_Expr]
    line: int | None = None

    def run(self, scope: Scope) -> None:
        self.tick(scope)
        if self.size is None:
            scope.variables[self.name] = self.values[0].value(scope) if self.values else scope.variables.get(self.name, 0.0)
            return
        n = self.size.value(scope)
        if not (0 < n <= MAX_ARRAY) or n != int(n):
            raise DerivationError(f"array {self.name} needs a whole size from 1 to {MAX_ARRAY:,}, not {n:g}", self.line)
        data = np.zeros(int(n))
        if len(self.values) > len(data):
            raise DerivationError(f"array {self.name}[{int(n)}] is given {len(self.values)} values", self.line)
        data[: len(self.values)] = [v.value(scope) for v in self.values]
        scope.arrays[self.name] = data


# -- parsing ----------------------------------------------------------------------------------
class _Text:
    """The block's text and where it stands in the file (line and column of each offset)."""

    def __init__(self, text: str, line: int | None, column: int, lines: list[str] | None, functions: dict | None = None) -> None:
        self.text, self.line, self.column, self.lines = text, line, column, lines
        self.functions = functions  # e.g. cpfg's func(id, x)

    def where(self, offset: int) -> tuple[int | None, int, str | None]:
        before = self.text[:offset]
        extra = before.count("\n")
        column = offset - before.rfind("\n") if extra else self.column + offset
        line = None if self.line is None else self.line + extra
        source = self.lines[line - 1] if self.lines and line is not None and 0 < line <= len(self.lines) else None
        return line, column, source

    def error(self, message: str, offset: int) -> GrammarError:
        line, column, source = self.where(offset)
        return GrammarError(message, line, column, source if source is not None else self.text.split("\n")[0])

    def expr(self, start: int, end: int) -> _Expr:
        piece = self.text[start:end]
        lead = len(piece) - len(piece.lstrip())
        if not piece.strip():
            raise self.error("an expression is missing here", start)
        line, column, source = self.where(start + lead)
        return _Expr(piece.strip().replace("\n", " "), line, column, source, self.functions)


def parse_program(
    text: str, line: int | None = None, column: int = 1, lines: list[str] | None = None, functions: dict | None = None
) -> Block:
    """Parse the statements of ``text`` (a braced block or bare statements); ``line`` and
    ``column`` place its first character in the file (whose ``lines`` errors quote);
    ``functions`` are called as in rules (cpfg's ``func``)."""
    source = _Text(text, line, column, lines, functions)
    parser = _Parser(source)
    body = parser.statements(len(text))
    return Block(body)


class _Parser:
    def __init__(self, source: _Text) -> None:
        self.src = source
        self.text = source.text
        self.at = 0

    def skip(self) -> None:
        while self.at < len(self.text) and self.text[self.at].isspace():
            self.at += 1

    def peek_word(self) -> str:
        self.skip()
        m = _NAME.match(self.text, self.at)
        return m.group() if m else ""

    def expect(self, char: str) -> None:
        self.skip()
        if not self.text.startswith(char, self.at):
            found = self.text[self.at : self.at + 1] or "the end of the block"
            raise self.src.error(f"expected '{char}' here, found {found!r}", self.at)
        self.at += len(char)

    def line_of(self, offset):
        return self.src.where(offset)[0]

    def statements(self, end: int) -> list[Statement]:
        out: list[Statement] = []
        while True:
            self.skip()
            if self.at >= end:
                return out
            out.append(self.statement())

    def statement(self) -> Statement:
        self.skip()
        start = self.at
        if self.text.startswith("{", self.at):
            close = _matching(self.text, self.at, "{", "}")
            if close < 0:
                raise self.src.error("this '{' is never closed", self.at)
            self.at += 1
            body = self.statements(close)
            self.at = close + 1
            return Block(body)
        if self.text.startswith(";", self.at):
            self.at += 1
            return Block([])
        word = self.peek_word()
        if word == "if":
            self.at += 2
            condition = self.parenthesised()
            then = self.statement()
            otherwise = None
            if self.peek_word() == "else":
                self.at += 4
                otherwise = self.statement()
            return If(condition, then, otherwise)
        if word == "while":
            self.at += 5
            condition = self.parenthesised()
            return Loop(condition, self.statement())
        if word == "do":
            self.at += 2
            inner = self.statement()
            if self.peek_word() != "while":
                raise self.src.error("'do' needs 'while (...)' after its body", self.at)
            self.at += 5
            condition = self.parenthesised()
            self.expect(";")
            return Loop(condition, inner, test_first=False)
        if word == "for":
            return self.for_loop()
        if word in ("printf", "fprintf", "sprintf") and word != "printf":
            raise self.src.error(f"'{word}' (files and strings) is not supported; printf is", self.at)
        end = self.simple_end()
        statement = self.simple(start, end)
        self.at = end + 1
        return statement

    def parenthesised(self) -> _Expr:
        self.skip()
        if not self.text.startswith("(", self.at):
            raise self.src.error("expected '(' here", self.at)
        close = _matching(self.text, self.at, "(", ")")
        if close < 0:
            raise self.src.error("this '(' is never closed", self.at)
        expr = self.src.expr(self.at + 1, close)
        self.at = close + 1
        return expr

    def for_loop(self) -> Statement:
        self.at += 3
        self.skip()
        if not self.text.startswith("(", self.at):
            raise self.src.error("expected '(' after 'for'", self.at)
        close = _matching(self.text, self.at, "(", ")")
        if close < 0:
            raise self.src.error("this '(' is never closed", self.at)
        parts = _split_top(self.text, self.at + 1, close, ";")
        if len(parts) != 3:
            raise self.src.error("'for (init; condition; step)' needs two ';'", self.at)
        (a, b), (c, d), (e, f) = parts
        init = [self.simple(s, t) for s, t in _split_top(self.text, a, b, ",") if self.text[s:t].strip()]
        condition = self.src.expr(c, d) if self.text[c:d].strip() else None
        step = [self.simple(s, t) for s, t in _split_top(self.text, e, f, ",") if self.text[s:t].strip()]
        self.at = close + 1
        return Loop(condition, self.statement(), init, step)

    def simple_end(self) -> int:
        end = _find_top(self.text, self.at, len(self.text), ";")
        if end < 0:
            raise self.src.error("this statement does not end with ';'", self.at)
        return end

    def simple(self, start: int, end: int) -> Statement:
        """An assignment, ++/--, a declaration, printf(...) or srand(...) in text[start:end]."""
        piece = self.text[start:end]
        lead = len(piece) - len(piece.lstrip())
        start += lead
        piece = piece.strip()
        line = self.line_of(start)
        word = _NAME.match(piece)
        head = word.group() if word else ""
        if head in ("printf", "srand") and piece[len(head) :].lstrip().startswith("("):
            open_at = start + piece.index("(")
            close = _matching(self.text, open_at, "(", ")")
            if close < 0 or self.text[close + 1 : end].strip():
                raise self.src.error(f"cannot read this {head}(...) call", start)
            if head == "srand":
                return Seed(self.src.expr(open_at + 1, close))
            return self.printf(open_at + 1, close, line)
        if head in ("array", "int", "float", "double"):
            return self.declaration(head, start + len(head), end, line)
        if piece.startswith(("++", "--")):
            name = piece[2:].strip()
            return self.incremented(name, start + 2 + (len(piece[2:]) - len(piece[2:].lstrip())), piece[0], line)
        if piece.endswith(("++", "--")):
            return self.incremented(piece[:-2].strip(), start, piece[-1], line)
        m = _ASSIGN.search(self.text, start, end)
        while m is not None and _depth(self.text, start, m.start()) != 0:
            m = _ASSIGN.search(self.text, m.end(), end)
        if m is None:
            raise self.src.error("expected an assignment (x = ...), x++, printf(...), srand(...) or a declaration", start)
        target, index = self.target(start, m.start())
        return Assign(target, index, m.group(), self.src.expr(m.end(), end), line)

    def incremented(self, text_name, offset, sign, line):
        target, index = self.target(offset, offset + len(text_name))
        return Assign(target, index, sign + "=", None, line)

    def target(self, start: int, end: int) -> tuple[str, _Expr | None]:
        piece = self.text[start:end].strip()
        m = _NAME.fullmatch(piece)
        if m:
            return piece, None
        m = re.fullmatch(r"([A-Za-z_]\w*)\s*\[(.*)\]", piece, re.S)
        if not m or "][" in piece:
            raise self.src.error(f"cannot assign to '{piece}': a variable or an array element a[i]", start)
        first = start + self.text[start:end].index("[") + 1
        return m.group(1), self.src.expr(first, first + len(m.group(2)))

    def declaration(self, kind, start, end, line) -> Statement:
        body = self.text[start:end]
        m = re.match(r"\s*([A-Za-z_]\w*)\s*", body)
        if m is None:
            raise self.src.error(f"'{kind}' needs a name", start)
        name, at = m.group(1), start + m.end()
        size = None
        if kind == "array" or self.text.startswith("[", at):
            if not self.text.startswith("[", at):
                raise self.src.error(f"array {name} needs a size: array {name}[n]", at)
            close = _matching(self.text, at, "[", "]")
            if close < 0 or close > end:
                raise self.src.error("this '[' is never closed", at)
            size = self.src.expr(at + 1, close)
            at = close + 1
        rest = self.text[at:end].strip()
        values: list[_Expr] = []
        if rest:
            if not rest.startswith("="):
                raise self.src.error(f"expected '=' or ';' after the declaration of {name}", at)
            eq = self.text.index("=", at) + 1
            if size is not None:
                first = self.text.find("{", eq, end)
                last = self.text.rfind("}", eq, end)
                if first < 0 or last < 0:
                    raise self.src.error(f"array {name} takes its values in braces: {{1, 2, 3}}", eq)
                values = [self.src.expr(s, t) for s, t in _split_top(self.text, first + 1, last, ",") if self.text[s:t].strip()]
            else:
                values = [self.src.expr(eq, end)]
        return Declare(name, size, values, line)

    def printf(self, start, end, line) -> Statement:
        parts = _split_top(self.text, start, end, ",")
        s, t = parts[0]
        literal = self.text[s:t].strip()
        if len(literal) < 2 or literal[0] != '"' or literal[-1] != '"':
            raise self.src.error('printf takes a "format" first', s)
        fmt = literal[1:-1].replace("\\n", "\n").replace("\\t", "\t").replace('\\"', '"').replace("\\\\", "\\")
        return Printf(fmt, [self.src.expr(a, b) for a, b in parts[1:]], line)


def _matching(text: str, start: int, opening: str, closing: str) -> int:
    """The offset of the bracket closing the one at ``start`` (strings skipped), else -1."""
    depth, i = 0, start
    while i < len(text):
        c = text[i]
        if c == '"':
            j = text.find('"', i + 1)
            if j < 0:
                return -1
            i = j
        elif c == opening:
            depth += 1
        elif c == closing:
            depth -= 1
            if depth == 0:
                return i
        i += 1
    return -1


def _depth(text: str, start: int, end: int) -> int:
    depth = 0
    for c in text[start:end]:
        depth += (c in "([{") - (c in ")]}")
    return depth


def _find_top(text: str, start: int, end: int, char: str) -> int:
    """The first ``char`` in text[start:end] outside brackets and strings, else -1."""
    depth, i = 0, start
    while i < end:
        c = text[i]
        if c == '"':
            j = text.find('"', i + 1)
            i = end if j < 0 else j
        elif c in "([{":
            depth += 1
        elif c in ")]}":
            depth -= 1
        elif c == char and depth == 0:
            return i
        i += 1
    return -1


def _split_top(text: str, start: int, end: int, char: str) -> list[tuple[int, int]]:
    """text[start:end] split at ``char`` outside brackets and strings: (start, end) pairs."""
    out = []
    while True:
        cut = _find_top(text, start, end, char)
        if cut < 0:
            out.append((start, end))
            return out
        out.append((start, cut))
        start = cut + 1


def assigned_names(program: Statement) -> set[str]:
    """The variable names a program assigns or declares (not its arrays)."""
    names: set[str] = set()
    stack = [program]
    while stack:
        s = stack.pop()
        if isinstance(s, Assign) and s.index is None:
            names.add(s.name)
        elif isinstance(s, Declare) and s.size is None:
            names.add(s.name)
        elif isinstance(s, Block):
            stack.extend(s.body)
        elif isinstance(s, If):
            stack.extend([s.then] + ([s.otherwise] if s.otherwise else []))
        elif isinstance(s, Loop):
            stack.extend([s.body, *s.init, *s.step])
    return names


class Blocks:
    """The cpfg blocks of one derivation and the :class:`Scope` they share (None: no blocks)."""

    def __init__(self, programs: dict[str, Block], variables: dict[str, float], seed: int) -> None:
        self.programs = programs
        self.scope = Scope(variables, rng=seeded_generator(seed)) if programs else None

    def run(self, *names: str) -> None:
        """Run the named blocks (``define``, ``start``, ``starteach``, ``endeach``, ``end``) in order."""
        if self.scope is None:
            return
        for name in names:
            program = self.programs.get(name)
            if program is not None:
                self.scope.budget = MAX_STATEMENTS
                program.run(self.scope)


def cpfg_blocks(grammar: Any, variables: dict[str, float], seed: int) -> Blocks:
    """The blocks of ``grammar`` (a cpfg file's ``programs``, none for other grammars) sharing
    ``variables`` (the derivation's constants: the rules read the globals the blocks set)."""
    return Blocks(grammar.programs, variables, seed)


class _Layered(dict):
    """A module's formal parameters over the globals: reads see the formals first; an
    assignment to a formal stays with the module, any other goes to the globals."""

    def __init__(self, formals: dict[str, float], globals_: dict[str, float]) -> None:
        super().__init__(formals)
        self.globals = globals_

    def __contains__(self, name: object) -> bool:
        return dict.__contains__(self, name) or name in self.globals

    def __getitem__(self, name: str) -> float:
        return dict.__getitem__(self, name) if dict.__contains__(self, name) else self.globals[name]

    def __setitem__(self, name: str, value: float) -> None:
        if dict.__contains__(self, name):
            dict.__setitem__(self, name, value)
        else:
            self.globals[name] = value


class RuleBlocks:
    """A cpfg production with statement blocks, ``pred : {pre} condition {post} --> successor``,
    run module by module in string order as cpfg runs it: the block before the condition, the
    condition, and for a module that it accepts the block after it and the successor's
    parameters.  Variables are cpfg's globals (the derivation's constants); the formal
    parameters are the module's own.

    Called as the rule's compiled condition ``f(V, C, R, n)``; :meth:`take` then gives the
    successor parameters of the accepted modules, in the same order.
    """

    def __init__(
        self, pre: Block | None, post: Block | None, condition: Any, successor: list[list[Any]], formals: list[str]
    ) -> None:
        self.pre, self.post, self.condition = pre, post, condition
        self.successor, self.formals = successor, formals
        self.rows: list[list[list[float]]] = []
        self.scope = Scope({})

    def __call__(self, V: dict, C: dict, R: Any, n: int) -> np.ndarray:
        ok = np.zeros(n)
        self.rows = []
        for i in range(n):
            one = {name: V[name][i : i + 1] for name in self.formals if name in V}
            variables = _Layered({k: float(v[0]) for k, v in one.items()}, C)
            scope = Scope(variables, rng=R)
            if self.pre is not None:
                self.pre.run(scope)
            one = {k: np.array([variables[k]]) for k in one}
            if self.condition is not None and self.condition(one, C, R, 1)[0] == 0:
                continue
            if self.post is not None:
                self.post.run(scope)
                one = {k: np.array([variables[k]]) for k in one}
            ok[i] = 1
            self.rows.append([[float(fn(one, C, R, 1)[0]) for fn in args] for args in self.successor])
        return ok

    def take(self) -> list[list[list[float]]]:
        """The successor parameters of the modules the last call accepted (module, successor
        module, parameter)."""
        rows, self.rows = self.rows, []
        return rows
