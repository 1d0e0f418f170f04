"""The ``.lsys`` grammar language: parsing text into a :class:`Grammar`.

A grammar file looks like ABOP with a few directives::

    /* Honda's sympodial tree (ABOP fig. 2.7) */
    #define r1 0.9          // contraction ratio 1
    #define a1 10
    #angle 90               // default angle of parameterless + - & ^ \\ / turns
    n: 10
    w: A(1,10)
    p:
      A(l,w) : * -> !(w)F(l)[&(a1)B(l*r1,w*0.7)] ...
                    /(180)[&(60)B(l*0.7,w*0.7)]   /* '...' continued the line */
      B(l,w) -> !(w)F(l)[+(a1)$B(l*r1,w*0.7)][-(60)$B(l*0.7,w*0.7)]

Comments never eat turtle symbols: ``/* ... */`` anywhere (it may span
lines); ``//`` to the end of the line only on a line of its own or after a
directive, ``n:`` or a bare ``p:`` (lines that hold no modules).  In an axiom
or a rule ``/`` is always the roll symbol, so ABOP's ``/////`` and ``B//``
stay modules.

Directives (one per line):

``#define NAME expr``
    a constant; may use earlier constants.  Constants are what the variant
    explorer varies and what the UI shows as sliders.
``#function f(x, y) = expr``
    a pure user function, inlined where it is called (in rules, conditions
    and constants).  Its body sees its parameters, ``#define`` constants and
    earlier functions; a function cannot call itself (no recursion).
``#include FILE``
    reads FILE (a path relative to the including file; quotes optional) as if
    its lines stood here: constants, modules, rules.  Cycles are refused
    naming both files; an error inside FILE names FILE and its line.  FILE
    must be a regular file in the grammar's own folder or below it (links and
    ``..`` resolved); anything else is refused unread, and so is any file
    named by text that was typed or loaded without a file of its own.  The
    grammar and its included files hold at most :data:`MAX_TEXT_CHARS`
    characters together.  ``#surface NAME "FILE"`` files follow the same rule.
``#module Name1 Name2 ...``
    multi-letter module names.  Any other letter is a module on its own, so
    ``FF-[-F+F]`` is ten modules.  ``Leaf`` and ``Fruit`` are always declared.
``#organ Name ...``
    declares organ modules drawn as organs (``Leaf`` and ``Fruit`` are organs).
``#ignore: + - F``
    symbols skipped when matching left/right contexts (commas between them
    are allowed: ``#ignore: +, -, F``).
``#consider: A B``
    the dual of ``#ignore`` (L-Py, cpfg): contexts see only these symbols
    (and the brackets); every other symbol is skipped.  Not with ``#ignore``.
``#angle deg``
    the angle of ``+ - & ^ \\ /`` written without a parameter (default 90).
``#step len`` / ``#width w``
    the length of a parameterless ``F``/``f`` (default 1) and the initial
    width (diameter) of the turtle (default 0.1).
``#widthscale s``
    radius = width * s / 2 (default 1), for grammars whose widths are pixels.
``#tropism tx ty tz e``
    ABOP tropism: after each ``F`` the heading bends toward (tx,ty,tz) by
    e·‖H×T‖.  Off by default; e·‖T‖ may be at most :data:`MAX_TROPISM_BEND`.
``#seed N``
    the random seed a plant of this grammar is derived with (a whole number
    >= 0; default 0).  The explorers write it when the user changes the seed,
    so a saved grammar grows the plant that was on screen.
``#dialect cpfg``
    match rules as cpfg does (the cpfg reader writes it; ``ramure import`` keeps it):
    a rule's strict predecessor may be several modules (``XF(x) -> ...``,
    ``spikef -> ...``: one module per letter, as cpfg reads names), and a module
    written with another number of parameters than a rule's predecessor is
    simply not rewritten by that rule (instead of being an error).  The turtle
    reads ``@Gc``, ``@o`` ... as cpfg does.  ``#dialect ramure`` is the default.
``n: N``, ``w: axiom``, ``p:``
    derivation count, axiom, then one rule per line.

Rules: ``[prob] [left <] Pred(x, y) [> right] : condition -> successor [: weight]``.
``*`` (or nothing) as condition means always.  ``*`` as a whole left or right
context (ABOP's ``* < + > * -> -``) means any neighbour, or none: the same as
no context.  A probability prefix must be a decimal number with a point
(``.25``, ``0.5``), so digit symbols such as the ``0 < 1 > 0`` of ABOP
fig. 1.31 stay modules; the probabilities of one predecessor sum to 1.  The
cpfg/L-studio suffix ``A -> B : 0.3`` is a stochastic **weight** (a constant
expression > 0); the weights of the rules with the same predecessor and
contexts are normalised to probabilities.  One group uses one form.

A rule (and the axiom) ends at the end of its line, unless the line ends
with ``...`` (:data:`CONTINUATION`): then the next non-blank line continues
its successor.  Any other line in the rules that is not a rule (``B => A``,
cpfg's ``endlsystem``) is a :class:`GrammarError` with line and column.

Rules sections: ``p:`` (or ``production:``) opens the productions;
``interpretation:`` (or cpfg's ``homomorphism:``) opens interpretation rules,
applied only for drawing (:mod:`ramure.lsys.interpretation.homomorphism`), at most
``#interpretation_depth n`` times (default 1, L-Py's default);
``decomposition:`` opens decomposition rules, applied after each production
step (:mod:`ramure.lsys.history.decompose`), at most ``#decomposition_depth n``
rounds (default 1).  Rules in every section are written alike.  cpfg/L-studio
``.l`` files are read by :mod:`ramure.lsys.language.cpfg`.

Limits, refused with a clear error: a grammar text of more than
:data:`MAX_TEXT_CHARS` characters, a module with more than
:data:`MAX_PARAMETERS` parameters.
"""

