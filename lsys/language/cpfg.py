"""Read L-studio/cpfg ``.l`` files (the common subset) as Ramure grammars.

A ``.l`` file is translated line by line into the ``.lsys`` language (one
output line per input line, so line numbers never move; column shifts are
mapped back, so every error points at the ``.l`` file's own line and column)
and then parsed by :func:`ramure.lsys.language.grammar.parse_grammar`.

===============================  ========================================================
cpfg                             Ramure
===============================  ========================================================
``#define N 5``                  ``#define N 5`` (a constant)
``#define f(x) (x*2)``           ``#function f(x) = (x*2)``
``Lsystem: 1``                   (a label; a second ``Lsystem:`` is refused)
``derivation length: 5``         ``n: 5``
``axiom: A``                     ``w: A``
``ignore: +-F`` / ``consider:``  ``#ignore +-F`` / ``#consider``
``seed: 3``                      ignored (Ramure takes the seed when deriving)
``A < B > C : x>1 --> D``        the same rule (``-->`` and ``->`` both)
``A --> B : 0.3``                a stochastic weight
``homomorphism``                 ``interpretation:``
``decomposition``                ``decomposition:``
``maximum depth: 3``             ``#interpretation_depth 3`` / ``#decomposition_depth 3``
``warnings`` / ``no warnings``   ignored (after ``homomorphism``/``decomposition``)
``ran(x)`` / ``nran(m, s)``      ``uniform(0, x)`` / ``normal(m, s)``
``endlsystem``                   end of the grammar
``XF(x) --> ...``                a predecessor of several modules (``#dialect cpfg``)
``@Gt(a, b)``                    a generalised cylinder's tangent coefficients (drawn)
``@Tx(id)``                      a texture: read, not drawn (``ramure check`` notes it)
``?E(v, i)`` with honda81        answered by Ramure's built-in honda81 (the ``.e`` file
                                 names it; :mod:`ramure.lsys.language.cpfg_environment`)
``func(id, x)``                  the view file's ``.func`` functions
                                 (:mod:`ramure.lsys.language.cpfg_functions`)
===============================  ========================================================

**Module names.**  cpfg's lexer reads a module name as *one character*
(``lsys_input.l``: a symbol is any single character but ``< > : *`` and
blanks; ``@``, ``?`` and ``~`` take the next character as part of the
command), so ``spikef`` is the six modules ``s p i k e f`` and ``XF(x)`` is
``X`` then ``F(x)``: the parameters belong to the character before ``(``.
Ramure's ``.lsys`` language reads undeclared names the same way.  A strict
predecessor may be several modules (cpfg's ``Strictpred : FormalModules``):
it matches a run of modules with the same symbols and numbers of
parameters, nothing skipped, and the run is rewritten as a whole (see
:meth:`ramure.lsys.LSystem.rewrite`).  A module written with another number
of parameters than a rule's predecessor is not rewritten by that rule, as
in cpfg (``.lsys`` refuses it).  Both come with ``#dialect cpfg``, which
the translation ends with.

Refused with a :class:`~ramure.errors.GrammarError` naming the construct
(line, column, caret): ``#include`` (view, surface and other files) and the
other preprocessor commands; a second ``Lsystem:`` (sub-L-systems); ``?E`` modules
of another environment program than honda81 (named, from the ``.e`` file) and
sub-L-system calls ``?(...)``;
``@`` modules Ramure does not draw (e.g. ``@Gs`` generalised cylinders);
C blocks ``{ ... }`` in a rule's condition; cpfg's ``start:``/``end:``
statement blocks and ``define:`` blocks.  Trigonometry is in degrees, as in
Ramure.

>>> g = parse_cpfg("Lsystem: 1\\nderivation length: 2\\naxiom: A\\nA --> F[+A]A\\nendlsystem\\n")
>>> g.n, [str(r) for r in g.rules]
(2, ['A --> F[+A]A'])
"""

from __future__ import annotations

import pathlib
import re
from dataclasses import dataclass, field

from ..errors import GrammarError
from .cpfg_environment import BUILT_IN
from .grammar import CONTINUATION, Grammar, parse_grammar, strip_comments

