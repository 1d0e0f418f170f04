"""MTG export and import: OpenAlea's multiscale tree graph text format (FORM-A).

Scales: ``P`` plant (1), ``A`` axis (2), ``S`` annual shoot (3), ``U`` growth unit (4),
``I`` internode (5). The ``MTG:`` section writes one entity per line; leading tabs give the
column, ``/`` decomposes (a component), ``<`` follows, ``+`` branches, and ``^`` refers to the
last entity of the same column (without it, to the last entity one column to the left).
Axes are labelled by their order (``A1`` trunk, ``A2`` ...), the other entities by their rank
in their container. Internodes carry the feature ``node`` (the history-tree node id), and a
comment line keeps the derivation's event counts, so :func:`read_mtg` gives back exactly the
:class:`~ramure.lsys.architecture.amap.Architecture` that :func:`write_mtg` wrote.

>>> import ramure, tempfile, pathlib
>>> from ramure.lsys.architecture.amap import architecture
>>> arch = architecture(ramure.derive("amap/rauh", n=6))
>>> path = pathlib.Path(tempfile.mkdtemp()) / "rauh.mtg"
>>> _ = write_mtg(arch, path)
>>> read_mtg(path).equals(arch)
True
"""

from __future__ import annotations

import json
import pathlib
import re

import numpy as np

from ramure.errors import RamureError
from ramure.io import FileRefused, read_regular, write_text

from .amap import Architecture, Table, rank_in_group
import os
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..interpretation.turtle import Skeleton

#: The largest MTG file read (a plant of a million entities is about 60 MB).
MAX_MTG_BYTES = 512 * 2**20
SCALES = {"P": 1, "A": 2, "S": 3, "U": 4, "I": 5}
_EVENTS = "# ramure-events: "
_TOKEN = re.compile(r"([/<+])([A-Za-z$]+)(\d*)")


class MTGError(RamureError, ValueError):
    """An MTG file Ramure cannot read: the message names the line."""


# -- export ---------------------------------------------------------------------------------
#: The geometry features written with a skeleton, named as OpenAlea's PlantFrame reads them:
#: the internode's top point, its top and bottom diameters and its length.
GEOMETRY_FEATURES = ("XX", "YY", "ZZ", "TopDiameter", "BottomDiameter", "Length")


def internode_geometry(arch: Architecture, skeleton: Skeleton) -> np.ndarray:
    """(internodes, 6) the :data:`GEOMETRY_FEATURES` of each internode from the segments its
    history node drew (the first segment's base, the last one's top); nan where it drew none."""
    order = np.argsort(skeleton.leaf_id, kind="stable")
    ids = skeleton.leaf_id[order]
    first = np.searchsorted(ids, arch.internodes.node, side="left")
    last = np.searchsorted(ids, arch.internodes.node, side="right") - 1
    drawn = last >= first
    out = np.full((len(arch.internodes), 6), np.nan)
    lo, hi = order[first[drawn]], order[last[drawn]]
    out[drawn, 0:3] = skeleton.end[hi]
    out[drawn, 3] = 2 * skeleton.top_radius[hi]
    out[drawn, 4] = 2 * skeleton.base_radius[lo]
    out[drawn, 5] = np.linalg.norm(skeleton.end[hi] - skeleton.start[lo], axis=1)
    return out