from __future__ import annotations

import math
import os
import pathlib
import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ramure.io import FileRefused, read_regular

from ..errors import GrammarError
from ..expr import Expression, Source, compile_expression, define_function, evaluate_constant, parse_expression

if TYPE_CHECKING:
    from ..expr import Function
    from ..interpretation.surfaces import SurfaceDefinition

DEFAULT_MODULES = ("Leaf", "Fruit")
DEFAULT_ORGANS = ("Leaf", "Fruit")
DEFAULT_ANGLE = 90.0
DEFAULT_STEP = 1.0
DEFAULT_WIDTH = 0.1
#: The longest grammar text parsed, in characters (refused at once beyond: a
#: huge pasted axiom would otherwise take minutes before any limit applies).
MAX_TEXT_CHARS = 4_000_000
#: The most parameters one module may have.
MAX_PARAMETERS = 100
#: The largest tropism bend e·‖T‖ (radians per F) accepted.
MAX_TROPISM_BEND = 1000.0
#: How many files deep ``#include`` may nest.
MAX_INCLUDE_DEPTH = 16
#: A rule or axiom line ending with this mark continues on the next non-blank line.
CONTINUATION = "..."
#: The deepest ``#interpretation_depth`` / ``#decomposition_depth`` accepted.
MAX_RULE_DEPTH = 1000  # cpfg files write maximum depth: 100 to 1000; rounds stop once no rule applies
#: Section headers of the rules: their name (and cpfg/L-Py spellings) -> the rule set they open.
SECTIONS = {
    "production": "production",
    "interpretation": "interpretation",
    "homomorphism": "interpretation",
    "decomposition": "decomposition",
}
_SECTION = re.compile(r"(production|interpretation|homomorphism|decomposition)\s*:?\s*$", re.I)
_NAME = re.compile(r"[A-Za-z_][A-Za-z_0-9]*$")
_PROBABILITY = re.compile(r"\s*(\d*\.\d+|\d+\.\d*)\s+")
_CPFG_KEYWORDS = re.compile(
    r"(homomorphism|decomposition|endlsystem|lsystem|derivation\s+length|axiom"
    r"|consider|ignore|define|include|endhomomorphism|enddecomposition)\b",
    re.I,
)


@dataclass
class ModuleSpec:
    """A module written in an axiom or successor: symbol and argument expressions."""

    symbol: str
    args: list  # list[Expression]
    column: int = 1
    line: SourceLine | None = field(default=None, repr=False, compare=False)  # for errors

    def __str__(self) -> str:
        return self.symbol + (f"({','.join(a.text.strip() for a in self.args)})" if self.args else "")


@dataclass
class Pattern:
    """A module in a rule's predecessor or context: symbol and formal parameter names."""

    symbol: str
    params: list
    column: int = 1
    line: object = field(default=None, repr=False, compare=False)

    def __str__(self) -> str:
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
    #: The cpfg-style weight suffix (``A -> B : 0.3``); normalised into ``probability``.
    weight: float | None = None
    #: cpfg's statement blocks before and after the condition (``A : {...} c {...} --> B``):
    #: (:class:`ramure.lsys.language.cstatements.Block` or None, the same), else None.
    blocks: tuple | None = None
    #: The modules of a several-module strict predecessor after the first (``pred``), as cpfg
    #: writes ``XF(x) --> ...`` (``#dialect cpfg``); empty for a one-module predecessor.
    sequence: list = field(default_factory=list)

    @property
    def formals(self) -> list[str]:
        names = []
        for pattern in [*self.left, self.pred, *self.sequence, *self.right]:
            names.extend(pattern.params)
        return names

    @property
    def strict(self) -> list[Pattern]:
        """The strict predecessor's modules: ``pred`` and, in cpfg, the ``sequence`` after it."""
        return [self.pred, *self.sequence]

    @property
    def is_context_sensitive(self) -> bool:
        return bool(self.left or self.right)

    def group_key(self) -> tuple:
        """Rules with the same key compete for the same modules (stochastic choice)."""
        key = (
            self.pred.symbol,
            len(self.pred.params),
            tuple((p.symbol, len(p.params)) for p in self.left),
            tuple((p.symbol, len(p.params)) for p in self.right),
        )
        return key + (tuple((p.symbol, len(p.params)) for p in self.sequence),) if self.sequence else key

    def __str__(self) -> str:
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
    #: The ``#seed`` directive's value (None: the text has none; plants derive with seed 0).
    seed: int | None = None
    symbols: list = field(default_factory=list)
    amap: tuple = ()  # (role, symbol, line, column, source line) of each #amap annotation
    #: Rules of the ``interpretation:`` section (applied only for drawing, see
    #: :mod:`ramure.lsys.interpretation.homomorphism`) and of the ``decomposition:`` section (applied after
    #: each production step, see :mod:`ramure.lsys.history.decompose`), with their maximum depths.
    interpretation: list = field(default_factory=list)
    decomposition: list = field(default_factory=list)
    interpretation_depth: int = 1
    decomposition_depth: int = 1
    #: ``#surface`` definitions (name -> :class:`ramure.lsys.interpretation.surfaces.SurfaceDefinition`) and the
    #: ``#material i r g b [a]`` table (index -> (r, g, b, a), components 0..1).
    surfaces: dict = field(default_factory=dict)
    materials: dict = field(default_factory=dict)
    #: cpfg's statement blocks (``define``, ``start``, ``starteach``, ``endeach``, ``end`` ->
    #: :class:`ramure.lsys.language.cstatements.Block`), run by :meth:`ramure.lsys.LSystem.derive`.
    programs: dict = field(default_factory=dict)
    #: The language the text was written in where the turtle reads a symbol its way: ``"cpfg"``
    #: (``@Gc`` a cylinder's control point, ``@o(d)`` a diameter), else ``""``.  cpfg files
    #: (and ``.lsys`` text with ``#dialect cpfg``) may have several-module predecessors.
    dialect: str = ""
    #: The built-in environment cpfg's ``?E`` modules talk to (:mod:`ramure.lsys.language.cpfg_environment`):
    #: ``{"program": "honda81", "radius": r, "3d": bool}``, else empty.
    environment: dict = field(default_factory=dict)

    def symbol_id(self, name: str) -> int:
        return self.symbols.index(name)


