"""Fruit defects on a volumetric fruit (Bohl 2015, ch. 3): shrinkage, rot, hail and the grade.

Every defect is a pure function ``GMap3 -> (GMap3, facts)``: the input map is
copied, never edited; bad input raises :class:`~ramure.gmap.errors.GMapError`
(a ``RamureError``) before anything is built.  Only vertex positions and the
``transpiration`` volume column change, so dart and volume ids stay those of
the input (facts refer to them).

Choices where the thesis and the spec leave things open:

* **Units.** Lengths given in millimetres are converted with
  :func:`mm_per_unit`: the fruit's largest bounding-box extent is ``size_mm``
  (default :data:`DEFAULT_SIZE_MM`, a 65 mm tomato).
* **Transpiration K** is a volume column ``transpiration`` created on first use
  from :data:`TRANSPIRATION` by tissue (seeds 0, every other tissue 1).
* **Shrinkage** shrinks *rest edge vectors*: every edge's rest vector is its
  current vector times the mean factor ``1 - rate K`` of its cells, and the
  fruit is re-embedded as the least-squares fit of all rest vectors (a sparse
  Laplacian solve, centroid kept).  Uniform K is then an exact homothety
  (volume x (1 - r)^3); edges weigh ``1 / (0.01 + K)``, so cells with K = 0
  (seeds) are stiff and keep their shape while their neighbours shrink.  The kernel's hierarchical ``reframe``
  rewrites template corners and does not apply to subdivided fruit, hence this
  re-embedding.  ``rate_kind="edge"`` (default, the thesis's "10 %" = 10 % of
  every edge, 27 % of the volume) or ``"volume"`` (the rate is the lost volume
  fraction of a K = 1 cell).
* **Rot** multiplies K on rings 1, 2, 3 of graph distance (volume adjacency by
  vertex) around a skin vertex: ring 1 = the cells at the vertex.
* **Hail** pushes a skin vertex inward along its *radial chain* (the chain of
  interior edges most aligned with the inward direction); the chain vertices
  between the skin and the first vertex touching a stop-tissue cell are
  compressed towards that vertex, which never moves, so stop cells keep all
  their vertices.  A crater deeper than :data:`HAIL_MAX_FRACTION` of that span
  stops there and widens instead: the skin neighbours are pushed by half the
  crater depth.  Craters are applied one after another; each crater's volume
  is the fruit's volume before it minus after it, so they add up to the
  volume lost.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph
from scipy.sparse.linalg import splu

from ramure.gmap import incidence as _incidence
from ramure.gmap.errors import GMapError
from ramure.gmap.map3 import GMap3
from ramure.gmap.tissue import CODES, TISSUES

#: A fruit is this many millimetres across (largest bounding-box extent) unless told.
DEFAULT_SIZE_MM = 65.0
#: Default transpiration rate K per tissue name (seeds do not dry).
TRANSPIRATION = {name: (0.0 if name == "seed" else 1.0) for name in TISSUES}
#: A cell's edges weigh ``1 / (STIFFNESS_FLOOR + K)`` in the re-embedding: cells that
#: do not dry (seeds, K = 0) are stiff and keep their shape among shrinking flesh.
STIFFNESS_FLOOR = 0.01
#: Rot multipliers on rings 1, 2, 3 (thesis rule 3.6).
ROT_COEFFICIENTS = (2.5, 2.0, 1.5)
#: A hail crater may use at most this fraction of the span down to the stop tissue.
HAIL_MAX_FRACTION = 0.7
#: OECD/UNECE tomato rule: a marketable crack is at most this long (mm).
MAX_CRACK_MM = 30.0


# ---------------------------------------------------------------- geometry helpers
def mm_per_unit(gm: GMap3, size_mm: float | None = None) -> float:
    """Millimetres per model unit when the fruit's largest extent is ``size_mm``."""
    size = DEFAULT_SIZE_MM if size_mm is None else size_mm
    if not (isinstance(size, (int, float)) and math.isfinite(size) and size > 0):
        raise GMapError(f"fruit size must be a finite number of millimetres > 0, got {size_mm!r}")
    _, pos = gm.vertex_positions()
    extent = float((pos.max(axis=0) - pos.min(axis=0)).max())
    if extent <= 0:
        raise GMapError("the fruit has no extent; cannot convert millimetres")
    return float(size) / extent


def orientation(gm: GMap3) -> np.ndarray:
    """+1/-1 per dart: a sign flipped by every alpha_i inside a volume, chosen so the volumes are positive."""
    n = gm.n_darts
    a = gm.alpha
    even = [a[0][a[1]], a[1][a[2]], a[0][a[2]]]          # the even words generate the rotation orbits
    rows = np.concatenate([np.arange(n)] * 3)
    graph = sparse.csr_matrix((np.ones(3 * n, bool), (rows, np.concatenate(even))), shape=(n, n))
    _, comp = csgraph.connected_components(graph, directed=False)
    vol = gm.dart_volume.astype(np.int64)
    first = np.full(gm.n_volumes, n, np.int64)
    np.minimum.at(first, vol, np.arange(n))
    sign = np.where(comp == comp[first[vol]], 1.0, -1.0)
    raw = _signed_volumes(gm, sign)
    flip = np.where(raw < 0, -1.0, 1.0)
    return sign * flip[vol]