def mtg_text(arch: Architecture, skeleton: Skeleton | None = None) -> str:
    """The MTG text of an architecture (see the module docstring); with the plant's
    ``skeleton`` each internode also carries the :data:`GEOMETRY_FEATURES`."""
    geometry = internode_geometry(arch, skeleton) if skeleton is not None else None
    lines = []  # (column, code, node or None)
    borne: dict[int, list[int]] = {}
    for row, bearer in enumerate(arch.axes.bearer.tolist()):
        borne.setdefault(bearer, []).append(row)
    by_axis = np.argsort(arch.internodes.axis, kind="stable")
    starts = np.searchsorted(arch.internodes.axis[by_axis], np.arange(len(arch.axes) + 1))
    ranks = {
        "rows": [by_axis[starts[a] : starts[a + 1]].tolist() for a in range(len(arch.axes))],
        "shoot": rank_in_group(arch.shoots.axis).tolist(),
        "unit": rank_in_group(arch.growth_units.shoot).tolist(),
        "shoot_of": arch.internodes.shoot.tolist(),
        "unit_of": arch.internodes.growth_unit.tolist(),
        "node": arch.internodes.node.tolist(),
        "rank": arch.internodes.rank.tolist(),
        "order": arch.axes.order.tolist(),
    }
    lines.append((0, "/P1", None))
    for axis in borne.get(-1, []):
        _write_axis(arch, axis, 0, "^/", borne, ranks, lines)
    width = max(col for col, _, _ in lines) + 1
    header = [
        _EVENTS + json.dumps(arch.events, sort_keys=True),
        "CODE:\tFORM-A",
        "",
        "CLASSES:",
        "SYMBOL\tSCALE\tDECOMPOSITION\tINDEXATION\tDEFINITION",
        "$\t0\tFREE\tFREE\tIMPLICIT",
    ]
    header += [f"{s}\t{scale}\tFREE\tFREE\tIMPLICIT" for s, scale in SCALES.items()]
    header += ["", "DESCRIPTION:", "LEFT\tRIGHT\tRELTYPE\tMAX"]
    header += [f"{a}\t{a}\t{r}\t?" for a in ("A", "S", "U", "I") for r in "<+"]
    names = ["node", *(GEOMETRY_FEATURES if geometry is not None else ())]
    header += ["", "FEATURES:", "NAME\tTYPE", "node\tINT", *(f"{n}\tREAL" for n in names[1:])]
    header += ["", "MTG:", "ENTITY-CODE" + "\t" * width + "\t".join(names)]
    row_of = {int(n): r for r, n in enumerate(arch.internodes.node.tolist())} if geometry is not None else {}
    body = []
    for col, code, node in lines:
        cells = "" if node is None else "\t" * (width - col) + str(node)
        if node is not None and geometry is not None:
            cells += "".join("\t" + ("" if np.isnan(x) else f"{x:.9g}") for x in geometry[row_of[node]].tolist())
        body.append("\t" * col + code + cells)
    return "\n".join(header + body) + "\n"


def _write_axis(arch, axis, col, prefix, borne, ranks, lines) -> None:
    lines.append((col, f"{prefix}A{ranks['order'][axis]}", None))
    shoot_of, unit_of, nodes, rank = ranks["shoot_of"], ranks["unit_of"], ranks["node"], ranks["rank"]
    previous_shoot = previous_unit = -1
    for row in ranks["rows"][axis]:
        shoot, unit = shoot_of[row], unit_of[row]
        if previous_shoot < 0:
            lines += [(col, "^/S1", None), (col, "^/U1", None)]
        elif shoot != previous_shoot:
            lines += [(col, f"^<S{ranks['shoot'][shoot] + 1}", None), (col, "^/U1", None)]
        elif unit != previous_unit:
            lines.append((col, f"^<U{ranks['unit'][unit] + 1}", None))
        code = "^/I1" if unit != previous_unit else f"^<I{rank[row] + 1}"
        lines.append((col, code, nodes[row]))
        previous_shoot, previous_unit = shoot, unit
        for child in borne.get(row, []):
            _write_axis(arch, child, col + 1, "+", borne, ranks, lines)


def write_mtg(arch: Architecture, path: str | os.PathLike, skeleton: Skeleton | None = None) -> pathlib.Path:
    """Write ``arch`` as an MTG file (temporary file in the same folder, fsync, then renamed);
    with ``skeleton``, the internodes' geometry features too (:func:`mtg_text`)."""
    path = pathlib.Path(path)
    text = mtg_text(arch, skeleton)
    write_text(path, text)
    return path


# -- import ---------------------------------------------------------------------------------
def read_mtg(path: str | os.PathLike) -> Architecture:
    """Read an MTG file written by :func:`write_mtg` (or any FORM-A file with these scales)."""
    path = pathlib.Path(path)
    try:
        text = read_regular(path, MAX_MTG_BYTES, "MTG file").decode("utf-8")
    except FileRefused as exc:
        raise MTGError(str(exc)) from None
    except UnicodeDecodeError:
        raise MTGError(f"{path}: not a UTF-8 text file") from None
    return parse_mtg(text, str(path))


