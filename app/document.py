"""The grammar document: the text a Save writes, with what the user changed written into it.

The explorer keeps the grammar text as typed or read (:attr:`Explorer.text
<ramure.app.model.Explorer.text>`) and, apart from it, the derivation count, the seed
and the constants the user set with sliders, the gallery or a qualifier.
:func:`document_text` writes those into the text: the ``n:`` line, a ``#seed``
directive and the ``#define`` lines, each only where it differs from what the text
says, so an untouched grammar comes back byte for byte.  Reading the result again
gives the plant that was on screen.

>>> text = "#define a2 60   // angle\\nn: 10\\nw: A\\np:\\n A -> FA"
>>> print(text_with_derivation(text, n=12, seed=7, written_n=10, written_seed=0))
#define a2 60   // angle
#seed 7
n: 12
w: A
p:
 A -> FA
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import TYPE_CHECKING

from ramure.errors import RamureError
from ramure.lsys import GrammarError, LSystem

if TYPE_CHECKING:
    from ramure.lsys.regen import Session

_TAIL = r"(\s*(?://.*|/\*.*)?)$"
DEFINE_LINE = re.compile(r"^(\s*#\s*define\s+)([A-Za-z_][A-Za-z_0-9]*)(\s+)(.*?)" + _TAIL)
_COUNT = re.compile(r"^(\s*(?:n|derivation\s+length)\s*:\s*)(.*?)" + _TAIL, re.I)
_SEED = re.compile(r"^(\s*#\s*seed\s+)(.*?)" + _TAIL, re.I)


def format_constant(value: float) -> str:
    """A constant as the grammar text writes it: ``60``, ``0.9``, ``1e-05`` (10 significant digits)."""
    return f"{float(value):.10g}"


def text_with_constants(text: str, constants: Mapping[str, float], written: Mapping[str, float]) -> str:
    r"""``text`` with each ``#define`` whose value differs from ``written`` (what the text says)
    rewritten to ``constants``' value; unchanged lines (expressions included) stay as typed.

    The comment after a rewritten value keeps its column where the spaces allow.

    >>> text_with_constants("#define a2 60   // angle\n#define r 0.9", {"a2": 30.0, "r": 0.9},
    ...                     {"a2": 60.0, "r": 0.9})
    '#define a2 30   // angle\n#define r 0.9'
    """
    changed = {k: v for k, v in constants.items() if k in written and float(v) != float(written[k])}
    if not changed:
        return text
    lines = text.split("\n")
    for i, line in enumerate(lines):
        m = DEFINE_LINE.match(line)
        if m and m.group(2) in changed:
            lines[i] = _spaced(m, format_constant(changed[m.group(2)]))
    return "\n".join(lines)


def text_with_derivation(text: str, n: int, seed: int, written_n: int, written_seed: int) -> str:
    """``text`` with its ``n:`` line set to ``n`` and its ``#seed`` to ``seed`` where they differ from
    what the text says (``written_n``, ``written_seed``).  A text without ``#seed`` gets one just
    above its ``n:`` line; with no ``n:`` line (an L-studio file) the seed is left out."""
    lines = text.split("\n")
    count = next((i for i, line in enumerate(lines) if _COUNT.match(line) and "->" not in line), None)
    if int(n) != int(written_n) and count is not None:
        m = _COUNT.match(lines[count])
        assert m is not None
        lines[count] = _spaced(m, str(int(n)))
    if int(seed) != int(written_seed):
        at = next((i for i, line in enumerate(lines) if _SEED.match(line)), None)
        if at is not None:
            m = _SEED.match(lines[at])
            assert m is not None
            lines[at] = _spaced(m, str(int(seed)))
        elif count is not None and not lines[count].lstrip().lower().startswith("derivation"):
            indent = lines[count][: len(lines[count]) - len(lines[count].lstrip())]
            lines.insert(count, f"{indent}#seed {int(seed)}")
    return "\n".join(lines)


def _spaced(m: re.Match, new: str) -> str:
    """Matched line ``m`` with its value (the group before the comment) replaced by ``new``."""
    groups = m.groups()
    value, tail = groups[-2], groups[-1]
    if tail.strip():  # keep the comment's column: pad or trim the spaces before it
        spaces = len(tail) - len(tail.lstrip())
        tail = " " * max(1, spaces + len(value) - len(new)) + tail.lstrip()
    return "".join(groups[:-2]) + new + tail


def document_text(
    text: str, lsystem: LSystem, n: int, seed: int, constants: Mapping[str, float], filename: str | None = None
) -> str:
    """The grammar text that grows the plant of ``n`` steps, ``seed`` and ``constants`` from the
    grammar ``text`` (parsed as ``lsystem``): what Save grammar writes and the editor shows.

    A ``#define`` another one reads (``#define b a*2``) keeps its value: once ``a`` is written,
    ``b`` is written as a number too if its expression would now give another value.
    """
    out = text_with_derivation(text, n, seed, lsystem.n, lsystem.seed)
    written = dict(lsystem.constants)
    for _ in range(len(constants) + 1):
        new = text_with_constants(out, constants, written)
        if new == out:
            break
        out = new
        try:
            written = LSystem.from_text(out, filename=filename).constants
        except GrammarError:
            break
    return out


def check_round_trip(text: str, session: Session, filename: str | None = None) -> None:
    """Refuse (RamureError) a ``text`` that would not grow ``session``'s plant again: another
    ``n``, seed or constant value once read back (e.g. an L-studio file, which has no ``#seed``)."""
    read = LSystem.from_text(text, filename=filename)
    wrong = []
    if read.n != session.n:
        wrong.append(f"n = {session.n} (the text says {read.n})")
    if read.seed != session.seed:
        wrong.append(f"seed {session.seed} (the text gives {read.seed})")
    for name, value in session.constants.items():
        got = read.constants.get(name)
        if got is None or not math.isclose(float(got), float(value), rel_tol=1e-9, abs_tol=1e-12):
            wrong.append(f"{name} = {format_constant(value)} (the text gives {got})")
    if wrong:
        raise RamureError(
            "the grammar text cannot hold " + ", ".join(wrong) + ": save a session (.json) to keep the plant as it is"
        )


__all__ = ["check_round_trip", "document_text", "format_constant", "text_with_constants", "text_with_derivation"]
