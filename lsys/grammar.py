"""The ``.lsys`` grammar language: parsing text into a :class:`Grammar`.

A grammar file looks like ABOP with a few directives::

    /* Honda's sympodial tree (ABOP fig. 2.7) */
    #define r1 0.9          // contraction ratio 1
    #define a1 10
    #angle 90               // default angle of parameterless + - & ^ \\ / turns
    n: 10
    w: A(1,10)
    p:
      A(l,w) : * -> !(w)F(l)[&(a1)B(l*r1,w*0.7)]
                    /(180)[&(60)B(l*0.7,w*0.7)]   // indented continuation
      B(l,w) -> !(w)F(l)[+(a1)$B(l*r1,w*0.7)][-(60)$B(l*0.7,w*0.7)]

Directives (one per line, ``//`` and ``/* */`` comments anywhere):

``#define NAME expr``
    a constant; may use earlier constants.  Constants are what the variant
    explorer varies and what the UI shows as sliders.
``#module Name1 Name2 ...``
    multi-letter module names.  Any other letter is a module on its own, so
    ``FF-[-F+F]`` is ten modules.  ``Leaf`` and ``Fruit`` are always declared.
``#organ Name ...``
    declares organ modules drawn as organs (``Leaf`` and ``Fruit`` are organs).
``#ignore: + - F``
    symbols skipped when matching left/right contexts.
``#angle deg``
    the angle of ``+ - & ^ \\ /`` written without a parameter (default 90).
``#step len`` / ``#width w``
    the length of a parameterless ``F``/``f`` (default 1) and the initial
    width (diameter) of the turtle (default 0.1).
``#widthscale s``
    radius = width * s / 2 (default 1), for grammars whose widths are pixels.
``#tropism tx ty tz e``
    ABOP tropism: after each ``F`` the heading bends toward (tx,ty,tz) by
    e·‖H×T‖.  Off by default.
``n: N``, ``w: axiom``, ``p:``
    derivation count, axiom, then one rule per line.

Rules: ``[prob] [left <] Pred(x, y) [> right] : condition -> successor``.
``*`` (or nothing) as condition means always.  A probability prefix must be a
decimal number with a point (``.25``, ``0.5``), so digit symbols such as the
``0 < 1 > 0`` of ABOP fig. 1.31 stay modules.  A line without ``->`` that
follows a rule continues that rule's successor.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

from .errors import GrammarError
from .expr import Expression, Source, compile_expression, evaluate_constant, parse_expression

DEFAULT_MODULES = ("Leaf", "Fruit")
DEFAULT_ORGANS = ("Leaf", "Fruit")
DEFAULT_ANGLE = 90.0
DEFAULT_STEP = 1.0
DEFAULT_WIDTH = 0.1
_NAME = re.compile(r"[A-Za-z_][A-Za-z_0-9]*$")
_PROBABILITY = re.compile(r"\s*(\d*\.\d+|\d+\.\d*)\s+")


@dataclass
class ModuleSpec:
    """A module written in an axiom or successor: symbol and argument expressions."""

    symbol: str
    args: list  # list[Expression]
    column: int = 1
    line: object = field(default=None, repr=False, compare=False)  # source _Line, for errors

    def __str__(self):
        return self.symbol + (f"({','.join(a.text.strip() for a in self.args)})" if self.args else "")


@dataclass
class Pattern:
    """A module in a rule's predecessor or context: symbol and formal parameter names."""

    symbol: str
    params: list
    column: int = 1
    line: object = field(default=None, repr=False, compare=False)

    def __str__(self):
        return self.symbol + (f"({','.join(self.params)})" if self.params else "")