def _signed_volumes(gm, sign, darts=None):
    """Signed cell volumes from the darts ``darts`` (all by default; pass whole volumes).

    A closed cell's volume does not depend on the fan's apex, so the apex is
    the mean of the cell's dart points (cheap, and close to the cell).
    """
    pts = gm.points
    a0 = gm.alpha[0]
    vol = gm.dart_volume.astype(np.int64)
    fid, nf = gm.orbit_ids("01")
    nv = gm.n_volumes
    d = np.arange(gm.n_darts) if darts is None else darts
    p, f, v = pts[d], fid[d], vol[d]
    count_f = np.bincount(f, minlength=nf)
    fc = np.stack([np.bincount(f, p[:, j], minlength=nf) for j in range(3)], 1) / np.maximum(count_f, 1)[:, None]
    count_v = np.bincount(v, minlength=nv)
    vc = np.stack([np.bincount(v, p[:, j], minlength=nv) for j in range(3)], 1) / np.maximum(count_v, 1)[:, None]
    c = vc[v]
    det = np.einsum("ij,ij->i", p - c, np.cross(pts[a0[d]] - c, fc[f] - c))
    return np.bincount(v, sign[d] * det, minlength=nv) / 12.0


def cell_volumes(gm: GMap3, sign: np.ndarray | None = None) -> np.ndarray:
    """Signed volume of every cell (faces fanned from their centroid).

    ``sign`` is an :func:`orientation` of this map or of the map it was moved
    from (dart ids unchanged): an inverted cell then comes out negative.
    """
    return _signed_volumes(gm, orientation(gm) if sign is None else sign)


def _transpiration(gm, rates=None):
    """The ``transpiration`` column (created from tissue defaults and ``rates`` by tissue name)."""
    vd = gm.volume_data
    table = dict(TRANSPIRATION)
    for name, k in (rates or {}).items():
        if name not in CODES:
            raise GMapError(f"unknown tissue {name!r} in transpiration rates; known: {', '.join(TISSUES)}")
        if not (math.isfinite(k) and k >= 0):
            raise GMapError(f"transpiration rate of {name} must be >= 0, got {k}")
        table[name] = float(k)
    by_code = np.array([table[name] for name in TISSUES])
    if "transpiration" not in vd:
        gm.add_volume_attribute("transpiration", np.float64, 1.0)
        vd = gm.volume_data
        vd["transpiration"][:] = by_code[vd["tissue"].astype(np.int64)]
    elif rates:
        tissue = vd["tissue"].astype(np.int64)
        for name in rates:
            vd["transpiration"][tissue == CODES[name]] = table[name]
    return vd["transpiration"]


def _skin_vertices(gm):
    vid, _ = gm.cells(0)
    free = gm.alpha[3] == np.arange(gm.n_darts)
    return np.unique(vid[free])


def _first_darts(gm):
    vid, nv = gm.cells(0)
    first = np.full(nv, gm.n_darts, np.int64)
    np.minimum.at(first, vid, np.arange(gm.n_darts))
    return first


def _edges(gm):
    """Unique vertex pairs (u < w) of the edges, and the edge of every dart."""
    vid, nv = gm.cells(0)
    u, w = vid.astype(np.int64), vid[gm.alpha[0]].astype(np.int64)
    key = np.minimum(u, w) * nv + np.maximum(u, w)
    uniq, edge_of_dart = np.unique(key, return_inverse=True)
    return uniq // nv, uniq % nv, edge_of_dart