def parse_mtg(text: str, where: str = "MTG") -> Architecture:
    """The architecture described by MTG ``text``."""
    lines = text.replace("\r\n", "\n").split("\n")
    events = {}
    if lines and lines[0].startswith(_EVENTS):
        events = _events(lines[0][len(_EVENTS) :], where)
    classes, start = _classes(lines, where)
    entities = _entities(lines, start, classes, where)
    return _to_architecture(entities, events, where)


def _events(text, where):
    """The ``# ramure-events:`` header: a JSON object, else an MTGError naming line 1."""
    try:
        events = json.loads(text)
    except (json.JSONDecodeError, RecursionError) as exc:
        raise MTGError(f"{where}, line 1: the '# ramure-events:' header is not valid JSON ({exc})") from None
    if not isinstance(events, dict):
        raise MTGError(f"{where}, line 1: the '# ramure-events:' header must be a JSON object")
    return events


def _classes(lines, where):
    classes: dict[str, int] = {}
    in_classes = False
    for number, line in enumerate(lines, start=1):
        head = line.strip().split("\t")[0].replace(" ", "")
        if head == "CLASSES:":
            in_classes = True
        elif head in ("DESCRIPTION:", "FEATURES:"):
            in_classes = False
        elif head == "MTG:":
            return classes, number
        elif in_classes and head and head != "SYMBOL":
            cells = [c for c in line.split("\t") if c.strip()]
            try:
                classes[cells[0].strip()] = int(cells[1])
            except (IndexError, ValueError):
                raise MTGError(f"{where}, line {number}: a class needs a symbol and a whole-number scale") from None
    raise MTGError(f"{where}: no 'MTG:' section")


def _entities(lines, start, classes, where):
    """Entities as dicts: class, scale, complex, relation, reference, fine (the line's reference)."""
    entities: list[dict] = []
    last: dict[int, int | None] = {}
    feature_col = None
    for number in range(start + 1, len(lines) + 1):
        line = lines[number - 1]
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if line.startswith("ENTITY-CODE"):
            names = line.split("\t")
            feature_col = names.index("node") if "node" in names else None
            continue
        col = len(line) - len(line.lstrip("\t"))
        cells = line.split("\t")
        code = cells[col]
        node = _node_feature(cells, feature_col, number, where)
        ref = last.get(col) if code.startswith("^") else last.get(col - 1, None)
        if code.startswith("^") and ref is None:
            raise MTGError(f"{where}, line {number}: '^' refers to nothing in column {col + 1}")
        tokens = _TOKEN.findall(code.lstrip("^"))
        if not tokens or "".join(r + s + i for r, s, i in tokens) != code.lstrip("^"):
            raise MTGError(f"{where}, line {number}: cannot read the entity code {code!r}")
        fine = ref
        for relation, symbol, _ in tokens:
            if symbol not in classes or symbol not in SCALES:
                raise MTGError(f"{where}, line {number}: unknown class or scale '{symbol}' (Ramure reads {', '.join(SCALES)})")
            ref = _add(entities, relation, symbol, ref, fine, number, where)
        assert ref is not None  # tokens is not empty: _add made at least one entity
        entities[ref]["node"] = node
        last[col] = ref
        for deeper in [c for c in last if c > col]:
            del last[deeper]
    return entities


def _node_feature(cells, feature_col, number, where):
    if feature_col is None or len(cells) <= feature_col or not cells[feature_col].strip():
        return None
    try:
        return int(cells[feature_col])
    except ValueError:
        raise MTGError(f"{where}, line {number}: the node feature must be a whole number") from None


def _ancestor(entities, index, scale):
    while index is not None and entities[index]["scale"] > scale:
        index = entities[index]["complex"]
    return index if index is not None and entities[index]["scale"] == scale else None