@dataclass
class Rule:
    index: int
    line: int
    text: str
    source_line: str
    pred: Pattern
    successor: list
    left: list = field(default_factory=list)
    right: list = field(default_factory=list)
    condition: Expression | None = None
    probability: float | None = None

    @property
    def formals(self):
        names = []
        for pattern in [*self.left, self.pred, *self.right]:
            names.extend(pattern.params)
        return names

    @property
    def is_context_sensitive(self):
        return bool(self.left or self.right)

    def group_key(self):
        """Rules with the same key compete for the same modules (stochastic choice)."""
        return (
            self.pred.symbol,
            len(self.pred.params),
            tuple((p.symbol, len(p.params)) for p in self.left),
            tuple((p.symbol, len(p.params)) for p in self.right),
        )

    def __str__(self):
        return self.text.strip()


@dataclass
class Grammar:
    """A parsed grammar.  Build one with :func:`parse_grammar`."""

    text: str
    constants: dict
    axiom: list
    rules: list
    n: int
    modules: tuple = DEFAULT_MODULES
    organs: tuple = DEFAULT_ORGANS
    ignore: frozenset = frozenset()
    angle: float = DEFAULT_ANGLE
    step: float = DEFAULT_STEP
    width: float = DEFAULT_WIDTH
    width_scale: float = 1.0
    tropism: tuple | None = None
    filename: str | None = None
    symbols: list = field(default_factory=list)
    amap: tuple = ()  # (role, symbol, line, column, source line) of each #amap annotation

    def symbol_id(self, name):
        return self.symbols.index(name)


def strip_comments(text):
    """Blank out ``//`` and ``/* */`` comments, keeping every other column in place."""
    out, i, n = [], 0, len(text)
    while i < n:
        if text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("".join("\n" if c == "\n" else " " for c in text[i:j]))
            i = j
        elif text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        else:
            out.append(text[i])
            i += 1
    return "".join(out)


class _Line:
    """One source line (comments blanked) with its number and original text."""

    def __init__(self, number, text, original):
        self.number, self.text, self.original = number, text, original

    def error(self, message, column):
        return GrammarError(message, self.number, column, self.original)

    def source(self, start, end=None):
        return Source(self.text[start:end], self.number, start + 1, self.original)