# ---------------------------------------------------------------- shrinkage
def shrink(gm: GMap3, rate: float = 0.1, steps: int = 1, rates: dict | None = None,
           rate_kind: str = "edge") -> tuple[GMap3, dict]:
    """Shrink a fruit by transpiration: every step, each cell's rest edges scale by ``1 - rate K``.

    ``rates`` overrides K by tissue name (e.g. ``{"seed": 0, "exocarp": 1.5}``);
    otherwise the ``transpiration`` column (see :func:`rot`) or the tissue
    defaults are used.  Refused: rate outside [0, 1), steps < 1, any
    ``rate K >= 1``, an unknown rate kind.  Facts: volume before and after,
    volume lost, steps.
    """
    if rate_kind not in ("edge", "volume"):
        raise GMapError(f"rate_kind must be 'edge' or 'volume', got {rate_kind!r}")
    if not (math.isfinite(rate) and 0 <= rate < 1):
        raise GMapError(f"shrink rate must be in [0, 1), got {rate}")
    if int(steps) != steps or steps < 1:
        raise GMapError(f"shrink steps must be a whole number >= 1, got {steps}")
    edge_rate = rate if rate_kind == "edge" else 1.0 - (1.0 - rate) ** (1.0 / 3.0)
    out = gm.copy()
    k = _transpiration(out, rates)
    worst = float(k.max()) if k.size else 0.0
    if edge_rate * worst >= 1:
        raise GMapError(f"shrink: rate x K must stay below 1 (edge rate {edge_rate:g} x K {worst:g} "
                        f"= {edge_rate * worst:g})")
    sign = orientation(out)
    before = float(_signed_volumes(out, sign).sum())
    factor = 1.0 - edge_rate * k
    stiffness = 1.0 / (STIFFNESS_FLOOR + k)
    for _ in range(int(steps)):
        _reembed(out, factor, stiffness)
    after = _signed_volumes(out, sign)
    if np.any(after <= 0):
        raise GMapError("shrink: a cell turned inside out; lower the rate")
    total = float(after.sum())
    return out, {"kind": "shrink", "rate": rate, "rate_kind": rate_kind, "edge_rate": edge_rate,
                 "steps": int(steps), "volume_before": before, "volume_after": total,
                 "volume_lost": before - total, "volume_kept": total / before}


def _reembed(gm, cell_factor, stiffness):
    """Weighted least-squares fit of every edge to its rest vector (current vector x mean cell factor).

    Each cell pulls each of its edges towards its own factor with its own
    ``stiffness``: an edge's rest factor is the stiffness-weighted mean of its
    cells' factors and its weight their summed stiffness.
    """
    vid, nv = gm.cells(0)
    _, pos = gm.vertex_positions()
    u, w, edge_of_dart = _edges(gm)
    ne = len(u)
    vol = gm.dart_volume.astype(np.int64)
    wt = np.bincount(edge_of_dart, stiffness[vol], minlength=ne)
    f = np.bincount(edge_of_dart, stiffness[vol] * cell_factor[vol], minlength=ne) / wt
    centre = pos.mean(axis=0)
    q = pos - centre
    rest = f[:, None] * (q[u] - q[w])
    inc = sparse.csr_matrix((np.r_[np.ones(ne), -np.ones(ne)],
                             (np.r_[np.arange(ne), np.arange(ne)], np.r_[u, w])), shape=(ne, nv))
    lap = (inc.T @ sparse.diags(wt) @ inc).tocsr()
    eps = 1e-9 * float(lap.diagonal().mean())
    mean_f = float(np.average(f, weights=wt))
    lap = lap + eps * sparse.identity(nv, format="csr")
    rhs = inc.T @ (wt[:, None] * rest) + eps * mean_f * q
    lu = splu(lap.tocsc(), permc_spec="MMD_AT_PLUS_A")
    new = lu.solve(rhs)
    _set_vertices(gm, new + centre)


def _set_vertices(gm, pos):
    """Write every vertex position (points and default corners), as manual embedding."""
    vid, _ = gm.cells(0)
    gm.points[:] = pos[vid]
    gm.corners[:] = pos[vid]


# ---------------------------------------------------------------- rot
def rot(gm: GMap3, vertex: int | None = None, coefficients=ROT_COEFFICIENTS, seed: int = 0
        ) -> tuple[GMap3, dict]:
    """Multiply transpiration K on rings 1, 2, 3 (graph distance by vertex) around a skin vertex.

    ``vertex`` is a vertex id of ``gm.cells(0)`` on the skin; ``None`` picks one
    at random from ``seed``.  Ring 1 = the cells at the vertex, ring k+1 = cells
    sharing a vertex with ring k and in no earlier ring.  The geometry moves
    when the fruit is then shrunk (:func:`shrink`).  Refused: a negative
    coefficient, a vertex that is not on the skin.
    """
    coef = [float(c) for c in coefficients]
    if not coef or any(not (math.isfinite(c) and c >= 0) for c in coef):
        raise GMapError(f"rot coefficients must be finite and >= 0, got {list(coefficients)}")
    skin = _skin_vertices(gm)
    if vertex is None:
        vertex = int(np.random.default_rng(seed).choice(skin))
    if int(vertex) not in set(skin.tolist()):
        raise GMapError(f"rot: vertex {vertex} is not a skin vertex (the fruit has {len(skin)} of them)")
    out = gm.copy()
    k = _transpiration(out)
    rings = rot_rings(out, int(vertex), len(coef))
    for ring, c in zip(rings, coef):
        k[ring] *= c
    return out, {"kind": "rot", "vertex": int(vertex), "coefficients": coef,
                 "ring_cells": [int(len(r)) for r in rings]}


def rot_rings(gm: GMap3, vertex: int, count: int = 3) -> list[np.ndarray]:
    """Volume ids at graph distance 1 .. ``count`` (adjacency by vertex) around ``vertex``."""
    inc = _incidence.vertex_volumes(gm).tocsr()
    by_volume = inc.T.tocsr()                       # volume -> its vertices
    seen = np.zeros(gm.n_volumes, bool)
    ring = np.unique(inc.indices[inc.indptr[vertex]:inc.indptr[vertex + 1]])
    rings = []
    for _ in range(count):
        seen[ring] = True
        rings.append(ring)
        verts = np.unique(by_volume[ring].indices)
        near = np.unique(inc[verts].indices)
        ring = near[~seen[near]]
    return rings