def _add(entities, relation, symbol, ref, fine, number, where):
    scale = SCALES[symbol]
    if relation == "/":
        complex_ = _ancestor(entities, ref, scale - 1) if ref is not None else None
        if ref is not None and complex_ is None:
            raise MTGError(f"{where}, line {number}: '/{symbol}' has no container at scale {scale - 1}")
        other = None
    else:
        other = _ancestor(entities, ref, scale) if ref is not None else None
        if other is None:
            raise MTGError(f"{where}, line {number}: '{relation}{symbol}' follows or branches from nothing at scale {scale}")
        complex_ = entities[other]["complex"]
    entities.append(
        {
            "symbol": symbol,
            "scale": scale,
            "complex": complex_,
            "relation": relation,
            "other": other,
            "fine": fine,
            "node": None,
            "line": number,
        }
    )
    return len(entities) - 1


def _to_architecture(entities, events, where):
    index = {s: [i for i, e in enumerate(entities) if e["symbol"] == s] for s in SCALES}
    row = {s: {e: r for r, e in enumerate(index[s])} for s in SCALES}

    def up(i, symbol):
        found = _ancestor(entities, i, SCALES[symbol])
        if found is None:
            e = entities[i]
            raise MTGError(f"{where}, line {e['line']}: this '{e['symbol']}' lies in no '{symbol}' (scale {SCALES[symbol]})")
        return row[symbol][found]

    inter = index["I"]
    nodes = [entities[i]["node"] for i in inter]
    if any(n is None for n in nodes):
        raise MTGError(f"{where}: every internode needs its 'node' feature")
    unit_of = np.array([up(i, "U") for i in inter], np.int64)
    internodes = Table(
        {
            "node": np.array(nodes, np.int64),
            "axis": np.array([up(i, "A") for i in inter], np.int64),
            "growth_unit": unit_of,
            "shoot": np.array([up(i, "S") for i in inter], np.int64),
            "rank": _ranks(unit_of),
        }
    )
    units = index["U"]
    growth_units = Table(
        {
            "axis": np.array([up(u, "A") for u in units], np.int64),
            "shoot": np.array([up(u, "S") for u in units], np.int64),
            "first": _firsts(unit_of, len(units)),
            "count": np.bincount(unit_of, minlength=len(units)),
        }
    )
    shoot_of_unit = growth_units.shoot
    shoots = Table(
        {
            "axis": np.array([up(s, "A") for s in index["S"]], np.int64),
            "first": _firsts(shoot_of_unit, len(index["S"])),
            "count": np.bincount(shoot_of_unit, minlength=len(index["S"])),
        }
    )
    axes = _axes(entities, index["A"], row, internodes, where)
    return Architecture(internodes, growth_units, shoots, axes, events)


def _ranks(groups):
    out = np.zeros(len(groups), np.int64)
    seen: dict[int, int] = {}
    for k, g in enumerate(groups.tolist()):
        out[k] = seen.get(g, 0)
        seen[g] = out[k] + 1
    return out


def _firsts(groups, count):
    first = np.full(count, -1, np.int64)
    for k in range(len(groups) - 1, -1, -1):
        first[groups[k]] = k
    return first


def _axes(entities, axes, row, internodes, where):
    parent = np.full(len(axes), -1, np.int64)
    bearer = np.full(len(axes), -1, np.int64)
    order = np.ones(len(axes), np.int64)
    node_row = {int(n): r for r, n in enumerate(internodes.node.tolist())}
    for r, i in enumerate(axes):
        e = entities[i]
        if e["relation"] == "+":
            fine = e["fine"]
            if fine is None or entities[fine]["symbol"] != "I":
                raise MTGError(f"{where}: axis {r + 1} branches from something that is not an internode")
            bearer[r] = node_row[entities[fine]["node"]]
            parent[r] = internodes.axis[bearer[r]]
        order[r] = int(e.get("order", 0)) or (order[parent[r]] + 1 if parent[r] >= 0 else 1)
    _refuse_bearer_cycles(parent, where)
    first = _firsts(internodes.axis, len(axes))
    return Table({"parent": parent, "bearer": bearer, "order": order, "first": first})


def _refuse_bearer_cycles(parent, where):
    state = np.zeros(len(parent), np.int8)  # 0 unseen, 1 on the path, 2 done
    for start in range(len(parent)):
        path, a = [], start
        while a >= 0 and state[a] == 0:
            state[a] = 1
            path.append(a)
            a = parent[a]
        if a >= 0 and state[a] == 1:
            raise MTGError(f"{where}: the bearer links of axes {sorted(path)} form a cycle")
        state[path] = 2