class _GrammarParser:
    def __init__(self, text, filename=None):
        self.text = text
        self.filename = filename
        self.constants = {}
        self.modules = list(DEFAULT_MODULES)
        self.organs = list(DEFAULT_ORGANS)
        self.ignore = set()
        self.settings = {"angle": DEFAULT_ANGLE, "step": DEFAULT_STEP, "width": DEFAULT_WIDTH,
                         "widthscale": 1.0}
        self.tropism = None
        self.amap = []
        self.n = None
        self.axiom = None
        self.rule_lines = []  # list of [line, start column, list of (line, start) continuations]

    # -- line level --------------------------------------------------------
    def parse(self):
        # Lines end at \n, \r\n or \r only (as editors count them); other Unicode
        # separators stay inside a line, so a '//' comment never runs to the end of file.
        text = self.text.replace("\r\n", "\n").replace("\r", "\n")
        originals = text.split("\n")
        stripped = strip_comments(text).split("\n")
        in_rules = False
        for number, (text, original) in enumerate(zip(stripped, originals), start=1):
            line = _Line(number, text, original)
            body = text.strip()
            if not body:
                continue
            start = len(text) - len(text.lstrip())
            if body.startswith("#"):
                self.directive(line, start)
                in_rules = False
            elif re.match(r"n\s*:", body):
                self.n = self.derivation_count(line, start + text[start:].index(":") + 1)
                in_rules = False
            elif re.match(r"(w|ω)\s*:", body):
                colon = start + text[start:].index(":") + 1
                self.axiom = self.modules_at(line, colon, None, formal=False)
                if not self.axiom:
                    raise line.error("the axiom is empty", colon + 1)
                _check_brackets(self.axiom, "axiom")
                in_rules = False
            elif re.match(r"p\s*:", body):
                in_rules = True
                rest = start + text[start:].index(":") + 1
                if text[rest:].strip():
                    self.rule_lines.append([line, rest, []])
            elif in_rules and ("->" in text or "→" in text):
                self.rule_lines.append([line, start, []])
            elif in_rules and self.rule_lines:
                self.rule_lines[-1][2].append((line, start))
            else:
                raise line.error(
                    "expected a directive (#define, #module, ...), 'n:', 'w:', 'p:' or a rule "
                    "with '->'", start + 1)
        if self.axiom is None:
            raise GrammarError("the grammar has no axiom: add a line 'w: ...'", filename=self.filename)
        if self.n is None:
            raise GrammarError("the grammar has no derivation count: add a line 'n: ...'",
                               filename=self.filename)
        rules = [self.rule(i, *entry) for i, entry in enumerate(self.rule_lines)]
        grammar = Grammar(
            text=self.text, constants=dict(self.constants), axiom=self.axiom, rules=rules, n=self.n,
            modules=tuple(self.modules), organs=tuple(self.organs), ignore=frozenset(self.ignore),
            angle=self.settings["angle"], step=self.settings["step"], width=self.settings["width"],
            width_scale=self.settings["widthscale"],
            tropism=self.tropism, filename=self.filename, amap=tuple(self.amap),
        )
        _check(grammar)
        if grammar.amap:
            from .amap import check_annotations

            check_annotations(grammar)
        return grammar

    def constant(self, line, start, end=None):
        return evaluate_constant(parse_expression(line.source(start, end)), self.constants)

    def derivation_count(self, line, start):
        value = self.constant(line, start)
        if value != int(value) or value < 0:
            raise line.error(f"the derivation count must be a whole number >= 0, not {value:g}",
                             start + 1)
        return int(value)

    def directive(self, line, start):
        text = line.text
        m = re.match(r"#\s*([A-Za-z_]+)\s*:?", text[start:])
        if not m:
            raise line.error("expected a directive name after '#'", start + 1)
        name, rest = m.group(1).lower(), start + m.end()
        if name == "define":
            m2 = re.match(r"\s*([A-Za-z_][A-Za-z_0-9]*)", text[rest:])
            if not m2:
                raise line.error("#define needs a name and a value", rest + 1)
            cname = m2.group(1)
            value_at = rest + m2.end()
            if not text[value_at:].strip():
                raise line.error(f"#define {cname} has no value", value_at + 1)
            self.constants[cname] = self.constant(line, value_at)
        elif name in ("module", "modules", "organ", "organs"):
            for word in re.finditer(r"\S+", text[rest:]):
                if not _NAME.match(word.group()):
                    raise line.error(f"'{word.group()}' is not a valid module name",
                                     rest + word.start() + 1)
                if word.group() not in self.modules:
                    self.modules.append(word.group())
                if name.startswith("organ") and word.group() not in self.organs:
                    self.organs.append(word.group())
            self.modules.sort(key=len, reverse=True)
        elif name == "ignore":
            self.ignore.update(p.symbol for p in self.modules_at(line, rest, None, formal=True))
        elif name in self.settings:
            self.settings[name] = self.constant(line, rest)
        elif name == "amap":  # architecture roles, checked by ramure.lsys.amap once every module is known
            words = [(w.group(), rest + w.start() + 1) for w in re.finditer(r"\S+", text[rest:])]
            if len(words) < 2:
                raise line.error("#amap takes a role and one or more modules, e.g. '#amap internode F'", rest + 1)
            (role, role_col), *symbols = words
            self.amap += [(role, sym, line.number, col, line.original, role_col) for sym, col in symbols]
        elif name == "tropism":
            words = [(w.group(), rest + w.start()) for w in re.finditer(r"\S+", text[rest:])]
            if len(words) != 4:
                raise line.error("#tropism takes four numbers: tx ty tz e", rest + 1)
            self.tropism = tuple(self.constant(line, col, col + len(w)) for w, col in words)
        else:
            raise line.error(
                f"unknown directive '#{m.group(1)}' (known: #define, #module, #organ, #ignore, "
                "#angle, #step, #width, #widthscale, #tropism)", start + 1)

    # -- module strings ----------------------------------------------------
    def modules_at(self, line, start, end, formal, pieces=None):
        """Parse the module string of ``line.text[start:end]`` (plus continuation pieces)."""
        out = []
        for piece_line, a, b in [(line, start, end), *(pieces or [])]:
            out.extend(self._scan(piece_line, a, b, formal))
        return out

    def _scan(self, line, start, end, formal):
        text = line.text if end is None else line.text[:end]
        i, out = start, []
        while i < len(text):
            ch = text[i]
            if ch.isspace():
                i += 1
                continue
            if ch in "),":
                raise line.error(f"unexpected '{ch}'", i + 1)
            if ch == "(":
                raise line.error("'(' must follow a module name directly, as in A(1,2)", i + 1)
            symbol = next((m for m in self.modules if text.startswith(m, i)), ch)
            column = i + 1
            i += len(symbol)
            args = []
            if i < len(text) and text[i] == "(":
                close = _matching_paren(line, text, i)
                args = self._arguments(line, i + 1, close, formal, symbol)
                i = close + 1
            out.append((Pattern if formal else ModuleSpec)(symbol, args, column, line))
        return out

    def _arguments(self, line, start, close, formal, symbol):
        pieces, depth, begin = [], 0, start
        for j in range(start, close):
            c = line.text[j]
            depth += c == "("
            depth -= c == ")"
            if c == "," and depth == 0:
                pieces.append((begin, j))
                begin = j + 1
        pieces.append((begin, close))
        if len(pieces) == 1 and not line.text[start:close].strip():
            raise line.error(f"empty parameter list after {symbol}", start + 1)
        args = []
        for a, b in pieces:
            piece = line.text[a:b]
            if not piece.strip():
                raise line.error(f"empty parameter in {symbol}(...)", a + 1)
            if formal:
                name = piece.strip()
                if not _NAME.match(name):
                    raise line.error(
                        f"a predecessor's parameters must be names, not '{name}'",
                        a + 1 + len(piece) - len(piece.lstrip()))
                args.append(name)
            else:
                args.append(parse_expression(line.source(a, b)))
        return args

    # -- rules -------------------------------------------------------------
    def rule(self, index, line, start, continuations):
        text = line.text
        arrow, width = _find_arrow(text, start)
        if arrow < 0:
            raise line.error("a rule needs '->'", start + 1)
        probability = None
        m = _PROBABILITY.match(text, start)
        lhs_start = start
        if m and m.end() < arrow:
            probability = float(m.group(1))
            if not 0 < probability <= 1:
                raise line.error(f"a rule probability must be in (0, 1], not {m.group(1)}",
                                 m.start(1) + 1)
            lhs_start = m.end()
        colon = _top_level(text, ":", lhs_start, arrow)
        pattern_end = colon if colon >= 0 else arrow
        lt = _top_level(text, "<", lhs_start, pattern_end)
        gt = _top_level(text, ">", lhs_start, pattern_end)
        left = self.modules_at(line, lhs_start, lt, formal=True) if lt >= 0 else []
        pred_start = lt + 1 if lt >= 0 else lhs_start
        pred_end = gt if gt >= 0 else pattern_end
        pred = self.modules_at(line, pred_start, pred_end, formal=True)
        right = self.modules_at(line, gt + 1, pattern_end, formal=True) if gt >= 0 else []
        if len(pred) != 1:
            raise line.error("a rule's predecessor must be exactly one module", pred_start + 1)
        for ctx in (left, right):
            for p in ctx:
                if p.symbol in "[]":
                    raise line.error("brackets inside a context are not supported", p.column)
        rule = Rule(index, line.number, text[start:], line.original, pred[0], [], left, right,
                    None, probability)
        formals = rule.formals
        dup = {f for f in formals if formals.count(f) > 1}
        if dup:
            raise line.error(f"parameter name '{sorted(dup)[0]}' is used twice in one rule",
                             pred_start + 1)
        if colon >= 0:
            cond = text[colon + 1:arrow]
            if cond.strip() not in ("", "*"):
                rule.condition = parse_expression(line.source(colon + 1, arrow))
                compile_expression(rule.condition, formals, self.constants)
        pieces = [(cl, cs, None) for cl, cs in continuations]
        rule.successor = self.modules_at(line, arrow + width, None, formal=False, pieces=pieces)
        for spec in rule.successor:
            for arg in spec.args:
                compile_expression(arg, formals, self.constants)
        _check_brackets(rule.successor, "successor")
        return rule