def strip_comments(text: str) -> str:
    """Blank out comments, keeping every other column (and every newline) in place.

    ``/* ... */`` anywhere (it may span lines).  ``//`` runs to the end of the
    line only where it cannot be a turtle symbol: on a line of its own, or
    after a directive (``#...``), ``n:`` or a ``p:`` with no rule on its line.
    In an axiom or a rule ``/`` is the roll symbol, so ``/////`` stays five modules.

    >>> strip_comments("w: A/////B // rolls\\n// note\\n#angle 30 // degrees")
    'w: A/////B // rolls\\n       \\n#angle 30           '
    """
    out, in_block = [], False
    for line in text.split("\n"):
        chars, in_block = _strip_line(line, in_block)
        out.append("".join(chars))
    return "\n".join(out)


def _strip_line(line, in_block):
    """One line of :func:`strip_comments`: its characters and whether a block comment stays open."""
    chars, i, n, kind = list(line), 0, len(line), None
    while i < n:
        if in_block:
            j = line.find("*/", i)
            end = n if j < 0 else j + 2
            chars[i:end] = " " * (end - i)
            in_block, i = j < 0, end
        elif line.startswith("/*", i):
            chars[i : i + 2] = "  "
            in_block, i = True, i + 2
        elif line.startswith("//", i) and kind in (None, "value"):
            chars[i:] = " " * (n - i)
            break
        else:
            if kind is None and not line[i].isspace():
                kind = _line_kind(line, i)
            i += 1
    return chars, in_block


def starts_line_comment(line: str, i: int) -> bool:
    """Whether the ``//`` at column ``i`` (0-based) of ``line`` starts a comment (for editors).

    >>> starts_line_comment("  // note", 2), starts_line_comment("A -> B//", 6), starts_line_comment("n: 3 // x", 5)
    (True, False, True)
    """
    before = line[:i]
    return line.startswith("//", i) and (not before.strip() or _line_kind(line, len(before) - len(before.lstrip())) == "value")


def _line_kind(line, i) -> str:
    """'value' for lines without modules (directives, ``n:``, a bare ``p:``), else 'modules'."""
    rest = line[i:]
    if rest.startswith("#") or re.match(r"n\s*:", rest):
        return "value"
    if re.match(r"p\s*:", rest) and "->" not in rest and "\u2192" not in rest:
        return "value"
    if _SECTION.match(rest.rstrip().split("//")[0].rstrip()):
        return "value"
    return "modules"


class SourceLine:
    """One source line (comments blanked) with its number and original text."""

    def __init__(self, number: int, text: str, original: str, filename: str | None = None) -> None:
        self.number, self.text, self.original = number, text, original
        self.filename = filename  # set for lines of an #include'd file

    def error(self, message: str, column: int) -> GrammarError:
        """A :class:`GrammarError` pointing at ``column`` (1-based) of this line."""
        return GrammarError(message, self.number, column, self.original, filename=self.filename)

    def source(self, start: int, end: int | None = None) -> Source:
        """The text ``[start:end]`` of this line, positioned for expression errors."""
        return Source(self.text[start:end], self.number, start + 1, self.original)


#: A continuation piece of a rule or axiom: the text ``line.text[start:end]``.
Piece = tuple[SourceLine, int, int | None]