# ---------------------------------------------------------------- hail
def _vertex_graph(gm):
    u, w, _ = _edges(gm)
    _, nv = gm.cells(0)
    g = sparse.csr_matrix((np.ones(2 * len(u), bool), (np.r_[u, w], np.r_[w, u])), shape=(nv, nv))
    return g


def _radial_chain(graph, pos, on_skin, stop_vertex, v, limit=256):
    """Vertices from skin vertex ``v`` inward until one touching the stop tissue (included)."""
    nb = graph.indices[graph.indptr[v]:graph.indptr[v + 1]]
    inner = nb[~on_skin[nb]]
    if inner.size == 0:
        return None
    direction = (pos[inner] - pos[v]).mean(axis=0)
    if np.linalg.norm(direction) == 0:
        direction = pos[inner[0]] - pos[v]
    chain = [v]
    seen = {v}
    while not stop_vertex[chain[-1]] and len(chain) < limit:
        cur = chain[-1]
        nb = graph.indices[graph.indptr[cur]:graph.indptr[cur + 1]]
        nb = np.array([x for x in nb if x not in seen and not on_skin[x]], np.int64)
        if nb.size == 0:
            break
        step = pos[nb] - pos[cur]
        unit = step / np.linalg.norm(step, axis=1, keepdims=True)
        d = direction / np.linalg.norm(direction)
        align = unit @ d
        best = int(np.argmax(align))
        if align[best] < 0.7:
            break
        chain.append(int(nb[best]))
        seen.add(int(nb[best]))
    return np.array(chain, np.int64)


def _push(pos, chain, depth):
    """Compress ``chain`` (skin first) so the skin moves ``depth`` along it; its last vertex stays."""
    seg = np.linalg.norm(np.diff(pos[chain], axis=0), axis=1)
    t = np.r_[0.0, np.cumsum(seg)]
    span = t[-1]
    new_t = depth + t[:-1] * (span - depth) / span
    out = {}
    for i, s in enumerate(new_t):
        j = min(int(np.searchsorted(t, s, side="right")) - 1, len(seg) - 1)
        frac = (s - t[j]) / seg[j] if seg[j] > 0 else 0.0
        out[int(chain[i])] = pos[chain[j]] + frac * (pos[chain[j + 1]] - pos[chain[j]])
    return out


