"""Any MTG file as OpenAlea writes it: a multiscale tree graph with its classes and features.

:mod:`ramure.lsys.architecture.mtg` reads back the MTG files Ramure writes (fixed scales P/A/S/U/I);
this module reads the others: the ``CLASSES`` section declares any symbols and scales, the
``FEATURES`` section any features (``INT``, ``REAL``, ``ALPHA``/``STRING``, dates
``DD/MM/YY`` ..., and geometry types kept as text), and the ``MTG:`` section starts with an
``ENTITY-CODE`` or ``TOPO`` header line naming the feature columns.

The code follows OpenAlea's reader (``openalea.mtg.io``) step for step, so the vertex ids,
the scales, the complexes, the parents and the edge types are OpenAlea's:

* each line's leading tabs give its column; a line starting with ``^`` continues from the
  last entity written, a line without it hangs from the entity of the column to its left
  (a ``+`` or ``/`` there opens a branch);
* ``/`` decomposes (a component, one scale finer; ``/P2`` after ``/P1`` starts a new
  plant), ``<`` follows, ``+`` branches, ``<<E6`` repeats ``<`` up to index 6;
* a line ``*`` adds dated feature values to the last entity (dynamic MTGs);
* the edges of the coarser scales are deduced from the finest, as OpenAlea's ``fat_mtg``.

A file that uses a class it does not declare, places an entity at another scale than its
class's, or whose columns do not nest is refused with an :class:`MTGError` naming the line:
a misread is never a silently different tree.  Files in UTF-8 or Latin-1 (the AMAPmod era)
are read; :attr:`MTGGraph.encoding` says which.

>>> g = parse_mtg_graph('''CODE: FORM-A
... CLASSES:
... SYMBOL SCALE DECOMPOSITION INDEXATION DEFINITION
... $ 0 FREE FREE IMPLICIT
... P 1 FREE FREE IMPLICIT
... I 2 FREE FREE IMPLICIT
... DESCRIPTION:
... LEFT RIGHT RELTYPE MAX
... FEATURES:
... NAME TYPE
... MTG:
... ENTITY-CODE
... /P1/I1
... ^<I2
... \\t+I3
... ^<I4''')
>>> g.vertices_per_scale()
{1: 1, 2: 4}
>>> [g.label[v] + g.edge[v] + g.label[g.parent[v]] for v in g.at_scale(2)[1:]]
['I2<I1', 'I3+I2', 'I4<I2']
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ramure.io import FileRefused, read_regular

from .mtg import MAX_MTG_BYTES, MTGError

#: Feature types and how their values are read (other declared types are kept as text).
FEATURE_TYPES = {"INT": int, "REAL": float, "ALPHA": str, "STRING": str}
DATE_TYPES = ("DD/MM/YY", "DD/MM/YYYY", "MM/YY", "DD/MM", "DD/MM-TIME", "DD/MM/YY-TIME", "DD/MM/YYYY-TIME")
GEOMETRY_TYPES = ("GEOMETRY", "APPEARANCE", "OBJECT")
_PIECE = re.compile(r"(<<|[/<+\[\]*])([A-Za-z]+[0-9]*)?")
_LABEL = re.compile(r"([A-Za-z]+)([0-9]*)")


@dataclass
class MTGGraph:
    """A multiscale tree graph: one row per vertex, vertex 0 the scale-0 root (OpenAlea's ids).

    ``complex`` is the vertex one scale coarser that a vertex is part of, ``parent`` its
    predecessor at its own scale (``-1``: none) and ``edge`` the relation to it: ``"<"``
    follows, ``"+"`` branches, ``""`` none.  ``features`` maps each declared feature to a list
    with one value per vertex (None where the file gives none); ``dated`` keeps the ``*``
    lines of a dynamic MTG: vertex -> list of {feature: value}.
    """

    label: list[str]
    scale: np.ndarray
    complex: np.ndarray
    parent: np.ndarray
    edge: np.ndarray
    line: np.ndarray
    classes: dict[str, int]
    feature_types: dict[str, str]
    features: dict[str, list[Any]]
    form: str = "FORM-A"
    encoding: str = "utf-8"
    dated: dict[int, list[dict[str, Any]]] = field(default_factory=dict)
    description: list[tuple[str, str, str, str]] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.label)

    def at_scale(self, scale: int) -> np.ndarray:
        """The vertices of ``scale`` in file order."""
        return np.flatnonzero(self.scale == scale)

    def vertices_per_scale(self) -> dict[int, int]:
        """Scale -> number of vertices (the root's scale 0 left out)."""
        counts = np.bincount(self.scale)
        return {s: int(counts[s]) for s in range(1, len(counts))}

    def edges_by_type(self) -> dict[str, int]:
        """Number of ``<`` and ``+`` edges (all scales) and of ``/`` decompositions."""
        return {
            "<": int(np.count_nonzero(self.edge == "<")),
            "+": int(np.count_nonzero(self.edge == "+")),
            "/": int(np.count_nonzero(self.complex > 0)),
        }

    def plants(self) -> int:
        """Number of vertices of scale 1 with no predecessor (OpenAlea's plants)."""
        return int(np.count_nonzero((self.scale == 1) & (self.parent < 0)))

    def symbol(self, vertex: int) -> str:
        """The class symbol of ``vertex`` (its label's letters)."""
        return _LABEL.match(self.label[vertex]).group(1) if vertex else "$"  # type: ignore[union-attr]  # every label matched

    def to_dict(self) -> dict[str, Any]:
        """What ``ramure mtg FILE`` prints: counts per scale, classes, features, edges."""
        return {
            "form": self.form,
            "encoding": self.encoding,
            "vertices_per_scale": {str(s): n for s, n in self.vertices_per_scale().items()},
            "plants": self.plants(),
            "classes": dict(self.classes),
            "features": dict(self.feature_types),
            "edges": self.edges_by_type(),
        }


def read_mtg_graph(path: str | os.PathLike) -> MTGGraph:
    """Read an MTG file (UTF-8, else Latin-1); see the module docstring."""
    try:
        raw = read_regular(path, MAX_MTG_BYTES, "MTG file")
    except FileRefused as exc:
        raise MTGError(str(exc)) from None
    text, encoding = decode_mtg(raw)
    graph = parse_mtg_graph(text, str(path))
    graph.encoding = encoding
    return graph


def decode_mtg(raw: bytes) -> tuple[str, str]:
    """The text of an MTG file and its encoding: UTF-8 (a BOM dropped), else Latin-1.

    >>> decode_mtg("Hêtre".encode("latin-1"))
    ('Hêtre', 'latin-1')
    """
    try:
        return raw.decode("utf-8-sig"), "utf-8"
    except UnicodeDecodeError:
        return raw.decode("latin-1"), "latin-1"


def parse_mtg_graph(text: str, where: str = "MTG") -> MTGGraph:
    """The multiscale tree graph of MTG ``text`` (``where`` names it in error messages)."""
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    header = _Header(lines, where)
    graph = _Builder(header, where)
    for number, pieces, values in _bracketed(lines, header, where):
        graph.run(pieces, values, number)
    return graph.finish()


# -- header ---------------------------------------------------------------------------------
class _Header:
    """The CODE, CLASSES, DESCRIPTION and FEATURES sections and the MTG section's first line."""

    def __init__(self, lines: list[str], where: str) -> None:
        self.where = where
        self.form = "FORM-A"
        self.classes: dict[str, int] = {}
        self.description: list[tuple[str, str, str, str]] = []
        self.types: dict[str, str] = {}
        section = None
        for number, line in enumerate(lines, start=1):
            words = line.split("#")[0].split()
            if not words:
                continue
            key = words[0].rstrip(":").upper() if ":" in "".join(words[:2]) else ""
            if key in ("CODE", "CLASSES", "DESCRIPTION", "FEATURES") and _is_section(words):
                section = key
                if key == "CODE":
                    self.form = "".join(words).split(":", 1)[1] or "FORM-A"
                continue
            if key == "MTG" and _is_section(words):
                self._columns(lines, number)
                return
            self._row(section, words, number)
        raise MTGError(f"{where}: no 'MTG:' section")

    def _row(self, section, words, number):
        where = self.where
        if section == "CLASSES" and words != ["SYMBOL", "SCALE", "DECOMPOSITION", "INDEXATION", "DEFINITION"]:
            if len(words) != 5 or not words[1].isdigit() or not (words[0].isalpha() or words[0] == "$"):
                raise MTGError(f"{where}, line {number}: a class is 'SYMBOL SCALE DECOMPOSITION INDEXATION DEFINITION'")
            if words[0] != "$":
                self.classes[words[0]] = int(words[1])
        elif section == "DESCRIPTION" and words != ["LEFT", "RIGHT", "RELTYPE", "MAX"]:
            if len(words) < 4 or words[-2] not in ("<", "+"):
                raise MTGError(f"{where}, line {number}: a description row is 'LEFT RIGHT RELTYPE MAX' (RELTYPE < or +)")
            self.description.append((words[0], "".join(words[1:-2]), words[-2], words[-1]))
        elif section == "FEATURES" and words != ["NAME", "TYPE"]:
            if len(words) != 2:
                raise MTGError(f"{where}, line {number}: a feature is 'NAME TYPE'")
            kind = words[1].upper()
            if kind not in FEATURE_TYPES and kind not in DATE_TYPES and kind not in GEOMETRY_TYPES:
                known = ", ".join([*FEATURE_TYPES, *DATE_TYPES, *GEOMETRY_TYPES])
                raise MTGError(f"{where}, line {number}: feature {words[0]!r} has type {words[1]!r}; known types: {known}")
            self.types[words[0]] = kind
        elif section is None:
            raise MTGError(f"{where}, line {number}: {' '.join(words)!r} stands before any section (CODE:, CLASSES: ...)")

    def _columns(self, lines, mtg_line):
        """The ENTITY-CODE/TOPO line: where the code columns end and which features follow."""
        for number in range(mtg_line + 1, len(lines) + 1):
            line = lines[number - 1]
            if not line.strip() or line.strip().startswith("#"):
                continue
            words = line.split("#")[0].split()
            if words[0] not in ("ENTITY-CODE", "TOPO"):
                raise MTGError(f"{self.where}, line {number}: the MTG section starts with an ENTITY-CODE or TOPO line")
            unknown = [w for w in words[1:] if w not in self.types]
            if unknown:
                raise MTGError(f"{self.where}, line {number}: feature {unknown[0]!r} is not declared in FEATURES")
            self.columns = words[1:]
            # As OpenAlea: the feature values are the cells from the first feature's column on.
            after = line.find(words[0]) + len(words[0])
            self.first = len(line[: line.find(words[1], after)].split("\t")) - 1 if len(words) > 1 else len(line.split("\t"))
            self.code_start = number + 1
            return
        raise MTGError(f"{self.where}: the MTG section has no ENTITY-CODE or TOPO line")


def _is_section(words):
    return words[0].endswith(":") or (len(words) > 1 and words[1].startswith(":"))


# -- code: OpenAlea's preprocessing into one bracketed string -------------------------------
def _bracketed(lines, header, where):
    """Per code line: (line number, pieces such as ``][+A2/U1``, the line's feature values)."""
    indent, edges = [0], []
    for number in range(header.code_start, len(lines) + 1):
        line = lines[number - 1]
        if not line.strip() or line.strip().startswith("#"):
            continue
        code = line.split()[0]
        tabs = len(line) - len(line.lstrip("\t"))
        if tabs >= header.first and header.columns:
            raise MTGError(f"{where}, line {number}: the entity code stands in a feature column")
        cells = line.split("\t")[header.first : header.first + len(header.columns)]
        values = {name: cell.strip() for name, cell in zip(header.columns, cells) if cell.strip()}
        if tabs > indent[-1]:
            if code.startswith("^"):
                raise MTGError(f"{where}, line {number}: '^' on a line indented deeper than the line before")
            indent.append(tabs)
            edges.append(code[0])
            code = "[" + code if code[0] in "+/" else code
        else:
            closing = []
            while tabs < indent[-1]:
                indent.pop()
                if edges and edges.pop() in "+/":
                    closing.append("]")
            if tabs != indent[-1]:
                raise MTGError(f"{where}, line {number}: column {tabs + 1} matches no line above (check the tabs)")
            code = "".join(closing) + _same_column(code, edges)
        yield number, code, values
    yield len(lines), "]" * sum(e in "+/" for e in edges), {}


def _same_column(code, edges):
    if code.startswith("^"):
        return code[1:]
    if edges and code[0] in "+/":
        close = "]" if edges[-1] in "+/" else ""
        if close:
            edges.pop()
        edges.append(code[0])
        return close + "[" + code
    if not edges and code[0] == "+":
        edges.append("+")
    return code


# -- code: OpenAlea's multiscale_edit --------------------------------------------------------
class _Builder:
    def __init__(self, header: _Header, where: str) -> None:
        self.header, self.where = header, where
        self.label, self.scale, self.explicit, self.parent, self.edge, self.line = ["$"], [0], [-1], [-1], [""], [0]
        self.values: list[dict[str, Any]] = [{}]
        self.dated: dict[int, list[dict[str, Any]]] = {}
        self.components: dict[int, list[int]] = {}
        self.vid = self.current = 0
        self.at = 0  # the scale being written
        self.pending = ""
        self.stack: list[int] = []

    def _new(self, label, scale, complex_, parent, edge, number):
        self.label.append(label)
        self.scale.append(scale)
        self.explicit.append(complex_)
        self.parent.append(parent)
        self.edge.append(edge)
        self.line.append(number)
        self.values.append({})
        vertex = len(self.label) - 1
        if complex_ >= 0:
            self.components.setdefault(complex_, []).append(vertex)
        return vertex

    def complex_of(self, vertex: int) -> int:
        while vertex >= 0 and self.explicit[vertex] < 0:
            vertex = self.parent[vertex]
        return self.explicit[vertex] if vertex >= 0 else -1

    def child(self, parent, label, edge, number):
        return self._new(label, self.scale[parent], -1, parent, edge, number)

    def component(self, complex_, label, number):
        if complex_ < 0:
            raise MTGError(f"{self.where}, line {number}: '{label}' is part of nothing (the scales go above the plant)")
        return self._new(label, self.scale[complex_] + 1, complex_, -1, "", number)

    def run(self, code: str, values: dict[str, str], number: int) -> None:
        made = None
        at = 0
        while at < len(code):
            m = _PIECE.match(code, at)
            if m is None or (m.group(1) in "/<+<<") != (m.group(2) is not None):
                raise MTGError(f"{self.where}, line {number}: cannot read the entity code {code.lstrip('[]')!r}")
            made = self._piece(m.group(1), m.group(2), number)
            at = m.end()
        if made == "*" and values:
            self.dated.setdefault(self.vid, []).append(self._typed(values, number))
        elif made is not None and values:
            self.values[made].update(self._typed(values, number))

    def _piece(self, tag, label, number):
        if tag == "*":
            return "*"
        if tag == "[":
            self.stack.append(self.vid)
            return None
        if tag == "]":
            if not self.stack:
                raise MTGError(f"{self.where}, line {number}: a branch closes that was never opened")
            self.vid = self.current = self.stack.pop()
            self.at = self.scale[self.vid]
            return None
        symbol = _LABEL.fullmatch(label).group(1)  # type: ignore[union-attr]  # _PIECE matched a label
        if symbol not in self.header.classes:
            raise MTGError(f"{self.where}, line {number}: class '{symbol}' of '{label}' is not declared in CLASSES")
        wanted = self.header.classes[symbol]
        made = self._place(tag, label, wanted, number)
        if self.scale[made] != wanted:
            raise MTGError(
                f"{self.where}, line {number}: '{tag}{label}' lands at scale {self.scale[made]}, "
                f"but class '{symbol}' is at scale {wanted}"
            )
        return made

    def _place(self, tag, label, wanted, number):
        if tag == "/" and wanted <= self.at:
            wanted -= 1
            self.pending = "/"
        while wanted < self.at:
            self.at -= 1
            self.current = self.complex_of(self.current)
        vid_scale = self.scale[self.vid]
        if tag in "+<":
            if vid_scale == self.at:
                self.vid = self.current = self.child(self.vid, label, tag, number)
                self.pending = ""
            else:
                self.current = self.component(self.complex_of(self.current), label, number)
                self.pending = tag
            return self.current
        if tag == "<<":
            return self._repeat(label, number)
        if vid_scale == self.at:
            self.vid = self.current = self.component(self.vid, label, number)
            self.at += 1
        elif vid_scale > self.at:
            self.at += 1
            made = self.component(self.current, label, number)
            if vid_scale == self.at and self.pending != "/":
                self.parent[made], self.edge[made] = self.vid, self.pending
                self.vid = made
            elif self.pending == "/":
                self.vid = made
                self.at = self.scale[made]
            self.current = made
        else:
            self.vid = self.current = self.component(self.current, label, number)
        return self.current

    def _repeat(self, label, number):
        symbol, last = _LABEL.fullmatch(label).groups()  # type: ignore[union-attr]  # _PIECE matched a label
        first = _index(self.label[self.current]) if self.current else None
        if first is None or not last:
            raise MTGError(f"{self.where}, line {number}: '<<{label}' needs indexed entities on both sides")
        self.pending = ""
        for index in range(first + 1, int(last) + 1):
            self.vid = self.current = self.child(self.vid, f"{symbol}{index}", "<", number)
        return self.current

    def _typed(self, values, number):
        out = {}
        for name, text in values.items():
            read = FEATURE_TYPES.get(self.header.types[name], str)
            try:
                out[name] = read(text)
            except ValueError:
                kind = self.header.types[name]
                raise MTGError(f"{self.where}, line {number}: feature {name} = {text!r} is not of type {kind}") from None
        return out

    def finish(self) -> MTGGraph:
        self._fat()
        complexes = np.array([self.complex_of(v) if v else -1 for v in range(len(self.label))], np.int64)
        names = self.header.types
        return MTGGraph(
            label=self.label,
            scale=np.array(self.scale, np.int64),
            complex=complexes,
            parent=np.array(self.parent, np.int64),
            edge=np.array(self.edge, dtype="<U1"),
            line=np.array(self.line, np.int64),
            classes=dict(self.header.classes),
            feature_types=dict(names),
            features={name: [v.get(name) for v in self.values] for name in names},
            form=self.header.form,
            dated=self.dated,
            description=self.header.description,
        )

    def _fat(self):
        """OpenAlea's ``fat_mtg``: a coarse vertex with no parent gets the complex of its first
        component's parent, with that component's edge type (finest scale first)."""
        top = max(self.scale)
        for scale in range(top - 1, 0, -1):
            for vertex in range(1, len(self.label)):
                if self.scale[vertex] != scale or self.parent[vertex] >= 0 or vertex not in self.components:
                    continue
                first = self.components[vertex][0]
                if self.parent[first] < 0:
                    continue
                above = self.complex_of(self.parent[first])
                if above >= 0:
                    self.parent[vertex], self.edge[vertex] = above, self.edge[first]


def _index(label):
    digits = _LABEL.fullmatch(label)
    return int(digits.group(2)) if digits and digits.group(2) else None