class GrammarParser:
    """Reads a grammar's text into a :class:`Grammar`; directive modules (``#surface``,
    ``#material``) get it to read constants and module strings at a :class:`SourceLine`."""

    def __init__(self, text: str, filename: str | None = None) -> None:
        self.text = text
        self.filename = filename
        self.constants: dict[str, float] = {}
        self.functions: dict[str, Function] = {}  # #function name -> expr.Function, inlined where called
        self.modules = list(DEFAULT_MODULES)
        self.organs = list(DEFAULT_ORGANS)
        self.context_filter: dict[str, set[str]] = {"ignore": set(), "consider": set()}
        self.includes = [str(pathlib.Path(filename).resolve())] if filename else []
        #: The folder ``#include`` and ``#surface "FILE"`` files must lie in (symbolic links and
        #: ``..`` resolved): the grammar file's own folder, as the user opened it.  Text with no
        #: file name reads no file at all.
        self.root = confinement_root(filename)
        self.chars_read = len(text)  # the grammar and its #include files: MAX_TEXT_CHARS in all
        self.settings = {"angle": DEFAULT_ANGLE, "step": DEFAULT_STEP, "width": DEFAULT_WIDTH, "widthscale": 1.0}
        self.tropism: tuple[float, ...] | None = None
        self.amap: list[tuple] = []
        self.surfaces: dict[str, SurfaceDefinition] = {}
        self.materials: dict[int, tuple[float, ...]] = {}  # #surface, #material: interpretation.surfaces, .materials
        self.n: int | None = None
        self.seed: int | None = None
        self.axiom: list[ModuleSpec] | None = None
        self.rule_lines: list[list] = []  # [line, start, end, continuation pieces (line, start, end)] per rule
        self.section = "production"  # the rules section being read (production, interpretation, ...)
        self.section_lines: dict[str, list[list]] = {"interpretation": [], "decomposition": []}
        self.depths = {"interpretation": 1, "decomposition": 1}
        self.dialect = ""  # '#dialect cpfg': cpfg's matching (several-module predecessors, any arity written)
        self._token_key: tuple[str, ...] | None = None
        self._token_re: re.Pattern[str] | None = None

    # -- line level --------------------------------------------------------
    def parse(self) -> Grammar:
        """The :class:`Grammar` of the whole text."""
        self.read(self.text, None)
        return self.finish()

    def read(self, text: str, filename: str | None) -> None:
        """Read the lines of ``text`` (the grammar, or an ``#include``'d file named ``filename``)."""
        # Lines end at \n, \r\n or \r only (as editors count them); other Unicode
        # separators stay inside a line, so a '//' comment never runs to the end of file.
        text = text.replace("\r\n", "\n").replace("\r", "\n")
        lines = [
            SourceLine(number, t, o, filename)
            for number, (t, o) in enumerate(zip(strip_comments(text).split("\n"), text.split("\n")), start=1)
        ]
        try:
            self._read_lines(lines)
        except GrammarError as err:
            if filename and not err.filename:  # e.g. an expression error on an #include'd line
                err.filename = filename
                err.args = (err.formatted(),)
            raise

    def _read_lines(self, lines):
        in_rules, k = False, 0
        while k < len(lines):
            line = lines[k]
            k += 1
            text = line.text
            body = text.strip()
            if not body:
                continue
            start = len(text) - len(text.lstrip())
            if body.startswith("#"):
                self.directive(line, start)
                # a depth directive may stand inside its section (cpfg's 'maximum depth:'); others end it
                in_rules = in_rules and re.match(r"#\s*(interpretation|decomposition)_depth\b", body) is not None
            elif re.match(r"p\s*:", body):
                in_rules, self.section = True, "production"
                rest = start + text[start:].index(":") + 1
                if text[rest:].strip():
                    end, pieces, k = _continued(lines, k, line)
                    self.add_rule([line, rest, end, pieces])
            elif section := _SECTION.match(body):
                in_rules, self.section = True, SECTIONS[section.group(1).lower()]
            elif in_rules and _find_arrow(text, start)[0] >= 0:
                end, pieces, k = _continued(lines, k, line)
                self.add_rule([line, start, end, pieces])
            elif re.match(r"n\s*:", body):
                self.n = self.derivation_count(line, start + text[start:].index(":") + 1)
                in_rules = False
            elif re.match(r"(w|\u03c9)\s*:", body):
                colon = start + text[start:].index(":") + 1
                end, pieces, k = _continued(lines, k, line)
                self.axiom = self.modules_at(line, colon, end, formal=False, pieces=pieces)
                if not self.axiom:
                    raise line.error("the axiom is empty", colon + 1)
                _check_brackets(self.axiom, "axiom")
                in_rules = False
            elif in_rules:
                raise _not_a_rule(line, start)
            else:
                raise line.error("expected a directive (#define, #module, ...), 'n:', 'w:', 'p:' or a rule with '->'", start + 1)

    def add_rule(self, entry: list) -> None:
        """Record a rule's lines in the section being read."""
        if self.section == "production":
            self.rule_lines.append(entry)
        else:
            self.section_lines[self.section].append(entry)

    def finish(self) -> Grammar:
        """The :class:`Grammar` of every line read."""
        if self.axiom is None:
            raise GrammarError("the grammar has no axiom: add a line 'w: ...'", filename=self.filename)
        if self.n is None:
            raise GrammarError("the grammar has no derivation count: add a line 'n: ...'", filename=self.filename)
        rules = [_located(self.rule, entry[0], i, *entry) for i, entry in enumerate(self.rule_lines)]
        grammar = Grammar(
            text=self.text,
            constants=dict(self.constants),
            axiom=self.axiom,
            rules=rules,
            n=self.n,
            modules=tuple(self.modules),
            organs=tuple(self.organs),
            ignore=frozenset(self.context_filter["ignore"]),
            angle=self.settings["angle"],
            step=self.settings["step"],
            width=self.settings["width"],
            width_scale=self.settings["widthscale"],
            tropism=self.tropism,
            filename=self.filename,
            seed=self.seed,
            amap=tuple(self.amap),
            interpretation_depth=self.depths["interpretation"],
            decomposition_depth=self.depths["decomposition"],
            dialect=self.dialect,
        )
        for name, entries in self.section_lines.items():
            setattr(grammar, name, [_located(self.rule, entry[0], i, *entry) for i, entry in enumerate(entries)])
        grammar.surfaces, grammar.materials = dict(self.surfaces), dict(self.materials)
        _check(grammar)
        _check_drawing(grammar)
        if self.context_filter["consider"]:  # the dual of #ignore: every other symbol but brackets
            grammar.ignore = frozenset(set(grammar.symbols) - self.context_filter["consider"] - {"[", "]"})
        if grammar.amap:
            from ..architecture.amap import check_annotations

            check_annotations(grammar)
        return grammar

    def constant(self, line: SourceLine, start: int, end: int | None = None) -> float:
        """The value of the constant expression ``line.text[start:end]`` (``#define`` names known)."""
        return evaluate_constant(parse_expression(line.source(start, end), functions=self.functions), self.constants)

    def derivation_count(self, line: SourceLine, start: int) -> int:
        """The ``n:`` value at ``start``: a whole number >= 0."""
        value = self.constant(line, start)
        if value != int(value) or value < 0:
            raise line.error(f"the derivation count must be a whole number >= 0, not {value:g}", start + 1)
        return int(value)

    def random_seed(self, line: SourceLine, start: int) -> int:
        """The ``#seed`` value at ``start``: a whole number from 0 to 2^63 - 1."""
        if not line.text[start:].strip():
            raise line.error("#seed needs a whole number, e.g. '#seed 7'", start + 1)
        value = self.constant(line, start)
        if value != int(value) or not 0 <= value < 2**63:
            at = start + 1 + len(line.text[start:]) - len(line.text[start:].lstrip())
            raise line.error(f"the seed must be a whole number >= 0, not {value:g}", at)
        return int(value)

    def directive(self, line: SourceLine, start: int) -> None:
        """Read the ``#name ...`` directive at ``start``."""
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
                    raise line.error(f"'{word.group()}' is not a valid module name", rest + word.start() + 1)
                if word.group() not in self.modules:
                    self.modules.append(word.group())
                if name.startswith("organ") and word.group() not in self.organs:
                    self.organs.append(word.group())
            self.modules.sort(key=len, reverse=True)
        elif name == "include":
            self.include(line, rest)
        elif name == "function":
            function = define_function(line.source(rest), functions=self.functions, constants=self.constants)
            self.functions[function.name] = function
        elif name in ("ignore", "consider"):  # ABOP writes '#ignore: +-F'; commas are allowed too
            other = "consider" if name == "ignore" else "ignore"
            if self.context_filter[other]:
                raise line.error(
                    f"#{name} and #{other} cannot both be used: #consider lists the only "
                    "symbols contexts see, #ignore the symbols they skip",
                    start + 1,
                )
            listed = SourceLine(line.number, _blank_top_level_commas(text), line.original)
            self.context_filter[name].update(p.symbol for p in self.modules_at(listed, rest, None, formal=True))
        elif name in self.settings:
            self.settings[name] = self.constant(line, rest)
        elif name == "seed":
            self.seed = self.random_seed(line, rest)
        elif name in ("interpretation_depth", "decomposition_depth"):
            depth = self.constant(line, rest)
            if depth != int(depth) or not 1 <= depth <= MAX_RULE_DEPTH:
                raise line.error(
                    f"#{name} must be a whole number from 1 to {MAX_RULE_DEPTH}, not {depth:g}",
                    rest + 1 + len(text[rest:]) - len(text[rest:].lstrip()),
                )
            self.depths[name.split("_")[0]] = int(depth)
        elif name == "amap":  # architecture roles, checked by ramure.lsys.architecture.amap once every module is known
            words = [(w.group(), rest + w.start() + 1) for w in re.finditer(r"\S+", text[rest:])]
            if len(words) < 2:
                raise line.error("#amap takes a role and one or more modules, e.g. '#amap internode F'", rest + 1)
            (role, role_col), *symbols = words
            self.amap += [(role, sym, line.number, col, line.original, role_col) for sym, col in symbols]
        elif name == "surface":
            from ..interpretation.surfaces import parse_directive

            definition = parse_directive(self, line, rest)
            self.surfaces[definition.name] = definition
        elif name == "material":
            from ..interpretation.materials import parse_directive as parse_material

            index, rgba = parse_material(self, line, rest)
            self.materials[index] = rgba
        elif name == "dialect":
            dialect = text[rest:].strip().lower()
            if dialect not in ("cpfg", "ramure"):
                raise line.error(f"#dialect is 'cpfg' or 'ramure', not '{text[rest:].strip()}'", rest + 1)
            self.dialect = "" if dialect == "ramure" else dialect
        elif name == "tropism":
            words = [(w.group(), rest + w.start()) for w in re.finditer(r"\S+", text[rest:])]
            if len(words) != 4:
                raise line.error("#tropism takes four numbers: tx ty tz e", rest + 1)
            self.tropism = tuple(self.constant(line, col, col + len(w)) for w, col in words)
            _check_tropism(line, rest, self.tropism)
        else:
            raise line.error(
                f"unknown directive '#{m.group(1)}' (known: #define, #function, #include, #module, #organ, "
                "#ignore, #consider, #angle, #step, #width, #widthscale, #seed, #tropism, #amap, #surface, #material, "
                "#interpretation_depth, #decomposition_depth, #dialect)",
                start + 1,
            )

    def include(self, line: SourceLine, start: int) -> None:
        """``#include FILE``: read FILE (relative to the including file) as if its lines stood here.

        FILE must be a regular file in the grammar's folder or below it (:attr:`root`): an
        absolute path elsewhere, a ``..`` or a symbolic link out of it is refused without
        reading it, and so is a device or a pipe.  The grammar and all its included files hold
        at most :data:`MAX_TEXT_CHARS` characters together."""
        word = line.text[start:].strip()
        quoted = len(word) >= 2 and (word[0] + word[-1]) in ('""', "''", "<>")
        name = word[1:-1] if quoted else word
        if not name:
            raise line.error('#include needs a file name, e.g. #include "leaves.lsys"', start + 1)
        including = line.filename or self.filename
        path = self.confined(line, start, "#include", name, including)
        chain = self.includes
        if str(path) in chain:
            raise line.error(
                f"#include cycle: {including or 'the grammar'} includes {name}, which "
                f"(directly or not) includes {including or 'the grammar'} again",
                start + 1,
            )
        if len(chain) > MAX_INCLUDE_DEPTH:
            raise line.error(f"#include nests more than {MAX_INCLUDE_DEPTH} files deep", start + 1)
        try:
            text = read_regular(path, 4 * MAX_TEXT_CHARS, "#include").decode("utf-8-sig")
        except (FileRefused, UnicodeDecodeError) as exc:
            reason = exc.reason if isinstance(exc, FileRefused) else "it is not UTF-8 text"
            raise line.error(f"cannot #include {name} ({path}): {reason}", start + 1) from None
        self.chars_read += len(text)
        if len(text) > MAX_TEXT_CHARS or self.chars_read > MAX_TEXT_CHARS:
            raise line.error(
                f"#include {name}: the grammar and its included files have more than {MAX_TEXT_CHARS:,} characters",
                start + 1,
            )
        chain.append(str(path))
        try:
            self.read(text, str(path))
        finally:
            chain.pop()

    def check_file(self, path: pathlib.Path) -> None:
        """Parse the grammar file ``path`` (a ``#surface`` names one): its first error, raised."""
        parse_grammar(read_grammar_file(path), str(path))

    def confined(self, line: SourceLine, start: int, directive: str, name: str, including: str | None) -> pathlib.Path:
        """The resolved path of file ``name`` named by ``directive`` on ``line``, relative to the
        ``including`` file's folder; refused (line, column) unless it lies in :attr:`root`."""
        if self.root is None or including is None:
            raise line.error(
                f"{directive} {name}: a grammar typed or loaded without a file reads no other file; "
                "save it in a folder beside the files it names",
                start + 1,
            )
        path = (pathlib.Path(including).absolute().parent / name).resolve()
        if not path.is_relative_to(self.root):
            raise line.error(
                f"{directive} {name}: the file is outside the grammar's folder {self.root}; "
                "a grammar reads files in its own folder and below only",
                start + 1,
            )
        return path

    # -- module strings ----------------------------------------------------
    def modules_at(self, line: SourceLine, start: int, end: int | None, formal: bool, pieces: list[Piece] | None = None) -> list:
        """Parse the module string of ``line.text[start:end]`` (plus continuation pieces)."""
        out = []
        for piece_line, a, b in [(line, start, end), *(pieces or [])]:
            out.extend(self._scan(piece_line, a, b, formal))
        return out

    def _scan(self, line, start, end, formal):
        text = line.text if end is None else line.text[:end]
        out, token = [], self._token()
        make = Pattern if formal else ModuleSpec
        m = token.search(text, start)
        while m is not None:
            symbol, i = m.group(), m.end()
            if symbol == ")":
                raise line.error(_comma_message(symbol), m.start() + 1)
            if symbol == "(":
                raise line.error("'(' must follow a module name directly, as in A(1,2)", m.start() + 1)
            args = []
            if i < len(text) and text[i] == "(":
                close = _matching_paren(line, text, i)
                args = self._arguments(line, i + 1, close, formal, symbol)
                i = close + 1
            out.append(make(symbol, args, m.start() + 1, line))
            m = token.search(text, i)
        return out

    def _token(self):
        """A regex for one module symbol: a declared name (longest first) or one character."""
        key = tuple(self.modules)
        if self._token_key != key:
            names = sorted(key, key=len, reverse=True)
            # @O (sphere), @Ts (elasticity), the other @ commands and ~name (a surface) are single modules
            at_names = r"@Ts|@Tp|@Tx|@Gs|@Gc|@Ge|@Gt|@O|@o|@c|@v|@M|@R|@B|@#|@!"
            self._token_re = re.compile("|".join([*(re.escape(n) for n in names), at_names, r"\?[PHLUE]|~[A-Za-z_]\w*", r"\S"]))
            self._token_key = key
        return self._token_re

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
        if len(pieces) > MAX_PARAMETERS:
            raise line.error(f"{symbol} has {len(pieces)} parameters; a module may have at most {MAX_PARAMETERS}", start)
        args = []
        for a, b in pieces:
            piece = line.text[a:b]
            if not piece.strip():
                raise line.error(f"empty parameter in {symbol}(...)", a + 1)
            if formal:
                name = piece.strip()
                if not _NAME.match(name):
                    raise line.error(
                        f"a predecessor's parameters must be names, not '{name}'", a + 1 + len(piece) - len(piece.lstrip())
                    )
                args.append(name)
            else:
                args.append(parse_expression(line.source(a, b), functions=self.functions))
        return args

    # -- rules -------------------------------------------------------------
    def rule(self, index: int, line: SourceLine, start: int, end: int | None, continuations: list[Piece]) -> Rule:
        """The rule ``index`` written at ``line.text[start:end]`` plus its continuation pieces."""
        text = line.text if end is None else line.text[:end]
        arrow, width = _find_arrow(text, start)
        if arrow < 0:
            raise line.error("a rule needs '->'", start + 1)
        probability, probability_at = None, 0
        m = _PROBABILITY.match(text, start)
        lhs_start = start
        if m and m.end() < arrow:
            probability, probability_at = float(m.group(1)), m.start(1) + 1
            if not 0 < probability <= 1:
                raise line.error(f"a rule probability must be in (0, 1], not {m.group(1)}", probability_at)
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
        if not pred or len(pred) > 1 and self.dialect != "cpfg":
            raise line.error(
                "a rule's predecessor must be exactly one module (several, as in cpfg's 'XF(x) --> ...', "
                "only with '#dialect cpfg')",
                pred_start + 1,
            )
        left, right = _context(line, left), _context(line, right)
        for ctx in (left, right):
            for p in ctx:
                if p.symbol in "[]":
                    raise line.error("brackets inside a context are not supported", p.column)
        pieces = [(line, arrow + width, end), *continuations]
        rule_text = " ".join(pl.text[a:b].strip() for pl, a, b in [(line, start, end), *continuations])
        rule = Rule(index, line.number, rule_text, line.original, pred[0], [], left, right, None, probability)
        rule.sequence = pred[1:]
        formals = rule.formals
        dup = {f for f in formals if formals.count(f) > 1}
        if dup:
            raise line.error(f"parameter name '{sorted(dup)[0]}' is used twice in one rule", pred_start + 1)
        if colon >= 0:
            cond = text[colon + 1 : arrow]
            if cond.strip() not in ("", "*"):
                rule.condition = parse_expression(line.source(colon + 1, arrow), functions=self.functions)
                compile_expression(rule.condition, formals, self.constants)
        pieces, rule.weight = self._weight(pieces)
        if rule.sequence and (rule.weight is not None or probability is not None):
            raise line.error("a rule whose predecessor is several modules cannot be stochastic", pred_start + 1)
        if rule.weight is not None and probability is not None:
            raise line.error(
                "a rule has either a probability prefix ('.5 A -> B') or a weight suffix ('A -> B : 0.5'), not both",
                probability_at,
            )
        for pl, a, b in pieces:
            second, _ = _find_arrow(pl.text if b is None else pl.text[:b], a)
            if second >= 0:
                raise pl.error("a second '->' in one rule: write one rule per line", second + 1)
        (first, a, b), *rest = pieces
        rule.successor = self.modules_at(first, a, b, formal=False, pieces=rest)
        for spec in rule.successor:
            for arg in spec.args:
                compile_expression(arg, formals, self.constants)
        _check_brackets(rule.successor, "successor")
        return rule

    def _weight(self, pieces):
        """Split a cpfg/L-studio weight suffix ``: w`` off a successor's pieces: (pieces, weight or None)."""
        for k, (pl, a, b) in enumerate(pieces):
            text = pl.text if b is None else pl.text[:b]
            c = _top_level(text, ":", a, len(text))
            if c < 0:
                continue
            if k < len(pieces) - 1:
                raise pl.error("a weight suffix ': w' must end the rule (it is followed by a continued line)", c + 1)
            if not text[c + 1 :].strip():
                raise pl.error("':' in a successor starts a weight: write 'A -> B : 0.5' (a number > 0)", c + 1)
            weight = self.constant(pl, c + 1, b)
            if not weight > 0:
                raise pl.error(f"a rule weight must be a number > 0, not {weight:g}", c + 2)
            return [*pieces[:k], (pl, a, c)], weight
        return pieces, None