def hail(gm: GMap3, vertices=None, depth_mm=(2.0, 6.0), count: int | None = None, stop: str = "endocarp",
         size_mm: float | None = None, seed: int = 0) -> tuple[GMap3, dict]:
    """Hail craters: targeted at skin ``vertices`` or ``count`` random distinct skin vertices.

    ``depth_mm`` is one depth or a ``(low, high)`` range drawn uniformly per
    crater (millimetres on a fruit ``size_mm`` across).  A crater never moves
    a vertex of a ``stop`` cell: it stops at :data:`HAIL_MAX_FRACTION` of the
    span to that tissue and widens instead (neighbouring skin vertices pushed
    by half its depth).  Facts per crater: vertex, requested and actual depth
    (mm), widened, volume.  Refused: depth <= 0, count < 1 or above the skin
    vertices, an unknown stop tissue, a vertex not on the skin.
    """
    if stop not in CODES:
        raise GMapError(f"hail: unknown stop tissue {stop!r}; known: {', '.join(TISSUES)}")
    lo, hi = (depth_mm, depth_mm) if np.isscalar(depth_mm) else (float(depth_mm[0]), float(depth_mm[1]))
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi):
        raise GMapError(f"hail depth must be > 0 mm (a range low..high with low <= high), got {depth_mm}")
    if not np.any(gm.volume_data["tissue"] == CODES[stop]):
        raise GMapError(f"hail: this fruit has no {stop} cells to stop at; layered defects need a fruit "
                        "with tissues (--subdivide volume:2 builds exocarp, mesocarp, endocarp, locules)")
    scale = mm_per_unit(gm, size_mm)
    skin = hail_sites(gm)
    rng = np.random.default_rng(seed)
    if vertices is None:
        n = 1 if count is None else count
        if int(n) != n or n < 1:
            raise GMapError(f"hail count must be a whole number >= 1, got {count}")
        if n > len(skin):
            raise GMapError(f"hail count {n} is above the {len(skin)} skin vertices (with one inward edge) "
                            "of this fruit")
        vertices = rng.choice(skin, int(n), replace=False)
    vertices = np.atleast_1d(np.asarray(vertices, np.int64))
    if vertices.size == 0:
        raise GMapError("hail: no vertex to hit")
    bad = vertices[~np.isin(vertices, skin)]
    if bad.size:
        raise GMapError(f"hail: vertex {int(bad[0])} is not a skin vertex with one inward edge")
    if len(np.unique(vertices)) != len(vertices):
        raise GMapError("hail: the same vertex is hit twice")
    depths = rng.uniform(lo, hi, len(vertices)) if hi > lo else np.full(len(vertices), lo)
    out = gm.copy()
    sign = orientation(out)
    graph = _vertex_graph(out)
    _, nv = out.cells(0)
    on_skin = np.zeros(nv, bool)
    on_skin[skin] = True
    inc = _incidence.vertex_volumes(out).tocsr()
    tissue = out.volume_data["tissue"]
    stop_cells = ((tissue == CODES[stop]) | (tissue == CODES["columella"])).astype(np.int8)
    stop_vertex = (inc @ stop_cells) > 0
    _, pos = out.vertex_positions()
    volume = float(_signed_volumes(out, sign).sum())
    before = volume
    craters = []
    vid, _ = out.cells(0)
    order = np.argsort(vid, kind="stable")
    starts = np.searchsorted(vid[order], np.arange(len(pos) + 1))
    by_volume = np.argsort(out.dart_volume, kind="stable")
    vstarts = np.searchsorted(out.dart_volume[by_volume], np.arange(out.n_volumes + 1))
    for v, d_mm in zip(vertices.tolist(), depths.tolist()):   # one step per crater
        moves, actual, widened = _crater(graph, pos, on_skin, stop_vertex, v, d_mm / scale)
        moved = np.array(sorted(moves), np.int64)
        darts = np.concatenate([order[starts[x]:starts[x + 1]] for x in moved])
        cells = np.unique(out.dart_volume[darts])
        local = np.concatenate([by_volume[vstarts[c]:vstarts[c + 1]] for c in cells])
        old_vol = _signed_volumes(out, sign, local)[cells]
        pos[moved] = np.array([moves[x] for x in moved.tolist()])
        out.points[darts] = pos[vid[darts]]
        out.corners[darts] = pos[vid[darts]]
        new_vol = _signed_volumes(out, sign, local)[cells]
        if np.any(new_vol <= 0):
            raise GMapError(f"hail: the crater at vertex {v} ({d_mm:.3g} mm) turns a cell inside out; "
                            "use shallower craters")
        lost = float(old_vol.sum() - new_vol.sum())
        craters.append({"vertex": int(v), "depth_mm": float(d_mm), "actual_depth_mm": actual * scale,
                        "widened": widened, "volume": lost, "moved": len(moves)})
        volume -= lost
    return out, {"kind": "hail", "count": len(craters), "stop": stop, "craters": craters,
                 "volume_before": before, "volume_after": volume, "volume_lost": before - volume}


def hail_sites(gm: GMap3) -> np.ndarray:
    """Skin vertices with exactly one interior edge (4-valent skin vertices of a subdivided fruit)."""
    skin = _skin_vertices(gm)
    _, nv = gm.cells(0)
    on_skin = np.zeros(nv, bool)
    on_skin[skin] = True
    g = _vertex_graph(gm).tocoo()
    inner = np.bincount(g.row[~on_skin[g.col]], minlength=nv)
    inc = _incidence.vertex_volumes(gm).tocsr()
    axis = (inc @ (gm.volume_data["tissue"] == CODES["columella"]).astype(np.int8)) > 0
    return skin[(inner[skin] == 1) & ~axis[skin]]


def _crater(graph, pos, on_skin, stop_vertex, v, depth):
    chain = _radial_chain(graph, pos, on_skin, stop_vertex, v)
    if chain is None or len(chain) < 2:
        raise GMapError(f"hail: skin vertex {v} has no inward edge")
    span = float(np.linalg.norm(np.diff(pos[chain], axis=0), axis=1).sum())
    cap = HAIL_MAX_FRACTION * span
    actual, widened = min(depth, cap), depth > cap
    moves = _push(pos, chain, actual)
    if widened:
        nb = graph.indices[graph.indptr[v]:graph.indptr[v + 1]]
        for x in nb[on_skin[nb]].tolist():
            c = _radial_chain(graph, pos, on_skin, stop_vertex, int(x))
            if c is None or len(c) < 2:
                continue
            s = float(np.linalg.norm(np.diff(pos[c], axis=0), axis=1).sum())
            moves.update({k: p for k, p in _push(pos, c, min(0.5 * actual, 0.5 * s)).items()
                          if k not in moves})
    return moves, actual, widened