#: Suffixes read as cpfg files by :meth:`ramure.lsys.LSystem.from_file`.
CPFG_SUFFIXES = (".l",)
_QUERY = {
    "P": "the turtle position query ?P",
    "H": "the turtle heading query ?H",
    "L": "the turtle left-vector query ?L",
    "U": "the turtle up-vector query ?U",
    "E": "the communication module ?E",
}
_AT_MEANING = {
    "Gs": "generalised cylinders",
    "Gc": "generalised cylinders",
    "Ge": "generalised cylinders",
    "Gr": "generalised cylinders",
    "o": "circles",
    "c": "circles",
    "v": "roll to vertical",
    "M": "absolute moves",
    "R": "absolute headings",
    "Tf": "texture",
    "Tx": "texture",
    "D": "scale factor",
    "b": "blackboard",
    "Ca": "contours",
}
_FUNCTIONS = (
    (re.compile(r"\bnran\s*\("), "normal("),
    (re.compile(r"\bran\s*\("), "uniform(0,"),
    (re.compile(r"\bfabs\s*\("), "abs("),
)


@dataclass
class _Out:
    """One translated line and the edits that made it (to map columns back)."""

    text: str
    edits: list = field(default_factory=list)  # (original column 0-based, original length, new length)

    def original_column(self, column):
        """The 1-based column in the ``.l`` line of a 1-based column of the translated line."""
        t, shift = column - 1, 0
        for at, old, new in self.edits:
            if t < at + shift:
                break
            if t < at + shift + new:
                return at + 1  # inside replaced text: its start in the .l line
            shift += new - old
        return t - shift + 1


