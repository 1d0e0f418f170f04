"""Excrescences addressed by paths (Bohl 2015, §3.2): ``(3, C1, *)`` and add-rules on what it names.

**Paths.**  ``(s0, Ck, s1)``: go up ``s0`` stages of the trunk (ring ``s0``; the axiom is
stage 0), move to the child axis on lateral face ``Ck`` (the branch of sector ``k - 1``),
go up ``s1`` stages of that axis.  A branch's stages are its **radial layers counted from
the trunk** (0 = innermost, ``L - 1`` = the skin layer, ``L`` = 1 unsubdivided, 2 or 4
after one or two volume subdivisions: the thesis's layer shells are stages of the branch
axis too), and an excrescence grown on the skin continues the axis: its segments are
stages ``L, L + 1, ...``.  Wildcards: ``*`` for a stage (every stage), ``C*`` for a face
(every sector).  ``(3)`` names the trunk cells of ring 3.  Paths are resolved on the
volume attributes ``ring``, ``sector`` and the radial layer (:func:`ramure.gmap.organs.defects.radial_layers`),
which volume subdivision keeps: a path names the children of the cells it named before.

**Side axes** (``(3, C1, 4, C5, 2)``: a second ``Ck`` and after).  In the thesis a child
grown on lateral face ``Ck`` of the stage reached starts a new axis (stage 0), and a path
moves to that child.  The fruit's branch cells carry no grown children on their sides:
every lateral face is glued to the neighbouring branch (``B_C* | B_C*``), so the volume
across face ``Ck`` *is* the cell a side axis reaches.  Ramure's choice: a side turn
``Ck`` moves from the cell reached to its glued neighbour across its face ``Ck`` (side
stage 0), and side stage ``j`` is ``j`` further cells straight on in that direction,
keeping the radial stage (layer, or excrescence segment).  A branch cell is a quad prism
whose faces point C1 = ring - 1 (towards ring 0, the blossom end), C2 = sector + 1,
C3 = ring + 1 (towards the stem), C4 = sector - 1 (read from the built map), the same for
its subdivided children and its excrescence segments, so the walk is done on the ``(ring, sector, stage)`` attributes,
which volume subdivision keeps.  Lateral faces are numbered cyclically counter-clockwise
round the prism, so on these order-4 cells ``C5`` is ``C1`` again, ``C6`` is ``C2``, ...
(the issue's ``C5`` thus names a real face).  Around the fruit the sectors wrap; along
it a step past the first or last ring leaves the fruit, and so does a step onto a stage
that has no cell there (an excrescence segment not grown on that neighbour).  A path
leaving the fruit is refused with a caret under the token of the step that leaves; with a
wildcard (``C*`` or a side stage ``*``) the alternatives that leave are dropped (``*`` on a
side axis = every stage up to the pole, or once round the fruit but for the start).
A branch has at most 4 radial stages (two volume subdivisions), so the issue's literal
``(3, C1, 4, C5, 2)`` names cells once excrescence segments make stage 4 there, e.g. after
``(*, C1, 1)`` with 3 segments on a once-subdivided fruit (a ridge; tested).

**Excrescences** (:func:`excrescence`) are add-rules on the volumes a path names: on every
free E face (skin face) of those cells a quad prism is grown (kernel
:func:`ramure.gmap.kernel.embedding.grow`), the prisms grown on one branch are glued to each
other along their shared lateral faces (one bump per branch, as the thesis's
``B_C* | B_C*``), and further segments grow on their E faces.  Geometry (manual
embedding, as after subdivision): segment ``j`` of ``S`` rises ``j/S`` of ``height_mm``
along the bump's mean normal and narrows towards the bump's centre by ``taper j / S``.
A segment grows on the top (E) face of an excrescence cell only, never on
its free sides.  New cells: label ``X``, order 1, the base's ring, sector and tissue (exocarp on the
columella: a mucron at a pole is skin), volume attribute
``excrescence`` = segment number (kept by later subdivision).

>>> from ramure.gmap.organs.fruit import build_fruit
>>> gm = build_fruit("round_tomato")
>>> len(resolve_path(gm, "(3, C1, *)")), len(resolve_path(gm, "(*, C2, 0)")), len(resolve_path(gm, "(0)"))
(1, 10, 1)
>>> [(int(gm.volume_data["ring"][v]), int(gm.volume_data["sector"][v]))
...  for v in resolve_path(gm, "(3, C1, 0, C2, 1, C3, 2)")]      # sectors 1, 2 then rings 4, 5, 6
[(6, 2)]
>>> out, facts = excrescence(gm, "(3, C*, 0)", height_mm=4)
>>> facts["cells"], out.is_valid()
(10, True)
"""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np