def _continued(lines, k, line):
    """Follow ``...`` continuations from ``line`` (``lines[k]`` is the next line).

    Returns (end of ``line``'s own text, continuation pieces as (line, start, end),
    index of the first line after them).  A continuation must be the rest of a
    successor or axiom: a directive, ``n:``/``w:``/``p:`` or another rule there
    is an error naming the ``...`` that asked for it.
    """
    pieces: list[Piece] = []
    current = line
    end = _continuation_at(line)
    while True:
        cont = _continuation_at(current)
        if cont is None:
            return end, pieces, k
        while k < len(lines) and not lines[k].text.strip():
            k += 1
        if k == len(lines):
            raise current.error(f"the line ends with '{CONTINUATION}' but no line follows to continue it", cont + 1)
        nxt, k = lines[k], k + 1
        body = nxt.text.strip()
        if body.startswith("#") or re.match(r"[nwp\u03c9]\s*:", body) or _find_arrow(nxt.text, 0)[0] >= 0:
            raise nxt.error(
                f"line {current.number} ends with '{CONTINUATION}', but this line is not the "
                "rest of its successor (remove the '...' or join the lines)",
                len(nxt.text) - len(nxt.text.lstrip()) + 1,
            )
        start = len(nxt.text) - len(nxt.text.lstrip())
        pieces.append((nxt, start, _continuation_at(nxt)))
        current = nxt