class _Translator:
    def __init__(self, filename=None, functions=None, environment=None) -> None:
        self.filename = filename
        self.environment = environment or {}  # the .e file's program (lsys.language.cpfg_environment)
        self.functions = functions or {}  # func(id, x) of the view file (lsys.language.cpfg_functions)
        self.section = "production"
        self.lsystems = 0
        self.ended = False
        self.in_rules = False  # whether the .lsys text is inside a rules section here
        self.open_successor = False  # whether the last line was a rule or axiom a next line may continue
        self.block: tuple | None = None  # the Start:/End:/... block being read: (name, line, column, lines)
        self.blocks: list = []
        self.head: tuple | None = None  # a production with blocks being read: (first line, lines)
        self.head_lines: list[str] = []
        self.rule_blocks: dict = {}  # output line -> ((text, line, column) or None) * 2

    def error(self, message, number, column, original):
        return GrammarError(message, number, column, original, filename=self.filename)

    def translate(self, text):
        text = text.replace("\r\n", "\n").replace("\r", "\n")
        # cpfg runs its files through the C preprocessor: '//' and '/* */' are comments
        # everywhere, and the output is built from the comment-free text
        stripped = strip_c_comments(text).split("\n")
        stripped = _join_define_continuations(stripped)
        outs = []
        for number, s in enumerate(stripped, 1):
            if self.block is not None or _BLOCK.match(s):
                outs.append(self.block_line(number, s))
                continue
            if self.head is not None or self.starts_block_rule(s):
                outs.append(self.block_rule_line(number, s))
                continue
            slash = _line_continuation(s)
            if slash is not None:  # a rule or axiom going on over the next line: Ramure's '...'
                s = s[:slash] + " " * (len(s) - slash)
            if self.continues(s):
                out = self.modules(number, s, s, 0, len(s), _Out(s))
                self.mark_continued(outs)
            else:
                out = self.line(number, s, s)
                self.open_successor = out.text.lstrip().startswith(("p:", "w:")) or (self.in_rules and "->" in out.text)
            if slash is not None:
                out.text += " " + CONTINUATION
                self.open_successor = True  # the mark is written: the next line continues it
            outs.append(out)
        if self.block is not None:
            name, number, _, _ = self.block
            raise self.error(f"the '{name}:' block's '{{' is never closed", number, 1, text.split("\n")[number - 1])
        return outs

    def block_line(self, number, s):
        """A line of a Start:/End:/StartEach:/EndEach:/Define: block: kept for :meth:`programs`."""
        if self.block is None:
            m = _BLOCK.match(s)
            assert m is not None  # translate() reads a block line only where _BLOCK matches
            self.block = (m.group(1), number, m.end() + 1, [s[m.end() :]])
        else:
            self.block[3].append(s)
        body = "\n".join(self.block[3])
        if "{" in body and _braces_closed(body):
            self.blocks.append(self.block)
            self.block = None
        self.open_successor = False
        return _Out(" " * len(s))

    def parsed_rule_blocks(self, lines):
        """Output line -> (pre, post) programs of the productions with blocks."""
        from .cstatements import parse_program

        out = {}
        for number, pair in self.rule_blocks.items():
            programs: list = []
            for block in pair:
                if block is None:
                    programs.append(None)
                    continue
                text, line, column = block
                try:
                    programs.append(parse_program(text, line, column, lines, self.functions))
                except GrammarError as err:
                    err.filename = self.filename
                    raise
            out[number] = tuple(programs)
        return out

    def starts_block_rule(self, s):
        """Whether ``s`` starts a production with a statement block before its arrow."""
        body = s.strip()
        if not body or body.startswith("#") or self.ended or not self.in_rules and self.section != "production":
            return False
        colon, brace = _find_depth0(s, ":"), _find_depth0(s, "{")
        arrow = s.find("-->") if "-->" in s else s.find("->")
        if colon < 0 or (arrow >= 0 and (brace < colon or arrow < brace)):
            return False  # no head going on over lines, no block before the arrow
        word = s[:colon].strip().lower()
        keywords = ("lsystem", "derivation length", "axiom", "ignore", "consider", "seed", "maximum depth")
        return word not in (*keywords, "homomorphism", "decomposition")  # 'homomorphism: no warnings' too

    def block_rule_line(self, number, s):
        """A line of ``pred : {pre} condition {post} --> successor``: the rule is written on the
        line of its arrow, as ``pred : condition -> successor``, its blocks kept aside."""
        if self.head is None:
            self.head = (number, [])
        self.head[1].append(s)
        text = "\n".join(self.head[1])
        colon = _find_depth0(text, ":")
        arrow = _arrow_after_blocks(text, colon)
        if arrow < 0:
            return _Out(" " * len(s))
        first, self.head_lines, self.head = self.head[0], self.head[1], None
        parts = _split_blocks(text, colon + 1, arrow)
        if parts is None:
            line, column = _position(text, text.index("{", colon), first)
            raise self.error(
                "cannot read the blocks of this production: {pre} condition {post}", line, column, self.head_lines[line - first]
            )
        pre, condition, post = parts
        width = 3 if text.startswith("-->", arrow) else 2
        line = f"{text[:colon].strip()} : {condition.strip() or '*'} --> {text[arrow + width :]}"
        if pre is not None or post is not None:
            self.rule_blocks[number] = tuple(None if b is None else (b[0], *_position(text, b[1], first)) for b in (pre, post))
        out = self.rule(number, line, line, 0)
        self.open_successor = True
        return out

    def programs(self, lines):
        """The blocks parsed (:mod:`ramure.lsys.language.cstatements`): cpfg's name (lower case) -> program."""
        from .cstatements import parse_program

        out = {}
        if self.head is not None:
            raise self.error(
                "this cpfg line is not supported: it reads as a production's predecessor and condition, "
                "but no '-->' follows (or it is a keyword Ramure does not know)",
                self.head[0],
                1,
                lines[self.head[0] - 1],
            )
        for name, number, column, pieces in self.blocks:
            key = name.lower()
            if key in out:
                raise self.error(f"a second '{name}:' block", number, 1, lines[number - 1])
            try:
                out[key] = parse_program("\n".join(pieces), number, column, lines, self.functions)
            except GrammarError as err:
                err.filename = self.filename
                raise
        return out

    def continues(self, s):
        """Whether line ``s`` goes on with the successor (or axiom) of the line before: cpfg
        reads a production until the next production, keyword or directive."""
        body = s.strip()
        if not body or not self.open_successor or self.ended:
            return False
        if body.startswith("#") or "->" in body or re.match(r"[A-Za-z][A-Za-z ]*?\s*:", body):
            return False
        return not re.fullmatch(r"(homomorphism|decomposition|endlsystem)(\s*:)?(\s+(no\s+)?warnings)?", body, re.I)

    def mark_continued(self, outs):
        """End the last non-blank output line with Ramure's continuation mark."""
        for out in reversed(outs):
            if out.text.strip():
                if not out.text.rstrip().endswith(CONTINUATION):
                    out.text = out.text.rstrip() + " " + CONTINUATION
                return

    def line(self, number, text, original):
        body = text.strip()
        start = len(text) - len(text.lstrip())
        if not body:
            return _Out(original)
        if self.ended:
            if re.match(r"lsystem\s*:", body, re.I):
                raise self.error(
                    "a second L-system after 'endlsystem' (sub-L-systems) is not supported", number, start + 1, original
                )
            return _Out(" " * len(original))  # after endlsystem cpfg reads no more
        if body.startswith("#"):
            self.in_rules = False  # a directive ends a rules section in .lsys
            return self.preprocessor(number, text, original, start)
        keyword = re.match(r"([A-Za-z][A-Za-z ]*?)\s*:", body)
        word = keyword.group(1).lower() if keyword else body.lower()
        handler = {
            "lsystem": self.label,
            "derivation length": self.count,
            "axiom": self.axiom,
            "ignore": self.context_filter,
            "consider": self.context_filter,
            "seed": self.blank,
            "maximum depth": self.depth,
        }.get(word if keyword else "")
        if handler is not None and keyword is not None:  # a handler is found for a keyword only
            self.in_rules = self.in_rules and handler == self.depth  # other keyword lines end the rules
            return handler(number, text, original, start, keyword.end() + start)
        if re.fullmatch(r"(homomorphism|decomposition)(\s*:)?(\s+(no\s+)?warnings)?", body, re.I):
            self.section = "interpretation" if body.lower().startswith("homo") else "decomposition"
            self.in_rules = True
            return _Out(f"{' ' * start}{self.section}:", [(start, len(original) - start, len(self.section) + 1)])
        if re.fullmatch(r"(no\s+)?warnings", body, re.I):
            return _Out(" " * len(original))
        if body.lower() == "endlsystem":
            self.ended = True
            return _Out(" " * len(original))
        if "->" in text:
            return self.rule(number, text, original, start)
        raise self.error(
            "this cpfg line is not supported: expected a keyword (derivation length:, axiom:, "
            "ignore:, ...) or a production with '-->'",
            number,
            start + 1,
            original,
        )

    # -- keyword lines ------------------------------------------------------
    def preprocessor(self, number, text, original, start):
        m = re.match(r"#\s*(\w+)", text[start:])
        name = m.group(1) if m else ""
        if name == "define":
            macro = re.match(r"#\s*define\s+([A-Za-z_]\w*)\(([^)]*)\)\s*(.*)$", text[start:])
            if macro:  # a function-like macro: a Ramure user function
                head = f"#function {macro.group(1)}({macro.group(2)}) = "
                at = start + macro.start(3)
                out = _Out(" " * start + head + original[at:], [(start, at - start, len(head))])
                return self.rename(text, at, len(text), out)
            return self.rename(text, start, len(text), _Out(original))
        if name == "include":
            raise self.error(
                "#include in a cpfg file is not supported (view, surface and other files are "
                "not read): copy what you need into the .l file",
                number,
                start + 1,
                original,
            )
        raise self.error(f"the cpfg preprocessor command '#{name}' is not supported (only #define)", number, start + 1, original)

    def label(self, number, text, original, start, after):
        self.lsystems += 1
        if self.lsystems > 1:
            raise self.error("a second 'Lsystem:' (sub-L-systems) is not supported", number, start + 1, original)
        return _Out(" " * len(original))

    def blank(self, number, text, original, start, after):
        return _Out(" " * len(original))

    def count(self, number, text, original, start, after):
        return self.keyword(original, start, after, "n:")

    def axiom(self, number, text, original, start, after):
        out = self.keyword(original, start, after, "w:")
        return self.modules(number, text, original, after, len(text), out)

    def context_filter(self, number, text, original, start, after):
        name = text[start:after].split(":")[0].strip().lower()
        return self.keyword(original, start, after, f"#{name}")

    def depth(self, number, text, original, start, after):
        if self.section == "production":
            raise self.error("'maximum depth:' belongs after 'homomorphism' or 'decomposition'", number, start + 1, original)
        return self.keyword(original, start, after, f"#{self.section}_depth ")

    @staticmethod
    def keyword(original, start, after, new):
        return _Out(original[:start] + new + original[after:], [(start, after - start, len(new))])

    # -- rules and module strings --------------------------------------------
    def rule(self, number, text, original, start):
        arrow = text.find("-->")
        width = 3
        if arrow < 0:
            arrow, width = text.find("->"), 2
        brace = text.find("{", 0, arrow)
        if brace >= 0:
            raise self.error("C blocks { ... } in a production's condition are not supported", number, brace + 1, original)
        out = _Out(original)
        if width == 3:
            out.text = original[:arrow] + " ->" + original[arrow + 3 :]
        if self.section == "production" and not self.in_rules:  # productions start (again) here
            out.text, out.edits = "p: " + out.text, [(0, 0, 3)]
        self.in_rules = True
        end = _successor_end(text, arrow + width)
        out = self.modules(number, text, original, arrow + width, end, out)
        return self.rename(text, 0, arrow, out)

    def modules(self, number, text, original, start, end, out):
        """Check a module string for unsupported modules; rename cpfg's random functions."""
        depth, i = 0, start
        while i < end:
            c = text[i]
            if c == "(":
                depth += 1
            elif c == ")":
                depth -= 1
            elif depth == 0 and c == "?" and text[i + 1 : i + 2] not in ("P", "H", "L", "U"):
                nxt = text[i + 1 : i + 2]
                if nxt == "E" and self.environment.get("program") in BUILT_IN:
                    i += 1
                    continue
                what = _QUERY.get(nxt, "the sub-L-system call ?(...)" if nxt == "(" else "the query module ?")
                if nxt == "E":
                    what += self.missing_environment()
                raise self.error(f"{what} is not supported", number, i + 1, original)
            elif depth == 0 and c == "@":
                self.at_module(number, text, original, i)
            i += 1
        return self.rename(text, start, end, out)

    @staticmethod
    def rename(text, start, end, out):
        """cpfg's ran/nran/fabs in text[start:end] written as Ramure's functions."""
        for pattern, new in _FUNCTIONS:
            for m in reversed(list(pattern.finditer(text, start, end))):
                at = _shifted(out, m.start())
                out.text = out.text[:at] + new + out.text[at + len(m.group()) :]
                out.edits.append((m.start(), len(m.group()), len(new)))
        out.edits.sort()
        return out

    def missing_environment(self):
        """Why a ``?E`` cannot be answered: the program the ``.e`` file names, or no ``.e`` file."""
        program, where = self.environment.get("program"), self.environment.get("file")
        if program:
            return (
                f" talks to the environment program {program} (named in {where}), which Ramure does not run "
                f"(Ramure answers {', '.join(BUILT_IN)} itself), so it"
            )
        return (
            " talks to an environment program (named in cpfg's -e file, here none beside the .l file: "
            f"Ramure answers {', '.join(BUILT_IN)} itself), so it"
        )

    def at_module(self, number, text, original, i):
        m = re.match(r"@([A-Za-z#]+)", text[i:])
        name = "@" + (m.group(1) if m else "")
        from ..interpretation.turtle import CPFG_CODES, SYMBOL_CODES  # the rich walk's tables
        from ..interpretation.turtle import NOT_DRAWN, SYMBOL_ACTIONS

        if any(text.startswith(k, i) and not text[i + len(k) : i + len(k) + 1].isalpha() for k in NOT_DRAWN):
            return  # read, not drawn: 'ramure check' notes it
        drawn = [*SYMBOL_ACTIONS, *SYMBOL_CODES, *CPFG_CODES]
        known = sorted({s for s in drawn if s.startswith("@")}, key=lambda s: (-len(s), s))  # what the turtle draws
        if any(name.startswith(k) and not name[len(k) : len(k) + 1].isalpha() for k in known) or any(
            text.startswith(k, i) for k in known
        ):
            return
        meaning = next((v for k, v in _AT_MEANING.items() if name[1:].startswith(k)), None)
        raise self.error(
            f"the cpfg module {name}{f' ({meaning})' if meaning else ''} is not supported"
            + (f"; Ramure draws {', '.join(known)}" if known else ""),
            number,
            i + 1,
            original,
        )


