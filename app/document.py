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

import json
import math
import os
import pathlib
import re
from collections.abc import Callable, Iterable, Mapping
from typing import TYPE_CHECKING

from ramure.errors import RamureError
from ramure.io import read_regular
from ramure.lsys import GrammarError, LSystem
from ramure.lsys.language.grammar import read_grammar_file
from ramure.lsys.readers.lpy import LpyLSystem
from ramure.lsys.regeneration.regen import MAX_SESSION_BYTES

if TYPE_CHECKING:
    from ramure.lsys.regeneration.regen import Session

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


_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def lpy_text_with_constants(text: str, constants: Mapping[str, float], written: Mapping[str, float]) -> str:
    """An L-Py model's ``text`` with each ``extern(name=number)`` whose value differs from
    ``written`` rewritten to ``constants``' value (the first such ``extern`` of each name).

    >>> lpy_text_with_constants("extern(k=2, angle = 30.5)\\nAxiom: A", {"k": 3.0, "angle": 30.5},
    ...                         {"k": 2.0, "angle": 30.5})
    'extern(k=3, angle = 30.5)\\nAxiom: A'
    """
    for name, value in constants.items():
        if name not in written or float(value) == float(written[name]):
            continue
        pattern = re.compile(rf"(\bextern\s*\([^)]*?\b{re.escape(name)}\s*=\s*)({_NUMBER})")
        text = pattern.sub(_replacer(format_constant(value)), text, count=1)
    return text


def _replacer(value: str) -> Callable[[re.Match], str]:
    """A ``re.sub`` replacement: the match's first group, then ``value``."""
    return lambda m: m.group(1) + value


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
    if isinstance(lsystem, LpyLSystem):  # an L-Py model: its constants are extern(...) values
        return lpy_text_with_constants(out, constants, lsystem.grammar.constants)
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


# -- opening files: grammars, L-studio/cpfg, L-Py models, MTGs ------------------------------------

#: Suffixes of the files the explorer opens as a plant: Ramure grammars, L-studio/cpfg files,
#: L-Py models and OpenAlea MTGs.
OPEN_SUFFIXES = (".lsys", ".l", ".lpy", ".mtg")
#: Suffixes whose opening runs the file's code: an L-Py model is a Python program.
CODE_SUFFIXES = (".lpy",)
#: The largest session file :func:`session_runs_code` looks into (what :meth:`Session.load` reads).
_SESSION_PEEK_BYTES = MAX_SESSION_BYTES


def runs_code(path: str | os.PathLike) -> bool:
    """Whether opening ``path`` runs code written in it (an L-Py ``.lpy`` model does)."""
    return pathlib.Path(path).suffix.lower() in CODE_SUFFIXES


def code_folder(path: str | os.PathLike) -> pathlib.Path:
    """The folder a permission to run ``path``'s code is given for: its resolved parent."""
    return pathlib.Path(path).absolute().parent.resolve()


class CodeNotAllowed(RamureError):
    """Opening ``path`` would run its code, and the caller did not allow it.

    Front ends allow it after asking: the desktop once per folder (:class:`CodeTrust`), the
    notebook with ``Explorer(path, run_code=True)``."""

    def __init__(self, path: str | os.PathLike, how: str = "allow it only for files you would run as a script") -> None:
        self.path = pathlib.Path(path)
        self.folder = code_folder(path)
        what = (
            "is a session of an L-Py model: loading it runs the model's Python code"
            if self.path.suffix.lower() == ".json"
            else "is an L-Py model, a Python program: opening it runs its code"
        )
        super().__init__(f"{self.path.name} {what} with your rights; {how}")


class CodeTrust:
    """The folders whose L-Py models the user allowed to run: the desktop asks once per folder.

    ``folders`` are what a settings file stored (entries that are not text are dropped).

    >>> trust = CodeTrust()
    >>> trust.allows("/models/tree.lpy"), trust.allows("/models/tree.lsys")
    (False, True)
    >>> trust.allow("/models/tree.lpy")
    >>> trust.allows("/models/bush.lpy"), trust.allows("/elsewhere/bush.lpy")
    (True, False)
    """

    def __init__(self, folders: Iterable[object] = ()) -> None:
        self._folders = [f for f in folders if isinstance(f, str) and f]

    @property
    def folders(self) -> list[str]:
        """The allowed folders (resolved paths), in the order they were allowed."""
        return list(self._folders)

    def allows(self, path: str | os.PathLike) -> bool:
        """``path`` runs no code, or stands in a folder already allowed."""
        return not runs_code(path) or str(code_folder(path)) in self._folders

    def allow(self, path: str | os.PathLike) -> None:
        """Allow the code of every file in ``path``'s folder (not its subfolders)."""
        folder = str(code_folder(path))
        if folder not in self._folders:
            self._folders.append(folder)


def open_document(path: str | os.PathLike, run_code: bool = False) -> tuple[str, LSystem, pathlib.Path | None]:
    """The text, grammar and document path of the file ``path`` opened as a plant.

    * ``.lsys`` and L-studio ``.l`` files: their text, read as grammars;
    * L-Py ``.lpy`` models: their text, run as Python (:mod:`ramure.lsys.readers.lpy`) — only with
      ``run_code`` (else :class:`CodeNotAllowed`, before a byte of it is read);
    * OpenAlea ``.mtg`` files (UTF-8 or Latin-1): the grammar whose axiom draws the MTG
      (:mod:`ramure.lsys.architecture.mtg_plant`).  The MTG is imported: the document is that grammar,
      with no path yet (Save asks where to write it), and the MTG file is never overwritten.
    """
    path = pathlib.Path(path)
    if runs_code(path) and not run_code:  # refused before a byte of it is read
        if not path.exists():
            raise GrammarError("cannot read the model: no such file", filename=str(path))
        raise CodeNotAllowed(path)
    if path.suffix.lower() == ".mtg":
        from ramure.lsys.architecture.mtg_graph import read_mtg_graph
        from ramure.lsys.architecture.mtg_plant import mtg_grammar_text

        text = mtg_grammar_text(read_mtg_graph(path), where=str(path))
        return text, LSystem.from_text(text), None
    text = read_grammar_file(path)
    return text, LSystem.from_text(text, filename=str(path)), path


def session_runs_code(path: str | os.PathLike) -> bool:
    """Whether replaying the session file ``path`` runs code: its grammar is an L-Py model.

    A file that cannot be read or parsed gives False (loading it then says what is wrong)."""
    try:
        data = json.loads(read_regular(path, _SESSION_PEEK_BYTES, "session file").decode("utf-8"))
    except (RamureError, OSError, ValueError, RecursionError):
        return False
    if not isinstance(data, dict):
        return False
    names = (data.get("reader"), data.get("filename"))
    return any(isinstance(n, str) and runs_code("x" + n if n.startswith(".") else n) for n in names)


__all__ = [
    "CODE_SUFFIXES",
    "OPEN_SUFFIXES",
    "CodeNotAllowed",
    "CodeTrust",
    "code_folder",
    "open_document",
    "runs_code",
    "session_runs_code",
    "check_round_trip",
    "lpy_text_with_constants",
    "document_text",
    "format_constant",
    "text_with_constants",
    "text_with_derivation",
]