def _continuation_at(line):
    """Column (0-based) of the ``...`` ending ``line``'s text, or None."""
    text = line.text.rstrip()
    return len(text) - len(CONTINUATION) if text.endswith(CONTINUATION) else None


def _not_a_rule(line, start):
    """The error for a line of the rules section that is not a rule."""
    text = line.text
    if "=>" in text:
        return line.error("'=>' is not a rule arrow: write '->'", text.index("=>") + 1)
    m = _CPFG_KEYWORDS.match(text, start)
    if m:
        return line.error(
            f"'{m.group()}' is a cpfg keyword that Ramure does not read here: directives start with '#' and rules have '->'",
            start + 1,
        )
    return line.error(
        f"this line is not a rule (no '->'): a rule is 'predecessor -> successor' on one "
        f"line; end a line with '{CONTINUATION}' to continue its successor on the next",
        start + 1,
    )


def _located(parse, line, *args):
    """Call ``parse(*args)``; an error from an #include'd line names that file."""
    try:
        return parse(*args)
    except GrammarError as err:
        if line.filename and not err.filename:
            err.filename = line.filename
            err.args = (err.formatted(),)
        raise


def _context(line, patterns):
    """A left or right context; ABOP's ``*`` as the whole context means any neighbour (or none)."""
    stars = [p for p in patterns if p.symbol == "*"]
    if not stars:
        return patterns
    if len(patterns) == 1 and not stars[0].params:
        return []
    raise line.error(
        "'*' stands for a whole context (any neighbour, or none): it cannot be combined with other modules or take parameters",
        stars[0].column,
    )