def strip_c_comments(text: str) -> str:
    """Blank out C and C++ comments keeping every other column and newline in place: ``/*`` to ``*/``,
    and ``//`` to the end of the line where it starts a line or follows a space and is followed
    by a space or a letter (``F/////S`` rolls five times, as in ABOP's files); text inside
    double quotes is kept.

    >>> strip_c_comments('A --> F//F  /* a */ "//" // note')
    'A --> F//F          "//"        '
    """
    out, i, n = list(text), 0, len(text)
    while i < n:
        c = text[i]
        if c == '"':
            j = text.find('"', i + 1)
            i = n if j < 0 else j + 1
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            end = n if j < 0 else j + 2
            out[i:end] = [ch if ch == "\n" else " " for ch in text[i:end]]
            i = end
        elif text.startswith("//", i) and _comment_starts(text, i):
            j = text.find("\n", i)
            end = n if j < 0 else j
            out[i:end] = " " * (end - i)
            i = end
        else:
            i += 1
    return "".join(out)


def _find_depth0(text, char):
    """The first ``char`` outside parentheses, else -1."""
    depth = 0
    for i, c in enumerate(text):
        if c == char and depth == 0:
            return i
        depth += (c == "(") - (c == ")")
    return -1


def _arrow_after_blocks(text, start):
    """The ``-->`` (or ``->``) after the blocks of a production, else -1."""
    depth = 0
    for i in range(start, len(text)):
        c = text[i]
        depth += (c in "{(") - (c in "})")
        if depth == 0 and text.startswith("->", i):
            return i
        if depth == 0 and text.startswith("-->", i):
            return i
    return -1