from ramure.errors import GrammarError
from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.kernel.map3 import GMap3
from ramure.gmap.organs import defects as D
from ramure.gmap.organs.tissue import CODES

_TOKEN = re.compile(r"\s*(?:(?P<stage>\d+|\*)|(?P<face>[Cc](?:\d+|\*))|(?P<other>\S))")


class Path:
    """A parsed path: ``stages`` (int or None for ``*``) and ``faces`` (int or None for ``C*``),
    with the column of every token for error carets."""

    def __init__(self, text: str, stages: list[int | None], faces: list[int | None], columns: list[int]) -> None:
        self.text, self.stages, self.faces, self.columns = text, stages, faces, columns

    def __repr__(self) -> str:
        parts = [_show(self.stages[0])]
        for f, s in zip(self.faces, self.stages[1:]):
            parts += ["C*" if f is None else f"C{f}", _show(s)]
        return "(" + ", ".join(parts) + ")"

    def error(self, index: int, message: str) -> GrammarError:
        """A :class:`GrammarError` with a caret under token ``index``."""
        return GrammarError(f"path: {message}", column=self.columns[index] + 1, source_line=self.text)


def _show(stage: int | None) -> str:
    return "*" if stage is None else str(stage)


def parse_path(text: str) -> Path:
    """``"(3, C1, *)"`` -> :class:`Path`; a syntax error raises :class:`GrammarError` with a caret.

    >>> parse_path("(3, C1, 4, C5, 2)")
    (3, C1, 4, C5, 2)
    >>> parse_path("(*, C*, 1)").faces
    [None]
    """
    text = str(text)
    body = text.strip()
    start = text.index(body[0]) if body else 0
    if body.startswith("("):
        if not body.endswith(")"):
            raise GrammarError("path: missing ')'", column=len(text.rstrip()) + 1, source_line=text)
        inner, offset = body[1:-1], start + 1
    else:
        inner, offset = body, start
    items, columns, pos = [], [], 0
    pieces = inner.split(",")
    for piece in pieces:
        stripped = piece.strip()
        col = offset + pos + (len(piece) - len(piece.lstrip()))
        pos += len(piece) + 1
        if not stripped:
            raise GrammarError("path: empty item (two commas, or a comma at an end)", column=col + 1, source_line=text)
        items.append(stripped)
        columns.append(col)
    stages: list[int | None] = []
    faces: list[int | None] = []
    for i, (item, col) in enumerate(zip(items, columns)):
        want_stage = i % 2 == 0
        if want_stage:
            if item == "*":
                stages.append(None)
            elif item.isdigit():
                stages.append(int(item))
            else:
                raise GrammarError(
                    f"path: expected a stage (a whole number or *), got '{item}'", column=col + 1, source_line=text
                )
        else:
            m = re.fullmatch(r"[Cc](\d+|\*)", item)
            if not m:
                raise GrammarError(
                    f"path: expected a lateral face (C1, C2, ... or C*), got '{item}'", column=col + 1, source_line=text
                )
            faces.append(None if m.group(1) == "*" else int(m.group(1)))
            if faces[-1] == 0:
                raise GrammarError("path: lateral faces count from C1", column=col + 1, source_line=text)
    if len(items) % 2 == 0:
        raise GrammarError(
            "path: a path ends with a stage (a whole number or *) after its last face",
            column=len(text.rstrip()) + 1,
            source_line=text,
        )
    return Path(text, stages, faces, columns)