def _comma_message(symbol) -> str:
    if symbol == ",":
        return (
            "unexpected ',': a comma only separates parameters, as in A(1,2); modules follow "
            "each other without one (write AB, not A,B)"
        )
    return f"unexpected '{symbol}'"


def _blank_top_level_commas(text):
    out, depth = [], 0
    for c in text:
        depth += (c == "(") - (c == ")")
        out.append(" " if c == "," and depth == 0 else c)
    return "".join(out)


def _check_tropism(line, column, tropism):
    """``#tropism tx ty tz e``: the bend e·|T| must be a usable number of radians per F."""
    tx, ty, tz, e = tropism
    size = math.sqrt(tx * tx + ty * ty + tz * tz) if math.isfinite(tx * tx + ty * ty + tz * tz) else math.inf
    if not math.isfinite(size) or abs(e) * size > MAX_TROPISM_BEND:
        raise line.error(
            f"#tropism bends by e*|T| = {abs(e) * size:g} radians per F; it may be at most "
            f"{MAX_TROPISM_BEND:g} (use a unit direction T and a small e such as 0.2)",
            column + 1,
        )


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
        raise opened[-1].line.error(f"unbalanced '[' in the {what}: it is never closed", opened[-1].column)


def _check_drawing(grammar) -> None:
    """Polygon and surface mistakes visible before deriving (:mod:`ramure.lsys.interpretation.polygons`, ``surfaces``)."""
    from ..interpretation.polygons import check_grammar as check_polygons
    from ..interpretation.surfaces import check_grammar as check_surfaces

    check_polygons(grammar)
    check_surfaces(grammar)