def _split_blocks(text, start, end):
    """``{pre} condition {post}`` in text[start:end]: ((block text, offset) or None, condition,
    (block text, offset) or None), else None."""
    pieces: list = [None, None]
    condition: list[str] = []
    at = start
    while at < end:
        c = text[at]
        if c == "{":
            depth, j = 0, at
            while j < end:
                depth += (text[j] == "{") - (text[j] == "}")
                if depth == 0:
                    break
                j += 1
            if depth != 0:
                return None
            slot = 0 if not "".join(condition).strip() and pieces[0] is None else 1
            if pieces[slot] is not None:
                return None
            pieces[slot] = (text[at : j + 1], at)
            at = j + 1
        else:
            if pieces[1] is not None and not c.isspace():
                return None
            condition.append(c)
            at += 1
    return pieces[0], "".join(condition).replace("\n", " "), pieces[1]


def _position(text, offset, first_line):
    """(line, column) in the file of ``offset`` in ``text`` that starts at ``first_line``."""
    before = text[:offset]
    return first_line + before.count("\n"), offset - (before.rfind("\n") + 1) + 1


_BLOCK = re.compile(r"\s*(start|end|starteach|endeach|define)\s*:", re.I)


def _braces_closed(text):
    depth = 0
    for c in text:
        depth += (c == "{") - (c == "}")
        if depth == 0 and c == "}":
            return True
    return False