# ---------------------------------------------------------------- grade
def grade(facts: list[dict]) -> dict:
    """The OECD/UNECE FFV-36 rule for tomatoes on defect facts (lengths in mm).

    Marketable unless: a crack longer than :data:`MAX_CRACK_MM`, a crack that
    is not shallow (``depth_layers > 1``), a crack not fully healed
    (``healed_layers < depth_layers``), any hail crater, or rot (produce
    affected by rotting is excluded by the minimum requirements).  Shrinkage
    alone is reported, not graded.  Returns ``{"marketable", "grade",
    "reasons"}`` with one sentence per failed condition.
    """
    reasons = []
    for f in facts:
        kind = f.get("kind")
        if kind == "crack":
            length = float(f["length_mm"])
            depth, healed = int(f.get("depth_layers", 1)), int(f.get("healed_layers", 0))
            if length > MAX_CRACK_MM:
                reasons.append(f"crack {length:.1f} mm long, more than {MAX_CRACK_MM:g} mm")
            if depth > 1:
                reasons.append(f"crack {depth} layers deep, not shallow")
            if healed < depth:
                reasons.append(f"crack not fully healed ({healed} of {depth} layers)")
        elif kind == "hail" and f.get("count", 0) > 0:
            reasons.append(f"{f['count']} hail crater(s): any hail damage is excluded")
        elif kind == "rot":
            reasons.append("rot: produce affected by rotting is excluded")
    return {"marketable": not reasons, "grade": "marketable" if not reasons else "rejected",
            "reasons": reasons}


# ---------------------------------------------------------------- text specs (CLI, notebook, desktop)
#: Defect kinds and the options each accepts (``kind:name=value,...``).
DEFECT_OPTIONS = {
    "shrink": ("rate", "steps", "kind"),
    "rot": ("vertex", "coefficients", "rate", "steps"),
    "hail": ("count", "depth_mm", "stop", "vertex"),
    "crack": ("kind", "sector", "rings", "depth", "width_mm", "healed"),
}


def parse_defect(spec: str) -> tuple[str, dict]:
    """``"hail:count=5,depth_mm=2..6,stop=endocarp"`` -> ``("hail", {...})``, checked.

    Ranges are ``low..high``, ring spans ``3-6``; rot coefficients are ``2.5/2/1.5``.

    >>> parse_defect("hail:count=5,depth_mm=2..6")
    ('hail', {'count': 5, 'depth_mm': (2.0, 6.0)})
    """
    kind, _, rest = spec.partition(":")
    kind = kind.strip().lower()
    if kind not in DEFECT_OPTIONS:
        raise GMapError(f"unknown defect {kind!r} in '{spec}'; known: {', '.join(DEFECT_OPTIONS)}")
    opts = {}
    for item in filter(None, (x.strip() for x in rest.split(","))):
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or name not in DEFECT_OPTIONS[kind]:
            raise GMapError(f"defect {kind}: expected NAME=VALUE with NAME in "
                            f"{', '.join(DEFECT_OPTIONS[kind])}, got '{item}'")
        opts[name] = _option_value(kind, name, value.strip())
    return kind, opts


def _option_value(kind, name, value):
    try:
        if name == "rings":
            lo, sep, hi = value.partition("-")
            return (int(lo), int(hi if sep else lo))
        if name in ("steps", "count", "vertex", "sector", "depth", "healed"):
            number = float(value)
            if number != int(number):
                raise ValueError
            return int(number)
        if name == "depth_mm":
            lo, sep, hi = value.partition("..")
            return (float(lo), float(hi)) if sep else float(value)
        if name == "coefficients":
            return tuple(float(x) for x in value.split("/"))
        if name in ("stop", "kind"):
            return value
        return float(value)
    except ValueError:
        raise GMapError(f"defect {kind}: {name}={value!r} is not a valid value") from None


def apply_defects(gm: GMap3, specs, size_mm: float | None = None, seed: int = 0
                  ) -> tuple[GMap3, dict]:
    """Apply defect specs in order; returns the map and the facts.

    Facts: ``defects`` (one record per defect), ``volume_before``,
    ``volume_after``, ``volume_lost`` (fraction too), ``size_mm`` and
    ``grade`` (:func:`grade`).  Every spec is parsed before anything is
    applied; ``seed`` is offset per defect so two hail specs differ.
    """
    parsed = [parse_defect(s) if isinstance(s, str) else s for s in specs]
    mm_per_unit(gm, size_mm)
    sign = orientation(gm)
    before = float(_signed_volumes(gm, sign).sum())
    out, records = gm, []
    for i, (kind, opts) in enumerate(parsed):
        out, facts = _apply_one(out, kind, dict(opts), size_mm, seed + 1000 * i)
        records.append(facts)
    after = float(_signed_volumes(out, sign).sum())
    return out, {"defects": records, "size_mm": DEFAULT_SIZE_MM if size_mm is None else float(size_mm),
                 "volume_before": before, "volume_after": after, "volume_lost": before - after,
                 "volume_lost_fraction": (before - after) / before, "grade": grade(records)}