def _check(grammar):
    """Grammar-wide checks: probabilities and module arities (over every rules section)."""
    every = [*grammar.rules, *grammar.decomposition, *grammar.interpretation]
    for section in (grammar.rules, grammar.decomposition, grammar.interpretation):
        groups: dict[tuple, list[Rule]] = {}
        for rule in section:
            groups.setdefault(rule.group_key(), []).append(rule)
        for rules in groups.values():
            _check_probabilities(rules)
    arities: dict[str, set[int]] = {}
    for rule in every if grammar.dialect != "cpfg" else []:  # cpfg: a rule matches its own arity only
        arities.setdefault(rule.pred.symbol, set()).add(len(rule.pred.params))
    written = [(spec, None) for spec in grammar.axiom]
    written += [(spec, rule) for rule in every for spec in rule.successor]
    for spec, _rule in written:
        expected = arities.get(spec.symbol)
        if expected and len(spec.args) not in expected:
            want = " or ".join(str(a) for a in sorted(expected))
            raise spec.line.error(
                f"{spec.symbol} is written with {len(spec.args)} parameter(s) here, but the rules for {spec.symbol} take {want}",
                spec.column,
            )
    symbols = []
    for spec, _ in written:
        if spec.symbol not in symbols:
            symbols.append(spec.symbol)
    for rule in every:
        for p in [*rule.left, rule.pred, *rule.sequence, *rule.right]:
            if p.symbol not in symbols:
                symbols.append(p.symbol)
    grammar.symbols = symbols


def _check_probabilities(rules):
    """One group of competing rules: prefix probabilities sum to 1; suffix weights are normalised."""
    weighted = [r for r in rules if r.weight is not None]
    prefixed = [r for r in rules if r.probability is not None]
    if not weighted and not prefixed:
        return
    first = rules[0]
    if weighted and prefixed:
        raise GrammarError(
            f"rules for {first.pred} mix probability prefixes ('.5 A -> B') and weight suffixes ('A -> B : 0.5'): use one form",
            weighted[0].line,
            1,
            weighted[0].source_line,
        )
    if len(weighted) + len(prefixed) < len(rules):
        missing = next(r for r in rules if r.probability is None and r.weight is None)
        what, one = ("weights", "a weight") if weighted else ("probabilities", "a probability")
        raise GrammarError(
            f"rules for {first.pred} mix {what} and none: give every rule for {first.pred} {one}",
            missing.line,
            1,
            missing.source_line,
        )
    if weighted:
        total = sum(r.weight for r in weighted)
        for r in weighted:
            r.probability = r.weight / total
        return
    total = sum(r.probability for r in prefixed)
    if abs(total - 1.0) > 1e-6:
        raise GrammarError(
            f"the probabilities of the rules for {first.pred} sum to {total:g}, not 1", first.line, 1, first.source_line
        )


def read_grammar_file(path: str | os.PathLike) -> str:
    """The text of grammar file ``path``: a regular UTF-8 file (a BOM is dropped) of at most
    :data:`MAX_TEXT_CHARS` characters; anything else is a :class:`GrammarError` naming the file
    (never a device or a pipe read without end)."""
    try:
        raw = read_regular(path, 4 * MAX_TEXT_CHARS, "grammar")
    except FileRefused as exc:
        raise GrammarError(f"cannot read the grammar: {exc.reason}", filename=str(path)) from None
    try:
        return raw.decode("utf-8-sig")  # -sig: a BOM (Windows editors) is not text
    except UnicodeDecodeError as exc:
        raise GrammarError(
            f"the file is not UTF-8 text (byte 0x{raw[exc.start]:02x} cannot be decoded); save it as UTF-8",
            raw[: exc.start].count(b"\n") + 1,
            filename=str(path),
        ) from None


def confinement_root(filename: str | os.PathLike | None) -> pathlib.Path | None:
    """The folder a grammar named ``filename`` may read ``#include`` and ``#surface`` files
    from: the folder it stands in (resolved), or None for text with no file name."""
    return pathlib.Path(filename).absolute().parent.resolve() if filename else None


def parse_grammar(
    text: str, filename: str | None = None, functions: dict | None = None, constants: dict[str, float] | None = None
) -> Grammar:
    """Parse grammar text.  Raises :class:`~ramure.lsys.errors.GrammarError` with line and column.

    ``functions`` and ``constants`` are known before the first line (the cpfg reader gives
    ``func`` and the names of a view file's function set this way).

    >>> g = parse_grammar("n: 2\\nw: A(1)\\np:\\n A(x) -> A(x+1)B(x+1)C(1)\\n B(y) -> B(y+3)")
    >>> [str(r.pred) for r in g.rules]
    ['A(x)', 'B(y)']
    """
    if len(text) > MAX_TEXT_CHARS:
        raise GrammarError(
            f"the grammar text has {len(text):,} characters, more than the limit of "
            f"{MAX_TEXT_CHARS:,}: a grammar is a few rules, not a derived string",
            filename=filename,
        )
    try:
        parser = GrammarParser(text, filename)
        parser.functions.update(functions or {})  # e.g. cpfg's func(id, x) (lsys.language.cpfg_functions)
        parser.constants.update(constants or {})
        return parser.parse()
    except GrammarError as err:
        if filename and not err.filename:
            err.filename = filename
            err.args = (err.formatted(),)
        raise