def _comment_starts(text, i):
    before = text[i - 1] if i else "\n"
    after = text[i + 2] if i + 2 < len(text) else "\n"
    return before.isspace() and (after.isspace() or after.isalpha())


def _join_define_continuations(lines):
    """A ``#define`` continued with ``\\`` is joined into its first line (the lines it took blanked)."""
    lines = list(lines)
    for k in range(len(lines)):
        if not lines[k].lstrip().startswith("#"):
            continue
        following = k + 1
        while (cut := _line_continuation(lines[k])) is not None and following < len(lines):
            lines[k] = lines[k][:cut] + " " + lines[following].strip()
            lines[following] = ""
            following += 1
    return lines


def _line_continuation(line):
    """The column of a final ``\\`` (the line goes on over the next one), else None."""
    body = line.rstrip()
    return len(body) - 1 if body.endswith("\\") else None


def _successor_end(text, start):
    """Where a successor ends: before a top-level ': weight' suffix, else at the end of the line."""
    depth = 0
    for j in range(start, len(text)):
        depth += (text[j] == "(") - (text[j] == ")")
        if text[j] == ":" and depth == 0:
            return j
    return len(text)


def _shifted(out, column):
    """The 0-based position in ``out.text`` of the 0-based original ``column`` (edits before it applied)."""
    return column + sum(new - old for at, old, new in out.edits if at < column)


