"""Translate an L-Py ``.lpy`` file into Python, as L-Py's own parser does (for :mod:`ramure.lsys.readers.lpy`).

The file's Python stays as it is; its L-system sections become Python:

==================================  ==============================================================
``.lpy``                            Python
==================================  ==============================================================
``Axiom: A(1) B``                   ``__axiom__ = [("A", (1,)), ("B", ())]`` (or a body of ``nproduce``)
``derivation length: N``            ``__derivation_length__ = N``
``module A(x), B``                  declares the multi-letter names (``AB`` is ``A`` then ``B``)
``production:`` and the others      the section the next rules belong to
``A(x) < B(y) > C --> D(x+y)``      ``def __rule_k(x, y): return __produce__([("D", (x+y,))])``
``A << B`` / ``A >> B``             new contexts: what the step produced (``>>`` in ``backward()``)
``B(y) :`` + an indented body       ``def __rule_k(y):`` + the body
``produce S`` / ``nproduce S``      ``return __produce__([...])`` / ``__nproduce__([...])``
``maximum depth: N``                ``__max_depth__["decomposition"] = N`` (or interpretation)
``group N:`` / ``endgroup``         the group of the next rules (``useGroup(N)`` selects it)
``consider:`` / ``ignore:``         the context filter
``endlsystem``                      back to plain Python
==================================  ==============================================================

Refused with a :class:`LpyError` naming the construct and its line: ``lpyimport``,
``undeclare``, ``makestring``, ``InLeftContext``/``InRightContext``, ``>>`` with ``>`` or with a
repeated pattern ``x(...)``, ``<`` with ``<<``, brackets in a left context, pattern parameters that
are neither names nor values, and successors over several lines.
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass, field

from ..errors import GrammarError


class LpyError(GrammarError):
    """An ``.lpy`` file Ramure cannot read or run: names the construct and its line."""


#: L-Py's predefined multi-character module names (the turtle's and a few others).
PREDEFINED = frozenset(
    """SetGuide EndGuide SetContour SectionResolution Sweep Frame SetColor IncColor DecColor
    InterpolateColors SetWidth IncWidth DecWidth Sphere Cylinder Box Quad Label Left Right Up Down
    RollL RollR iRollL iRollR TurnAround LineTo OLineTo LineRel OLineRel MoveTo MoveRel Pinpoint
    PinpointRel SetHead EulerAngles Elasticity Tropism StartGC EndGC StartPolygon EndPolygon
    PointPolygon CpfgSurface GetPos GetHead GetLeft GetUp GetFrame TextureScale TextureUScale
    TextureVScale TextureTransformation TextureRotation ScreenProjection Circle Disc Surface
    PglShape CustomGeometry Leaf Fruit Flower None nF""".split()
)
AT_NAMES = (
    "@Gs",
    "@Gc",
    "@Ge",
    "@Gr",
    "@Ts",
    "@Tp",
    "@Dd",
    "@Di",
    "@D",
    "@O",
    "@o",
    "@c",
    "@M",
    "@R",
    "@v",
    "@B",
    "@b",
    "@g",
    "@L",
)
SECTIONS = {
    "production": "production",
    "interpretation": "interpretation",
    "homomorphism": "interpretation",
    "decomposition": "decomposition",
}
_REFUSED = re.compile(r"(?<![\w.])(lpyimport|undeclare|makestring|InLeftContext|InRightContext)\b")
_PRODUCE = re.compile(r"(?<![\w.])(n?produce)\b|-->")
_AXIOM = re.compile(r"^[Aa]xiom\s*:(.*)$")
_LENGTH = re.compile(r"^derivation\s+length\s*:(.*)$")
_SECTION = re.compile(r"^(production|interpretation|homomorphism|decomposition)\s*:\s*(#.*)?$")
_DEPTH = re.compile(r"^maximum\s+depth\s*:(.*)$")
_GROUP = re.compile(r"^group\s+(\d+)\s*:\s*(#.*)?$")
_FILTER = re.compile(r"^(consider|ignore)\s*:(.*)$")
_MODULE = re.compile(r"^(module|declare)\s+(.*)$")


@dataclass
class LpyRule:
    """One rule of the file: where it is, what it matches and the Python function it became."""

    section: str
    group: int
    line: int
    function: str
    pred: list[tuple[str, int | None]]  # (name, arity: None any, -k at least k) of each module
    left: list[tuple[str, int | None]] = field(default_factory=list)
    right: list[tuple[str, int | None]] = field(default_factory=list)
    text: str = ""
    #: (index among the rule's parameters, value) a module's parameter must equal (``M(0)``)
    equal: list[tuple[int, object]] = field(default_factory=list)
    #: the left context is L-Py's new context ``<<``: the modules this step already produced
    new_left: bool = False
    #: the right context is L-Py's new context ``>>``: what a backward step produced on the right
    new_right: bool = False


@dataclass
class Translation:
    """The Python source, the ``.lpy`` line of each of its lines, the rules and the filters."""

    source: str
    origin: list[int]
    rules: list[LpyRule]
    names: set[str]
    filters: dict[str, set[str]]


class _Translator:
    def __init__(self, text: str, filename: str | None) -> None:
        self.lines = text.splitlines()
        self.filename = filename
        self.out: list[str] = []
        self.origin: list[int] = []
        self.rules: list[LpyRule] = []
        self.names = set(PREDEFINED) | set(_declared(text))
        self.filters: dict[str, set[str]] = {}
        self.section: str | None = None
        self.group = 0
        self.open_rule: LpyRule | None = None
        self.body = 0
        self.indent = "    "

    def error(self, message: str, number: int, column: int = 1) -> LpyError:
        source = self.lines[number - 1] if 0 < number <= len(self.lines) else None
        return LpyError(message, number, column, source, self.filename)

    def emit(self, text: str, number: int) -> None:
        self.out.append(text)
        self.origin.append(number)

    def translate(self) -> Translation:
        for number, raw in enumerate(self.lines, start=1):
            self.line(number, raw.expandtabs(8).rstrip())
        self.close_rule(len(self.lines))
        return Translation("\n".join(self.out) + "\n", self.origin, self.rules, self.names, self.filters)

    def line(self, number: int, line: str) -> None:
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            self.emit("", number)
            return
        found = _REFUSED.search(_code_part(line))
        if found:
            raise self.error(f"L-Py's {found.group(1)} is not supported by Ramure", number, found.start() + 1)
        if line[0] in " \t":
            if self.open_rule is None and self.section is not None:
                raise self.error("an indented line in a rules section, outside any rule", number, 1)
            if not self.body:
                self.indent = line[: len(line) - len(line.lstrip())]
            self.body += 1
            self.emit(self.python(line, number), number)
            return
        self.close_rule(number)
        if not self.keyword(number, line) and self.section is not None:
            self.rule(number, line)
        elif self.section is None and not self.keyword_done:
            self.emit(self.python(line, number), number)

    keyword_done = False

    def keyword(self, number: int, line: str) -> bool:
        """Handle a section keyword at column 1; True if the line was one."""
        self.keyword_done = True
        if m := _AXIOM.match(line):
            if not _strip_comment(m.group(1)).strip() and not self.indented_after(number):
                self.emit("__axiom__ = []", number)
            elif not _strip_comment(m.group(1)).strip():  # an axiom made by a body of nproduce calls
                self.emit("def __axiom__():", number)
                self.open_rule = LpyRule("axiom", 0, number, "__axiom__", [])
            else:
                self.emit(f"__axiom__ = {self.modules(m.group(1), number, m.start(1))}", number)
        elif m := _LENGTH.match(line):
            self.emit(f"__derivation_length__ = int({_strip_comment(m.group(1)).strip()})", number)
        elif m := _SECTION.match(line):
            self.section, self.group = SECTIONS[m.group(1)], 0
            self.emit("", number)
        elif m := _DEPTH.match(line):
            where = self.section if self.section in ("interpretation", "decomposition") else "decomposition"
            self.emit(f"__max_depth__[{where!r}] = int({_strip_comment(m.group(1)).strip()})", number)
        elif m := _GROUP.match(line):
            self.group = int(m.group(1))
            self.emit("", number)
        elif line.startswith("endgroup"):
            self.group = 0
            self.emit("", number)
        elif m := _FILTER.match(line):
            self.filters = {m.group(1): {s for s, _, _ in scan_modules(_strip_comment(m.group(2)), self.names)}}
            self.emit("", number)
        elif _MODULE.match(line):
            self.emit("", number)
        elif line.startswith("endlsystem"):
            self.section = None
            self.emit("", number)
        else:
            self.keyword_done = False
        return self.keyword_done

    def indented_after(self, number: int) -> bool:
        """Whether the next line with code after line ``number`` is indented (L-Py's body test)."""
        for line in self.lines[number:]:
            if line.strip() and not line.strip().startswith("#"):
                return line[0] in " \t"
        return False

    def close_rule(self, number: int) -> None:
        if self.open_rule is not None and not self.body:
            self.emit("    pass", number)
        if self.open_rule is not None and self.open_rule.section == "axiom":
            self.emit(f"{self.indent}return __produce__([])", number)
            self.emit("__axiom__ = __axiom__()", number)
        self.open_rule, self.body, self.indent = None, 0, "    "

    def rule(self, number: int, line: str) -> None:
        code = _strip_comment(line)
        arrow, colon = _top_level(code, "-->"), _top_level(code, ":")
        if arrow < 0 and colon < 0:
            raise self.error("a rule needs ':' or '-->' after its predecessor", number, len(line) + 1)
        end = arrow if arrow >= 0 and (colon < 0 or arrow < colon) else colon
        rule = self.header(code[:end], number)
        rule.text = code.strip()
        self.rules.append(rule)
        formals = ", ".join(self.formals)
        self.emit(f"def {rule.function}({formals}):", number)
        self.open_rule = rule
        rest = code[end + (3 if end == arrow else 1) :]
        if rest.strip().startswith("@static"):  # L-Py's hint that the rule gives the same result
            rest = rest.replace("@static", "", 1)
        if end == arrow:
            self.emit("    return __produce__(" + self.modules(rest, number, end + 3) + ")", number)
            self.body = 1
        elif rest.strip():
            self.emit("    " + self.python(rest.strip(), number), number)
            self.body = 1

    def header(self, head: str, number: int) -> LpyRule:
        left, right, new, new_right = "", "", False, False
        if ">>" in head:
            head, right, new_right = *head.split(">>", 1), True
            if ">" in head or re.search(r"\bx\s*\(", right):
                raise self.error("'>>' with '>' or a repeated pattern x(...) is not supported by Ramure", number, 1)
        if "<<" in head:
            left, head, new = *head.split("<<", 1), True
            if "<" in left:
                raise self.error("a rule with both '<' and '<<' is not supported by Ramure", number, 1)
        elif "<" in head:
            left, head = head.split("<", 1)
        if ">" in head and not new_right:
            head, right = head.split(">", 1)
        self.formals: list[str] = []
        self.equal: list[tuple[int, object]] = []
        lefts, preds, rights = (self.pattern(p, number) for p in (left, head, right))
        if not preds:
            raise self.error("a rule without a predecessor", number, 1)
        if any(name in "[]" for name, _ in lefts):
            raise self.error("a bracket in a rule's left context is not supported by Ramure", number, 1)
        if any(f.startswith("*") for f in self.formals[:-1]):
            raise self.error("'*args' is supported in the last parameter of a rule only", number, 1)
        name = f"__rule_{len(self.rules)}"
        rule = LpyRule(self.section or "production", self.group, number, name, preds, lefts, rights, equal=self.equal)
        rule.new_left, rule.new_right = new, new_right
        return rule

    def pattern(self, text: str, number: int) -> list[tuple[str, int | None]]:
        out: list[tuple[str, int | None]] = []
        for name, args, column in scan_modules(text, self.names):
            if args is None:
                out.append((name, None))
                continue
            formals = [a.strip() for a in _split_args(args) if a.strip()]
            for k, f in enumerate(formals):
                if re.fullmatch(r"\*?[A-Za-z_]\w*", f):
                    continue
                try:
                    value = ast.literal_eval(f)
                except (ValueError, SyntaxError):
                    raise self.error(f"a pattern's parameter must be a name or a value, not {f!r}", number, column + 1) from None
                self.equal.append((len(self.formals) + k, value))
                formals[k] = f"__value_{len(self.formals) + k}"
            self.formals.extend(formals)
            star = bool(formals) and formals[-1].startswith("*")
            out.append((name, -len(formals) if star else len(formals)))
        return out

    def python(self, line: str, number: int) -> str:
        """A Python line with ``produce``/``nproduce``/``-->`` successors translated."""
        code = _code_part(line)
        m = _PRODUCE.search(code)
        if m is None:
            return line
        head, rest = line[: m.start()], line[m.end() :]
        if m.group(0) == "-->" or m.group(1) == "produce":
            call = "return __produce__("
        else:
            call = "__nproduce__("
        lstripped = rest.lstrip()
        if lstripped.startswith("("):
            offset = len(rest) - len(lstripped)
            close = _matching(lstripped, 0)
            if close < 0:
                raise self.error("a successor over several lines is not supported by Ramure", number, m.end() + 1)
            succ, after = lstripped[1:close], lstripped[close + 1 :]
            column = m.end() + offset + 1
            return head + call + self.modules(succ, number, column) + ")" + self.python(after, number)
        return head + call + self.modules(_strip_comment(rest), number, m.end()) + ")"

    def modules(self, text: str, number: int, column: int) -> str:
        """A successor as a Python list of ``(name, (args,))`` tuples."""
        items = []
        for name, args, _ in scan_modules(text, self.names, number, self, column):
            items.append(f"({name!r}, ({args},))" if args and args.strip() else f"({name!r}, ())")
        return "[" + ", ".join(items) + "]"


def _declared(text: str) -> list[str]:
    """Names of ``module`` declarations, and the words of rule predecessors (L-Py declares them)."""
    names, in_rules = [], False
    for line in text.splitlines():
        m = _MODULE.match(line)
        if m:
            decl = _strip_comment(m.group(2)).split(":")[0]
            names += re.findall(r"([A-Za-z_]\w*)\s*(?:\([^)]*\))?", _drop_parens(decl))
        elif _SECTION.match(line):
            in_rules = True
        elif line.startswith("endlsystem"):
            in_rules = False
        elif in_rules and line[:1].isalpha() and not _keyword_line(line):
            code = _strip_comment(line)
            ends = [e for e in (_top_level(code, "-->"), _top_level(code, ":")) if e >= 0]
            head = _drop_parens(code[: min(ends)]) if ends else ""
            names += [w for w in re.findall(r"(?<![~@?\w])[A-Za-z_]\w+", head)]
    return names


def _keyword_line(line: str) -> bool:
    return any(p.match(line) for p in (_AXIOM, _LENGTH, _SECTION, _DEPTH, _GROUP, _FILTER, _MODULE)) or line.startswith(
        ("endgroup", "endlsystem")
    )


def _drop_parens(text: str) -> str:
    return re.sub(r"\([^)]*\)", "", text)


def scan_modules(
    text: str, names: set[str] | frozenset[str], number: int = 0, where: _Translator | None = None, column: int = 0
) -> list[tuple[str, str | None, int]]:
    """The modules of ``text``: ``(name, argument text or None, offset)`` each.

    A name is the longest declared or predefined name that starts here, else one character
    (``@`` and ``?`` names take their letters, ``~`` a whole word).

    >>> [m[:2] for m in scan_modules("FA(1)[+(a, b)Internode]~leaf(2)@Gs", {"Internode"})]
    [('F', None), ('A', '1'), ('[', None), ('+', 'a, b'), ('Internode', None), (']', None), ('~leaf', '2'), ('@Gs', None)]
    """
    out: list[tuple[str, str | None, int]] = []
    i, size = 0, len(text)
    while i < size:
        c = text[i]
        if c.isspace():
            i += 1
            continue
        start = i
        i = _name_end(text, i, names)
        name = text[start:i]
        args = None
        if i < size and text[i] == "(":
            close = _matching(text, i)
            if close < 0:
                if where is not None:
                    raise where.error("an unclosed '(' in a successor", number, column + i + 1)
                raise LpyError(f"an unclosed '(' after {name!r}")
            args, i = text[i + 1 : close], close + 1
        out.append((name, args, start))
    return out


def _name_end(text: str, i: int, names: set[str] | frozenset[str]) -> int:
    c = text[i]
    if c == "@":
        for at in AT_NAMES:
            if text.startswith(at, i):
                return i + len(at)
        return min(i + 2, len(text))
    if c in "~?" and i + 1 < len(text):
        m = re.compile(r"[A-Za-z_]\w*").match(text, i + 1)
        if m:
            return m.end() if c == "~" else i + 2
    if c.isalpha() or c == "_":
        m = re.compile(r"[A-Za-z_]\w*").match(text, i)
        word = m.group(0) if m else c
        for k in range(len(word), 1, -1):
            if word[:k] in names:
                return i + k
    return i + 1


def _matching(text: str, open_at: int) -> int:
    depth, quote = 0, ""
    for j in range(open_at, len(text)):
        c = text[j]
        if quote:
            quote = "" if c == quote else quote
        elif c in "'\"":
            quote = c
        elif c in "([{":
            depth += 1
        elif c in ")]}":
            depth -= 1
            if depth == 0:
                return j
    return -1


def _split_args(text: str) -> list[str]:
    parts, depth, last = [], 0, 0
    for j, c in enumerate(text):
        if c in "([{":
            depth += 1
        elif c in ")]}":
            depth -= 1
        elif c == "," and depth == 0:
            parts.append(text[last:j])
            last = j + 1
    return parts + [text[last:]]


def _top_level(text: str, token: str) -> int:
    depth, quote = 0, ""
    for j, c in enumerate(text):
        if quote:
            quote = "" if c == quote else quote
        elif c in "'\"":
            quote = c
        elif c in "([{":
            depth += 1
        elif c in ")]}":
            depth -= 1
        elif depth == 0 and text.startswith(token, j):
            return j
    return -1


def _code_part(line: str) -> str:
    """``line`` with its strings blanked and its comment dropped (for keyword searches)."""
    out, quote = [], ""
    for c in line:
        if quote:
            out.append(" ")
            quote = "" if c == quote else quote
        elif c in "'\"":
            quote = c
            out.append(" ")
        elif c == "#":
            break
        else:
            out.append(c)
    return "".join(out)


def _strip_comment(text: str) -> str:
    return text[: len(_code_part(text))]


def translate(text: str, filename: str | None = None) -> Translation:
    """Translate ``.lpy`` text into Python (see the module's table)."""
    return _Translator(text, filename).translate()