def _apply_one(gm, kind, opts, size_mm, seed):
    if kind == "shrink":
        return shrink(gm, opts.get("rate", 0.1), opts.get("steps", 1), rate_kind=opts.get("kind", "edge"))
    if kind == "rot":
        out, facts = rot(gm, opts.get("vertex"), opts.get("coefficients", ROT_COEFFICIENTS), seed=seed)
        if opts.get("rate", 0.0) > 0:
            out, dried = shrink(out, opts["rate"], opts.get("steps", 1))
            facts.update(rate=dried["rate"], steps=dried["steps"], volume_lost=dried["volume_lost"])
        return out, facts
    if kind == "crack":
        return crack(gm, opts.get("kind", "longitudinal"), opts.get("sector", 0), opts.get("rings", (3, 6)),
                     opts.get("depth", 1), opts.get("width_mm", 1.0), opts.get("healed", 0), size_mm)
    vertices = None if "vertex" not in opts else [opts["vertex"]]
    return hail(gm, vertices, opts.get("depth_mm", (2.0, 6.0)), opts.get("count"),
                opts.get("stop", "endocarp"), size_mm, seed)


# ---------------------------------------------------------------- cracks
CRACK_KINDS = ("longitudinal", "transverse", "concentric")
#: An opening moves a vertex at most this fraction of its shortest edge leaving the crack
#: plane (the neighbouring cell's size across the crack).
CRACK_CAP = 0.3


def radial_layers(gm: GMap3) -> tuple[int, np.ndarray]:
    """``(layers, layer per volume)``: radial layers of a volume-subdivided fruit, 0 = skin."""
    vd = gm.volume_data
    branch = vd["order"] >= 1
    rho = gm.volume_means(gm.dart_data["radial"])
    if not branch.any():
        return 0, np.zeros(gm.n_volumes, np.int64)
    layers = int(round(1.0 / (2.0 * max(1.0 - rho[branch].max(), 1e-9))))
    layer = np.clip(np.floor((1.0 - rho) * max(layers, 1)).astype(np.int64), 0, max(layers - 1, 0))
    return layers, np.where(branch, layer, -1)


def crack(gm: GMap3, kind: str = "longitudinal", sector: int = 0, rings=(3, 6), depth: int = 1,
          width_mm: float = 1.0, healed: int = 0, size_mm: float | None = None) -> tuple[GMap3, dict]:
    """Open a crack along inter-branch faces: unsew the strip, let its inner vertices split, open it.

    ``longitudinal``: between sectors ``sector`` and ``sector + 1`` over rings
    ``rings = (first, last)``; ``transverse``: between ring ``rings[0]`` and
    the next one over sectors ``sector .. sector + span`` where span is
    ``rings[1] - rings[0]`` (a short arc); ``concentric``: between ring
    ``rings[0]`` and the next one all around.  ``depth`` radial layers from
    the skin are opened; the strip's bottom and end edges stay sewn (the tips
    stay shared), so the crack is a notch.  Each split vertex moves
    ``width_mm / 2`` off the crack along the strip normal, capped at
    :data:`CRACK_CAP` of its shortest edge leaving the crack plane.  The faces exposed in the first
    ``healed`` layers get the dart attribute ``healed = 1`` (rule copy, kept by
    later subdivision).  Refused: an unknown kind, depth < 1 or deeper than
    the pericarp, width <= 0, healed outside 0..depth, rings or sector out of
    range or reversed, a fruit without radial layers.
    """
    if kind not in CRACK_KINDS:
        raise GMapError(f"crack kind must be one of {', '.join(CRACK_KINDS)}, got {kind!r}")
    layers, layer = radial_layers(gm)
    if layers < 2:
        raise GMapError("crack: a layered defect needs a volume-subdivided fruit (needs --subdivide volume:N)")
    if int(depth) != depth or not 1 <= depth < layers:
        raise GMapError(f"crack depth must be 1..{layers - 1} layers (the pericarp has {layers}), got {depth}")
    if not (math.isfinite(width_mm) and width_mm > 0):
        raise GMapError(f"crack width must be > 0 mm, got {width_mm}")
    if int(healed) != healed or not 0 <= healed <= depth:
        raise GMapError(f"crack healed layers must be in 0..depth ({depth}), got {healed}")
    vd = gm.volume_data
    ring, sec = vd["ring"].astype(np.int64), vd["sector"].astype(np.int64)
    n_rings, ph = int(ring.max()) + 1, int(sec.max()) + 1
    r0, r1 = int(rings[0]), int(rings[1])
    if not (0 <= r0 <= r1 < n_rings) or not 0 <= sector < ph:
        raise GMapError(f"crack: rings {r0}-{r1} and sector {sector} must lie in rings 0..{n_rings - 1} "
                        f"(first <= last) and sectors 0..{ph - 1}")
    if kind != "longitudinal" and r0 + 1 >= n_rings:
        raise GMapError(f"crack: a {kind} crack needs a ring after ring {r0}")
    scale = mm_per_unit(gm, size_mm)
    shallow = (layer >= 0) & (layer < depth)
    if kind == "longitudinal":
        side_a = shallow & (sec == sector) & (ring >= r0) & (ring <= r1)
        side_b = shallow & (sec == (sector + 1) % ph) & (ring >= r0) & (ring <= r1)
    else:
        if kind == "concentric":
            arc = np.ones(gm.n_volumes, bool)
        else:
            arc = np.isin(sec, (sector + np.arange(r1 - r0 + 1)) % ph)
        side_a = shallow & (ring == r0) & arc
        side_b = shallow & (ring == r0 + 1) & arc
    out = gm.copy()
    n = out.n_darts
    a3 = out.alpha[3]
    vol = out.dart_volume.astype(np.int64)
    strip = np.flatnonzero((a3 != np.arange(n)) & side_a[vol] & side_b[vol[a3]])
    if strip.size == 0:
        raise GMapError("crack: no sewn faces between the chosen cells")
    sign = orientation(out)
    before = float(_signed_volumes(out, sign).sum())
    vid0, nv0 = out.cells(0)
    _, pos0 = out.vertex_positions()
    length = _strip_skin_length(out, strip, pos0, vid0) * scale
    partner = a3[strip].copy()
    fid, _ = out.orbit_ids("01")
    _, first = np.unique(fid[strip], return_index=True)
    out.unsew3(strip[first])
    if "healed" not in out.dart_data:
        out.add_dart_attribute("healed", np.int8, rule="copy")
    exposed = np.r_[strip, partner]
    heal = exposed[layer[vol[exposed]] < healed]
    out.dart_data["healed"][heal] = 1
    vid, nv = out.cells(0)
    split = np.unique(vid[exposed])
    moved_count, opening = _open(out, exposed, side_a, pos0, vid0, vid, nv, 0.5 * width_mm / scale)
    after_cells = _signed_volumes(out, sign)
    if np.any(after_cells <= 0):
        raise GMapError("crack: opening turned a cell inside out; use a narrower crack")
    after = float(after_cells.sum())
    return out, {"kind": "crack", "crack_kind": kind, "sector": int(sector), "rings": [r0, r1],
                 "depth_layers": int(depth), "healed_layers": int(healed), "width_mm": float(width_mm),
                 "opening_mm": opening * scale, "length_mm": length, "faces": int(len(first)),
                 "duplicated_vertices": int(nv - nv0),
                 "opened_vertices": int(moved_count), "crack_vertices": int(len(split)),
                 "volume_before": before, "volume_after": after, "volume_lost": before - after}