def translate(text: str, filename: str | None = None) -> str:
    """The Ramure grammar text of a cpfg file, one line per line of the cpfg file.

    >>> print(translate("derivation length: 3\\naxiom: A\\nA --> AB").strip())
    n: 3
    w: A
    p: A  -> AB
    """
    return "\n".join(out.text for out in _Translator(filename).translate(text))


_CPFG_LINE = re.compile(r"^[ \t]*derivation\s+length\s*:", re.I | re.M)


def is_cpfg(text: str, filename: str | None = None) -> bool:
    """Whether to read ``text`` as cpfg: its file name ends with ``.l``, or it has a
    ``derivation length:`` line (which the ``.lsys`` language never accepts).

    >>> is_cpfg("n: 2\\nw: A"), is_cpfg("derivation length: 2\\naxiom: A"), is_cpfg("", "tree.l")
    (False, True, True)
    """
    if filename is not None and str(filename).lower().endswith(CPFG_SUFFIXES):
        return True
    return _CPFG_LINE.search(text) is not None and _CPFG_LINE.search(strip_comments(text)) is not None


def to_lsys(text: str, filename: str | None = None, angle: float | None = None) -> str:
    """A ``.lsys`` file's text for a cpfg ``.l`` file: a header comment, ``#angle`` if given, the rules.

    cpfg keeps the turn angle in the view file, which is not read: pass
    ``angle`` (degrees) to write ``#angle``; otherwise Ramure's default (90) applies.
    Errors are those of :func:`parse_cpfg` (``.l`` lines and columns).
    """
    parse_cpfg(text, filename)  # refuse what cannot be translated, at the .l file's line and column
    calls = re.search(r"\bfunc\s*\(", strip_c_comments(text))
    if calls:
        line = text[: calls.start()].count("\n") + 1
        column = calls.start() - (text.rfind("\n", 0, calls.start()) + 1) + 1
        raise GrammarError(
            "func(id, x) reads the view file's function files, which a .lsys file cannot name: open the .l file itself",
            line,
            column,
            text.split("\n")[line - 1],
            filename=filename,
        )
    name = pathlib.Path(filename).name if filename else "a cpfg file"
    head = [f"/* Imported from {name} by 'ramure import'. The cpfg view file (angle, widths) is not read. */"]
    if angle is not None:
        head.append(f"#angle {angle:g}")
    head.append("#dialect cpfg")  # cpfg's matching and turtle (lsys.language.grammar)
    body = [line.rstrip() for line in translate(text, filename).split("\n")]
    while body and not body[-1]:
        body.pop()
    return "\n".join(head + body) + "\n"