def _matching_paren(line, text, i):
    depth = 0
    for j in range(i, len(text)):
        depth += text[j] == "("
        depth -= text[j] == ")"
        if depth == 0:
            return j
    raise line.error("unbalanced '(': no matching ')'", i + 1)


def _top_level(text, ch, start, end):
    depth = 0
    for j in range(start, end):
        c = text[j]
        depth += c == "("
        depth -= c == ")"
        if c == ch and depth == 0:
            return j
    return -1


def _find_arrow(text, start):
    for arrow in ("->", "→"):
        j = text.find(arrow, start)
        if j >= 0:
            return j, len(arrow)
    return -1, 0


def _check_brackets(specs, what):
    """Every '[' needs its ']' within the same successor (or axiom)."""
    opened = []
    for spec in specs:
        if spec.symbol == "[":
            opened.append(spec)
        elif spec.symbol == "]":
            if not opened:
                raise spec.line.error(f"unbalanced ']' in the {what}: no '[' before it", spec.column)
            opened.pop()
    if opened:
        raise opened[-1].line.error(f"unbalanced '[' in the {what}: it is never closed",
                                    opened[-1].column)


def _check(grammar):
    """Grammar-wide checks: probabilities and module arities."""
    groups = {}
    for rule in grammar.rules:
        groups.setdefault(rule.group_key(), []).append(rule)
    for rules in groups.values():
        probs = [r.probability for r in rules]
        if all(p is None for p in probs):
            continue
        first = rules[0]
        if any(p is None for p in probs):
            missing = next(r for r in rules if r.probability is None)
            raise GrammarError(
                f"rules for {first.pred} mix probabilities and none: give every rule for "
                f"{first.pred} a probability", missing.line, 1, missing.source_line)
        total = sum(probs)
        if abs(total - 1.0) > 1e-6:
            raise GrammarError(
                f"the probabilities of the rules for {first.pred} sum to {total:g}, not 1",
                first.line, 1, first.source_line)
    arities = {}
    for rule in grammar.rules:
        arities.setdefault(rule.pred.symbol, set()).add(len(rule.pred.params))
    written = [(spec, None) for spec in grammar.axiom]
    written += [(spec, rule) for rule in grammar.rules for spec in rule.successor]
    for spec, rule in written:
        expected = arities.get(spec.symbol)
        if expected and len(spec.args) not in expected:
            want = " or ".join(str(a) for a in sorted(expected))
            raise spec.line.error(
                f"{spec.symbol} is written with {len(spec.args)} parameter(s) here, but the rules "
                f"for {spec.symbol} take {want}", spec.column)
    symbols = []
    for spec, _ in written:
        if spec.symbol not in symbols:
            symbols.append(spec.symbol)
    for rule in grammar.rules:
        for p in [*rule.left, rule.pred, *rule.right]:
            if p.symbol not in symbols:
                symbols.append(p.symbol)
    grammar.symbols = symbols


def parse_grammar(text, filename=None) -> Grammar:
    """Parse grammar text.  Raises :class:`~ramure.lsys.errors.GrammarError` with line and column.

    >>> g = parse_grammar("n: 2\\nw: A(1)\\np:\\n A(x) -> A(x+1)B(x+1)C(1)\\n B(y) -> B(y+3)")
    >>> [str(r.pred) for r in g.rules]
    ['A(x)', 'B(y)']
    """
    try:
        return _GrammarParser(text, filename).parse()
    except GrammarError as err:
        if filename and not err.filename:
            err.filename = filename
            err.args = (err._format(),)
        raise