def _strip_skin_length(gm, strip, pos, vid):
    """Length of the strip's edges on the skin (each edge once)."""
    a0, a3 = gm.alpha[0], gm.alpha[3]
    d = strip
    e_u, e_w = vid[d], vid[a0[d]]
    edge_ids, _ = gm.cells(1)
    free = a3 == np.arange(gm.n_darts)
    on_skin_edge = np.zeros(int(edge_ids.max()) + 1, bool)
    on_skin_edge[edge_ids[free]] = True
    keep = on_skin_edge[edge_ids[d]]
    edges, first = np.unique(edge_ids[d][keep], return_index=True)
    u, w = e_u[keep][first], e_w[keep][first]
    return float(np.linalg.norm(pos[u] - pos[w], axis=1).sum())


def _open(gm, exposed, side_a, pos0, vid0, vid, nv, half):
    """Move every split vertex of the crack off it (side A one way, side B the other)."""
    vol = gm.dart_volume.astype(np.int64)
    old_of_new = np.zeros(nv, np.int64)
    old_of_new[vid] = vid0
    copies = np.bincount(old_of_new, minlength=len(pos0))
    ex_new = np.unique(vid[exposed])
    split = ex_new[copies[old_of_new[ex_new]] > 1]
    if split.size == 0:
        return 0, 0.0
    ca = gm.volume_means(gm.points)
    # strip normal per split vertex: from side A cells' centroid towards side B
    a_darts = exposed[side_a[vol[exposed]]]
    b_darts = exposed[~side_a[vol[exposed]]]
    normal = np.zeros((nv, 3))
    for darts in (a_darts, b_darts):              # cell centre -> crack face, per side
        np.add.at(normal, vid[darts], gm.points[darts] - ca[vol[darts]])
    # the cells' size across the crack: shortest edge at each vertex leaving the crack plane
    _, pos = gm.vertex_positions()
    unit = normal / np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    u, w = vid, vid[gm.alpha[0]]
    vec = pos[w] - pos[u]
    elen = np.linalg.norm(vec, axis=1)
    across = np.abs(np.einsum("ij,ij->i", vec, unit[u])) > 0.5 * elen
    shortest = np.full(nv, np.inf)
    np.minimum.at(shortest, u[across], elen[across])
    new = pos.copy()
    nrm = unit[split]
    step = np.minimum(half, CRACK_CAP * shortest[split])
    # a vertex of side A moves into A (against its outward normal towards B): -normal
    new[split] = pos[split] - step[:, None] * nrm
    take = np.isin(vid, split)
    gm.points[take] = new[vid[take]]
    gm.corners[take] = new[vid[take]]
    return int(split.size), float(2.0 * step.max())