def branch_stages(gm: GMap3) -> tuple[int, np.ndarray]:
    """``(L, stage per volume)``: the stage of every branch cell along its axis (-1 elsewhere).

    Pericarp cells: radial layer counted from the trunk; excrescence segment j: ``L - 1 + j``.
    """
    from ramure.gmap.organs.defects import radial_layers

    layers, layer = radial_layers(gm)
    layers = max(layers, 1)
    stage = np.where(layer >= 0, layers - 1 - layer, -1)
    vd = gm.volume_data
    if "excrescence" in vd:
        seg = vd["excrescence"].astype(np.int64)
        stage = np.where(seg > 0, layers - 1 + seg, stage)
    return layers, stage


def resolve_path(gm: GMap3, path: str | Path) -> np.ndarray:
    """Volume ids named by ``path`` (text or :class:`Path`); refused with a caret when out of range."""
    p = path if isinstance(path, Path) else parse_path(path)
    vd = gm.volume_data
    if "ring" not in vd or "sector" not in vd:
        raise GMapError("paths need a fruit (volumes with ring and sector attributes)")
    ring, sector, order = (vd[k].astype(np.int64) for k in ("ring", "sector", "order"))
    n_rings = int(ring.max()) + 1
    r = p.stages[0]
    if r is not None and r >= n_rings:
        raise p.error(0, f"ring {r} is past the trunk's last stage ({n_rings - 1})")
    on_ring = np.ones(gm.n_volumes, bool) if r is None else ring == r
    if not p.faces:
        return np.flatnonzero(on_ring & (order == 0))
    ph = int(sector.max()) + 1
    k = p.faces[0]
    if k is not None and k > ph:
        raise p.error(1, f"C{k}: the trunk prisms have faces C1..C{ph}")
    layers, stage = branch_stages(gm)
    s = p.stages[1]
    top = int(stage.max())
    if s is not None and s > top:
        raise p.error(
            2,
            f"stage {s} is past the branches' last stage ({top}: {layers} radial layer(s)"
            + (", then excrescences)" if top >= layers else ")"),
        )
    keep = on_ring & (order >= 1) & (stage >= 0)
    if k is not None:
        keep &= sector == k - 1
    if s is not None:
        keep &= stage == s
    if len(p.faces) == 1:
        return np.flatnonzero(keep)
    if not keep.any():
        raise p.error(2, "no cell at this stage to turn from (an excrescence segment not grown here)")
    return _side_axes(p, ring, sector, stage, keep, ph)


# a branch cell's lateral face Ck -> (ring step, sector step); read from the built map
SIDE_STEPS = {1: (-1, 0), 2: (0, 1), 3: (1, 0), 4: (0, -1)}


def _side_axes(p: Path, ring, sector, stage, start, ph: int) -> np.ndarray:
    """Follow the side turns of ``p`` (its faces after the first) from the ``start`` cells."""
    branch = stage >= 0
    n_rings, n_stages = int(ring.max()) + 1, int(stage.max()) + 1

    def key(r, s, t):
        return (r * ph + s) * n_stages + t

    cell_key = key(ring, sector, np.maximum(stage, 0))
    present = np.unique(cell_key[branch])
    cur = np.unique(np.stack([ring[start], sector[start], stage[start]], 1), axis=0)
    for turn in range(1, len(p.faces)):
        face, want = p.faces[turn], p.stages[turn + 1]
        face_token, stage_token = 2 * turn + 1, 2 * turn + 2
        moves = [SIDE_STEPS[(face - 1) % 4 + 1]] if face is not None else list(SIDE_STEPS.values())
        reached, left_at = [], face_token
        for dr, ds in moves:
            top = want if want is not None else (n_rings if dr else ph - 2)
            pos = cur.copy()
            for j in range(top + 1):
                pos = pos.copy()
                pos[:, 0] += dr
                pos[:, 1] = (pos[:, 1] + ds) % ph
                inside = (pos[:, 0] >= 0) & (pos[:, 0] < n_rings)
                inside &= np.isin(key(pos[:, 0], pos[:, 1], pos[:, 2]), present)
                pos = pos[inside]
                if pos.size == 0:
                    left_at = max(left_at, face_token if j == 0 else stage_token)
                    break
                if want is None or j == want:
                    reached.append(pos)
        if not reached:
            where = "its first cell" if left_at == face_token else "this stage"
            raise p.error(
                left_at,
                f"the side axis leaves the fruit at {where} (no cell there: past a pole, "
                "or an excrescence segment not grown on that neighbour)",
            )
        cur = np.unique(np.concatenate(reached), axis=0)
    return np.flatnonzero(branch & np.isin(cell_key, key(cur[:, 0], cur[:, 1], cur[:, 2])))