def parse_cpfg(text: str, filename: str | None = None) -> Grammar:
    """Parse a cpfg ``.l`` file's text; errors name the ``.l`` line and column."""
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    functions, names = _view_functions(text, filename)
    environment = _environment(text, filename)
    translator = _Translator(filename, functions, environment)
    outs = translator.translate(text)
    programs = translator.programs(lines)
    rule_blocks = translator.parsed_rule_blocks(lines)
    every = [*programs.values(), *(b for pair in rule_blocks.values() for b in pair if b is not None)]
    body = "\n".join(out.text for out in outs) + _globals(every, outs) + "\n#dialect cpfg"
    try:
        grammar = parse_grammar(body, filename, functions, names)
    except GrammarError as err:
        raise _in_cpfg_words(err, outs, lines, filename) from None
    grammar.text = text
    grammar.environment = environment if environment.get("program") in BUILT_IN else {}
    grammar.programs = programs  # run by LSystem.derive: Define, Start, StartEach, EndEach, End
    for rule in [*grammar.rules, *grammar.decomposition, *grammar.interpretation]:
        if rule.line in rule_blocks:
            rule.blocks = rule_blocks[rule.line]
    bare = strip_c_comments("\n".join(lines)).split("\n")
    for rule in [*grammar.rules, *grammar.decomposition, *grammar.interpretation]:
        rule.source_line = lines[rule.line - 1]  # derivation errors quote the .l line
        rule.text = bare[rule.line - 1].strip()  # and name the rule as the .l file writes it
    _locate_in_l_file(grammar, outs, lines, filename)
    return grammar


def _environment(text, filename):
    """The ``.e`` file's environment beside ``filename``, read only when the text has ``?E``."""
    if filename is None or "?E" not in strip_c_comments(text):
        return {}
    from .cpfg_environment import read_environment
    from .grammar import confinement_root

    root = confinement_root(filename)
    assert root is not None
    return read_environment(filename, root)


def _view_functions(text, filename):
    """({"func": tables} or {}, {function-set name: id}) of the view file beside ``filename``,
    read only when the text calls ``func`` (:mod:`ramure.lsys.language.cpfg_functions`)."""
    if filename is None or not re.search(r"\bfunc\s*\(", strip_c_comments(text)):
        return {}, {}
    from .cpfg_functions import view_tables
    from .grammar import confinement_root

    root = confinement_root(filename)
    assert root is not None  # a file name gives a folder
    tables, names = view_tables(filename, root)
    return ({"func": tables} if tables is not None else {}), names


def _globals(programs, outs):
    """``#define`` lines (value 0) for the variables the blocks set, so rules can read them."""
    from .cstatements import assigned_names

    defined = {m.group(1) for out in outs for m in [re.match(r"\s*#\s*(?:define|function)\s+(\w+)", out.text)] if m}
    names = sorted(set().union(*(assigned_names(p) for p in programs)) - defined) if programs else []
    return "".join(f"\n#define {name} 0" for name in names)


def _locate_in_l_file(grammar, outs, lines, filename):
    """Point every written module at its ``.l`` line and column (for errors found while deriving)."""
    rules = [*grammar.rules, *grammar.decomposition, *grammar.interpretation]
    written = [*grammar.axiom, *(m for r in rules for m in [*r.left, r.pred, *r.right, *r.successor])]
    for module in written:
        line = module.line
        if line is None or getattr(line, "filename", None) not in (None, filename) or not 1 <= line.number <= len(outs):
            continue
        module.column = outs[line.number - 1].original_column(module.column)
        line.original = lines[line.number - 1]


def _in_cpfg_words(err, outs, lines, filename):
    """The error of the translated text, located in the ``.l`` file and worded in cpfg's keywords."""
    message = err.message
    if message.startswith("unknown function 'func'"):
        message += (
            ": func(id, x) reads the functions a cpfg view file names ('function: f.func' lines), "
            "and no view file beside the .l file (same name with .v) names any"
        )
    for lsys_word, cpfg_word in (("'n: ...'", "'derivation length: ...'"), ("'w: ...'", "'axiom: ...'")):
        message = message.replace(lsys_word, cpfg_word)
    line, column, source = err.line, err.column, err.source_line
    if line is not None and 1 <= line <= len(outs) and err.filename in (None, filename):
        column = outs[line - 1].original_column(column) if column is not None else None
        source = lines[line - 1]
    return type(err)(message, line, column, source, filename=err.filename)