def excrescence(
    gm: GMap3, path: str | Path, height_mm: float = 3.0, segments: int = 1, taper: float = 0.5, size_mm: float | None = None
) -> tuple[GMap3, dict[str, Any]]:
    """Grow an excrescence on the free E (skin) faces of the cells ``path`` names; ``(map, facts)``.

    Refused, input unchanged: a path error (with a caret), a path naming no
    cell with a free face, height <= 0, segments outside 1..8, taper outside
    [0, 1).  Facts: path, cells (skin faces grown on), bumps, segments,
    height_mm, volume_added.
    """
    from ramure.gmap.kernel.embedding import grow

    p = path if isinstance(path, Path) else parse_path(path)
    if not (isinstance(height_mm, (int, float)) and math.isfinite(height_mm) and height_mm > 0):
        raise GMapError(f"excrescence height must be > 0 mm, got {height_mm}")
    if int(segments) != segments or not 1 <= segments <= 8:
        raise GMapError(f"excrescence segments must be 1..8, got {segments}")
    if not (math.isfinite(taper) and 0 <= taper < 1):
        raise GMapError(f"excrescence taper must be in [0, 1), got {taper}")
    cells = resolve_path(gm, p)
    scale = D.mm_per_unit(gm, size_mm)
    a3, vol = gm.alpha[3], gm.dart_volume.astype(np.int64)
    free = (a3 == np.arange(gm.n_darts)) & np.isin(vol, cells)
    if "excrescence" in gm.volume_data:  # on an excrescence, only its top (E) face grows
        from ramure.gmap.kernel.prism import FACE_E

        not_grown = gm.volume_data["excrescence"][vol] <= 0
        free &= not_grown | (gm.dart_data["face"] == FACE_E)
    free = np.flatnonzero(free)
    if free.size == 0:
        raise GMapError(
            f"excrescence: path {p!r} names {len(cells)} cell(s), none with a free face: an "
            "excrescence grows on the skin (the last radial layer, or an excrescence's top)"
        )
    side, _ = gm.orbit_ids("01")
    _, first = np.unique(side[free], return_index=True)
    anchors = free[first]
    out = gm.copy()
    if "excrescence" not in out.volume_data:
        out.add_volume_data("excrescence", np.int16, fill=0)
    before = float(D.cell_volumes(gm).sum())
    _, pos = out.vertex_positions()
    vid, _ = out.cells(0)
    group = out.volume_data["ring"][vol[anchors]].astype(np.int64) * 100_000 + out.volume_data["sector"][vol[anchors]].astype(
        np.int64
    )
    centre, normal = _bumps(_face_points(out, anchors, vid, pos), group, pos.mean(axis=0))
    height = height_mm / scale
    faces, grown, shrink, rise = anchors, [], 1.0, 0.0
    has_exocarp = bool(np.any(out.volume_data["tissue"] == CODES["exocarp"]))
    skin_tissue = CODES["exocarp"] if has_exocarp else CODES["pericarp"]
    for j in range(1, int(segments) + 1):
        base = out.dart_volume[faces].astype(np.int64)
        vd = out.volume_data
        tissue = vd["tissue"][base]
        tissue = np.where(tissue == CODES["columella"], skin_tissue, tissue)  # a mucron on the axis is skin
        new = grow(
            out,
            faces,
            4,
            height / segments,
            label="X",
            order=1,
            ring=vd["ring"][base],
            sector=vd["sector"][base],
            tissue=tissue,
            excrescence=j,
        )
        _glue_bump(out, new, group)
        step_shrink, step_rise = 1 - taper * j / segments, height * j / segments
        _place(out, new, group, centre + rise * normal, normal, step_shrink / shrink, step_rise - rise)
        shrink, rise = step_shrink, step_rise
        grown.append(new)
        faces = np.asarray(out.prism_face(_first_darts(out, new), 4, "E"))
    after = float(D.cell_volumes(out).sum())
    if np.any(D.cell_volumes(out) <= 0):
        raise GMapError("excrescence: a grown cell turned inside out; use a smaller taper or height")
    return out, {
        "kind": "excrescence",
        "path": repr(p),
        "cells": int(len(anchors)),
        "bumps": int(len(np.unique(group))),
        "segments": int(segments),
        "height_mm": float(height_mm),
        "volume_before": before,
        "volume_after": after,
        "volume_added": after - before,
        "volumes": [int(v) for v in np.concatenate(grown)],
    }


def _first_darts(gm, volumes):
    first = np.full(gm.n_volumes, gm.n_darts, np.int64)
    np.minimum.at(first, gm.dart_volume.astype(np.int64), np.arange(gm.n_darts))
    return first[np.asarray(volumes, np.int64)]


def _face_points(gm, anchors, vid, pos):
    """(faces, 4, 3) corner positions of the quad faces at ``anchors`` (walk order)."""
    walk, length = gm.face_walk(anchors)
    if np.any(length != 8):
        raise GMapError("excrescence: the skin faces named are not quads (subdivide the fruit by volume)")
    return pos[vid[walk[:, 0::2]]]


def _bumps(base_pos, group, middle):
    """Per group: the centre of its faces and their mean normal, pointing away from ``middle``."""
    keys, inv = np.unique(group, return_inverse=True)
    c = base_pos.mean(axis=1)
    n = np.cross(base_pos[:, 2] - base_pos[:, 0], base_pos[:, 3] - base_pos[:, 1])
    centre = np.stack([np.bincount(inv, c[:, j]) for j in range(3)], 1) / np.bincount(inv)[:, None]
    normal = np.stack([np.bincount(inv, n[:, j]) for j in range(3)], 1)
    normal = normal / np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    outward = np.einsum("ij,ij->i", normal, centre - middle) >= 0
    return centre, np.where(outward[:, None], normal, -normal)


def _glue_bump(gm, new, group) -> None:
    """Glue the lateral faces of new prisms of one bump that stand on a shared base edge."""
    first = _first_darts(gm, new)
    vid, _ = gm.cells(0)
    keys, inv = np.unique(group, return_inverse=True)
    rows = []
    for k in range(1, 5):
        d = gm.prism_face(first, 4, f"C{k}")  # base corner k-1, towards corner k
        u, w = vid[d], vid[gm.alpha[0][d]]
        rows.append((np.minimum(u, w), np.maximum(u, w), inv, d))
    lo = np.concatenate([r[0] for r in rows])
    hi = np.concatenate([r[1] for r in rows])
    g = np.concatenate([r[2] for r in rows])
    d = np.concatenate([r[3] for r in rows])
    key = (g * (int(vid.max()) + 1) + lo) * (int(vid.max()) + 1) + hi
    order = np.argsort(key, kind="stable")
    ks = key[order]
    pair = np.flatnonzero(ks[1:] == ks[:-1])
    if pair.size:
        gm.identify(d[order[pair]], d[order[pair + 1]])


def _place(gm, new, group, centre, normal, ratio, rise) -> None:
    """Place the new prisms: base corners on their support, tops narrowed by ``ratio`` towards
    their bump's (base) centre and raised by ``rise`` along its normal."""
    from ramure.gmap.kernel.prism import FACE_O

    _, inv = np.unique(group, return_inverse=True)
    n = 4
    first = _first_darts(gm, new)
    darts = first[:, None] + np.arange(12 * n)[None, :]
    prism = np.broadcast_to(np.arange(len(first))[:, None], darts.shape)
    vc = gm.dart_data["vcorner"][darts].astype(np.int64)
    a3 = gm.alpha[3]
    sewn = (gm.dart_data["face"][darts] == FACE_O) & (a3[darts] != darts)
    base_pos = np.zeros((len(first), n, 3))
    base_pos[prism[sewn], vc[sewn]] = gm.points[a3[darts[sewn]]]
    base = vc < n
    gm.points[darts[base]] = base_pos[prism[base], vc[base]]
    top = ~base
    b = base_pos[prism[top], vc[top] - n]
    g = inv[prism[top]]
    gm.points[darts[top]] = b + (ratio - 1.0) * (b - centre[g]) + rise * normal[g]
    gm.corners[darts.ravel()] = gm.points[darts.ravel()]
    gm.dart_data["radial"][darts.ravel()] = 1.0
