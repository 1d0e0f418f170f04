"""Plain functions over :class:`ramure.app.model.Explorer` used by the desktop window (no Qt).

The window draws from a :class:`Snapshot`: an immutable copy of what it needs
of the explorer at one ``version`` (mesh, segment midpoints, constants,
status...), taken in the worker thread right after a change.  The helpers
below turn the model's answers into what the view draws (cell colours, the
selection's box edges, screen projections, the cut graph layout) and hold the
few rules that are the window's own (the range a constant's slider offers).

>>> import numpy as np
>>> constant_range(0.9), constant_range(-2.0), constant_range(0.0)
((0.0, 1.8), (-4.0, 0.0), (-1.0, 1.0))
>>> m = np.eye(4)
>>> project_to_display(m, np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 0.0]]), (200, 100)).tolist()
[[100.0, 50.0], [200.0, 100.0]]
"""

from __future__ import annotations

import os
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ramure.app.document import DEFINE_LINE, format_constant, text_with_constants  # noqa: F401 (the desktop's names)
from ramure.app.model import project_to_display  # noqa: F401 (shared with the notebook; the desktop's name)
from ramure.app.render import plant_colors

if TYPE_CHECKING:
    import pyvista as pv
    from ramure.app.model import Explorer
    from ramure.gmap.kernel.map3 import GMap3
    from ramure.lsys import GrammarError
    from ramure.lsys.regeneration.mincut import CutResult
    from ramure.lsys.regeneration.regen import RegenResult
    from ramure.lsys.history.tree import DerivationTree
    from ramure.lsys.interpretation.turtle import Skeleton

STRING_PREVIEW_MODULES = 5000  # the string dock shows at most this many modules
#: The cut-graph dock draws a cut of at most this many tree nodes.  A quarter of Honda n = 17
#: (32,626 leaves) cuts a graph of about 65,000: laying it out took seconds in the worker and
#: drawing it (half a million scene items) tens of seconds and gigabytes in the window.
CUT_GRAPH_MAX_NODES = 3000


@dataclass(frozen=True)
class Snapshot:
    """What the window shows of the explorer at one ``version``."""

    version: int
    mesh: pv.PolyData  # cell data leaf_id, segment, kind, order
    skeleton: Skeleton
    segment_leaf: np.ndarray  # (s,) history leaf of each segment
    text: str
    error: GrammarError | None  # the last one
    constants: dict  # current values (grammar #define plus edits)
    grammar_constants: dict  # the grammar's #define values (the constants panel's rows)
    n: int
    seed: int
    rho: float
    selection: tuple
    status: str
    can_undo: bool
    can_redo: bool
    last_result: RegenResult | None
    n_modules: int
    string_preview: str = ""
    cut_layout: GraphLayout | None = None  # the last regeneration's cut (None: no cut)
    path: str | os.PathLike | None = None
    edits: int = 0
    extra: dict = field(default_factory=dict)
    job: str = ""  # the job that took this snapshot ("grammar" when the editor's text made it)
    dirty: bool = False  # the plant differs from the file last saved or opened
    local_edits: int = 0  # regrows, prunes and fruit edits of parts (a grammar file cannot hold them)
    organ_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # leaf and fruit centres
    organ_leaves: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))  # their history leaves
    note: str | None = None  # why the last edit drew the same plant, in the model's words (or None)

    @property
    def midpoints(self) -> np.ndarray:
        """(s, 3) the segments' midpoints, computed when asked (a rectangle selection): not
        kept with every version (3 MB at 131k segments), about 1 ms to compute."""
        return self.skeleton.midpoints()


def take_snapshot(explorer: Explorer, previous: Snapshot | None = None, job: str = "") -> Snapshot:
    """A :class:`Snapshot` of ``explorer``; reuses ``previous``'s heavy parts if the version is the same."""
    session = explorer.session
    light: dict[str, Any] = dict(
        text=shown_text(explorer),
        error=explorer.error,
        constants=explorer.constants,
        grammar_constants=dict(explorer.lsystem.constants),
        n=session.n,
        seed=session.seed,
        rho=explorer.rho,
        selection=tuple(explorer.selection),
        status=status_line(explorer),
        can_undo=explorer.can_undo,
        can_redo=explorer.can_redo,
        dirty=explorer.dirty,
        local_edits=len(explorer.local_edits()),
        last_result=explorer.last_result,
        path=explorer.path,
        edits=len(session.edits),
        job=job,
        note=getattr(explorer, "note", None),
    )
    if previous is not None and previous.version == explorer.version:
        return Snapshot(**{**previous.__dict__, **light})
    skeleton = explorer.skeleton
    mesh = explorer.mesh
    result = explorer.last_result
    layout = (
        cut_graph_layout(result.cut, explorer.derivation.tree, result.roots, explorer.lsystem.symbols)
        if result is not None and result.cut is not None and drawable_cut(result.cut)
        else None
    )
    organs = skeleton.organs
    return Snapshot(
        version=explorer.version,
        mesh=mesh,
        skeleton=skeleton,
        organ_points=np.asarray(organs.position, float).reshape(-1, 3),
        organ_leaves=np.asarray(organs.leaf_id, np.int64),
        segment_leaf=np.asarray(skeleton.leaf_id),
        n_modules=len(explorer.derivation),
        string_preview=string_preview(explorer),
        cut_layout=layout,
        **light,
    )


def shown_text(explorer: Explorer) -> str:
    """The grammar text as the editor shows it: the ``n:``, ``#seed`` and ``#define`` lines carry
    the session's current values (a slider edit rewrites its line; undoing it puts the old value
    back): :meth:`~ramure.app.model.Explorer.document_text`, what Save writes."""
    return explorer.document_text()


def set_constants_from_text(explorer: Explorer, text: str) -> GrammarError | None:
    """Apply the ``#define`` values of ``text`` (same grammar otherwise) as constants edits.

    Returns the grammar error (nothing changed) or None.
    """
    from ramure.lsys import GrammarError, LSystem

    try:
        written = LSystem.from_text(text).constants
    except GrammarError as err:
        explorer.error = err
        return err
    explorer.error = None
    current = explorer.constants
    for name, value in written.items():
        if name in current and float(value) != float(current[name]):
            explorer.set_constant(name, value)
    return None


def status_line(explorer: Explorer) -> str:
    """The status bar's line, in the user's words: what the plant is and what the last edit did.

    >>> from types import SimpleNamespace as NS
    >>> r = NS(op="regrow", roots=np.array([4, 9]), removed=412, added=398, cut=object())
    >>> ex = NS(derivation=range(2100), skeleton=range(1023), selection=[5, 6], last_result=r)
    >>> status_line(ex)
    '1,023 branch segments (2,100 modules), 2 selected — last edit: regrew 2 parts of the plant (412 modules replaced by 398)'
    """
    base = f"{len(explorer.skeleton):,} branch segments ({len(explorer.derivation):,} modules)"
    if explorer.selection:
        base += f", {len(explorer.selection):,} selected"
    r = explorer.last_result
    if r is None:
        return base
    summary = getattr(explorer, "summary", None)  # the model's words: share changed, climb (issue 34)
    if isinstance(summary, str) and r.op in ("regrow", "prune"):
        note = getattr(explorer, "note", None)
        return f"{base} — last edit: {summary}" + (f" — {note}" if isinstance(note, str) and note else "")
    warning = getattr(r, "warning", None)  # e.g. "this selection regrows from the axiom: ..."
    return f"{base} — last edit: {edit_words(r)}" + (f" — {warning}" if isinstance(warning, str) else "")


def edit_words(result: RegenResult) -> str:
    """What one edit did, for people: "regrew 2 parts of the plant (412 modules replaced by 398)"."""
    count = len(result.roots)
    parts = f"{count} part{'s' if count != 1 else ''} of the plant"
    if result.op == "fruit":
        return f"{count} fruit regrown (new seed or shape)"
    if result.op == "constants":
        return f"constants changed, whole plant re-derived ({result.removed:,} → {result.added:,} modules)"
    if result.op == "prune":
        return f"pruned {parts} ({result.removed:,} modules removed)"
    if getattr(result, "cut", None) is None and result.op == "regrow":
        return f"regrew the whole plant ({result.removed:,} modules replaced by {result.added:,})"
    return f"{result.op if result.op != 'regrow' else 'regrew'} {parts} ({result.removed:,} modules replaced by {result.added:,})"


#: Why a regrow drew the same plant, and what to do instead (the regeneration panel's note).
SAME_PLANT = (
    "Regrowing gave the same plant: this grammar is deterministic (no rule probabilities, "
    "no uniform() or normal() draws), so a new seed grows the same branches. To change the "
    "selected part: type values under 'Constants for the selection' and press 'Regrow with "
    "constants', apply a qualifier, or open a stochastic grammar."
)
#: The note after a regrow of a selection.
REGROWN = "The regrown part stays selected (red): Regrow again for another seed, Esc clears, Ctrl+Z undoes."


def regrow_note(job: str, note: str | None, same_as_before: bool, selected: bool) -> str:
    """The regeneration panel's note after edit ``job`` ("regrow", "prune", ...): the model's
    ``note`` as a sentence (e.g. new constants on a part made in the last step), else
    :data:`SAME_PLANT` when the regrow drew the plant drawn before it, else :data:`REGROWN`
    when a part stays ``selected``; "" after any other edit."""
    if job != "regrow":
        return ""
    if note:
        return note[0].upper() + note[1:] + "."
    if same_as_before:
        return SAME_PLANT
    return REGROWN if selected else ""


def regrown_leaves(explorer: Explorer, result: RegenResult | None) -> list[int]:
    """The leaves a regrow put in the string, sorted (:func:`ramure.app.model.regrown_leaves`)."""
    from ramure.app.model import regrown_leaves as model_regrown_leaves

    return model_regrown_leaves(explorer.derivation.tree, result)


def same_plant(before: tuple[np.ndarray, np.ndarray] | None, after: Skeleton | None) -> bool:
    """True if ``before`` (segment ``(start, end)`` arrays) and skeleton ``after`` draw the same
    plant (same segments, same places): a regrow that changed nothing, as on a deterministic grammar."""
    if before is None or after is None or len(before[0]) != len(after.start):
        return False
    return bool(np.array_equal(before[0], after.start) and np.array_equal(before[1], after.end))


_PREVIEW: list = []  # [(modules, text)]: the last preview and what it showed


def string_preview(explorer: Explorer, limit: int = STRING_PREVIEW_MODULES) -> str:
    """The current string, modules separated by spaces, cut after ``limit`` modules.

    The text of the last preview is kept with its modules (symbols and parameters): an edit
    that leaves the first ``limit`` modules as they were (most regrows) reuses it.
    """
    tree = explorer.derivation.tree
    leaves = tree.leaves
    head = leaves[:limit]
    modules = (tuple(explorer.lsystem.symbols), tree.symbol[head], tree.nparams[head], tree.params[head])
    last = _PREVIEW[0] if _PREVIEW else None
    if (
        last is not None
        and last[0][0] == modules[0]
        and all(np.array_equal(a, b, equal_nan=True) for a, b in zip(last[0][1:], modules[1:]))
    ):
        text = last[1]
    else:
        text = " ".join(explorer.lsystem.module_text(tree, v) for v in head.tolist())
        _PREVIEW[:] = [(modules, text)]
    if len(leaves) > limit:
        text += f" … ({len(leaves) - limit} more modules)"
    return text


def selected_modules(explorer: Explorer, limit: int = 200) -> list[str]:
    """``"id: module"`` lines for the selected leaves (for the string dock)."""
    tree = explorer.derivation.tree
    return [f"{leaf}: {explorer.lsystem.module_text(tree, leaf)}" for leaf in explorer.selection[:limit]]


# -- constants -------------------------------------------------------------------
def without_define_values(text: str) -> str:
    """``text`` with every ``#define`` value blanked: equal for two texts that differ only there."""
    return "\n".join(
        DEFINE_LINE.sub(lambda m: m.group(1) + m.group(2) + " _" + _comment(m.group(5)), line) for line in text.split("\n")
    )


def _comment(tail):
    return (" " + tail.strip()) if tail.strip() else ""


def constants_only_change(old_text: str, new_text: str) -> bool:
    """True if ``new_text`` differs from ``old_text`` in ``#define`` values only (then typing
    is a constants edit on the same plant, not a new grammar)."""
    return old_text != new_text and without_define_values(old_text) == without_define_values(new_text)


def set_constant_merging(explorer: Explorer, name: str, value: float, previous: dict | None = None) -> dict:
    """Set constant ``name``; if ``previous`` (an edit dict) is still the session's last edit,
    replace it, so a slider drag is one undo step.  Returns the new edit.

    Undoing a constants edit only swaps derivations back (cheap); on a refused
    value the replaced edit is redone, leaving the history as it was.
    """
    edits = explorer.session.edits
    merged = previous is not None and bool(edits) and edits[-1] is previous
    if merged:
        explorer.undo()
    try:
        explorer.set_constant(name, value)
    except Exception:
        if merged:
            explorer.redo()
        raise
    return explorer.session.edits[-1]


def constant_range(value: float) -> tuple[float, float]:
    """The slider range offered for a ``#define`` value: [0, 2v] (or [2v, 0]), [-1, 1] for 0."""
    value = float(value)
    if value > 0:
        return 0.0, 2.0 * value
    if value < 0:
        return 2.0 * value, 0.0
    return -1.0, 1.0


def changed_constants(edited: Mapping[str, float], current: Mapping[str, float], tol: float = 1e-12) -> dict[str, float]:
    """The entries of ``edited`` that differ from ``current`` (what "Regrow with constants" sends)."""
    return {k: float(v) for k, v in edited.items() if abs(float(v) - float(current.get(k, np.nan))) > tol or k not in current}


# -- drawing ---------------------------------------------------------------------
def base_colors(mesh: pv.DataSet) -> np.ndarray:
    """Per-cell RGB of the unselected plant (the shared palette: fruit in orange).

    The same colours as :func:`ramure.app.render.plant_colors`, looked up by ``kind`` in a
    three-row palette (1 instead of 9 ms at 393k cells); meshes with ``#material`` colours
    go through ``plant_colors`` itself.  The result is read-only and shared: the colours of
    the last three meshes are kept (an undo shows a mesh coloured before).
    """
    from ramure.app.render import BARK, FRUIT, LEAF

    if "material" in mesh.cell_data and "material_rgb" in mesh.field_data:
        return plant_colors(mesh)
    array = mesh.GetCellData().GetArray("kind")
    key = (array.GetAddressAsString("vtkDataArray"), array.GetMTime()) if array is not None else None
    for known, rgb in _BASE_COLORS:
        if key is not None and known == key:
            return rgb
    palette = (np.array([BARK, LEAF, FRUIT]) * 255).astype(np.uint8)  # plant_colors' own rounding
    kind = np.clip(np.asarray(mesh.cell_data["kind"]), 0, 2)
    rgb = np.empty((len(kind), 3), np.uint8)
    first = kind[0] if len(kind) else 0
    for c in range(3):  # the first cell's kind (bark) a column at a time: 5x faster than a gather
        rgb[:, c] = palette[first, c]
    others = np.flatnonzero(kind != first)  # organs
    rgb[others] = palette.take(kind[others], axis=0)
    rgb.flags.writeable = False  # shared: callers copy (cell_colors does)
    if key is not None:
        _BASE_COLORS.insert(0, (key, rgb))
        del _BASE_COLORS[3:]
    return rgb


#: The last few meshes' :func:`base_colors`, keyed by their ``kind`` array (its address and
#: VTK modification time): an undo shows a mesh coloured before.
_BASE_COLORS: list[tuple[tuple[str, int], np.ndarray]] = []


KIND_FRUIT = 2  # mesh cell_data["kind"] of a Fruit organ (ramure.lsys.interpretation.geometry.KIND_FRUIT)
FRUIT_SELECTED = (40, 110, 255)  # a selected fruit: blue, never mistaken for a ripe one


def fruit_leaves(mesh: pv.DataSet) -> np.ndarray:
    """The history leaves drawn as fruit spheres (sorted, unique)."""
    if mesh is None or mesh.n_cells == 0:
        return np.zeros(0, np.int64)
    kind = np.asarray(mesh.cell_data["kind"])
    return np.unique(np.asarray(mesh.cell_data["leaf_id"])[kind == KIND_FRUIT])


def points_without_fruit(mesh: pv.DataSet) -> np.ndarray | None:
    """A copy of the mesh's points with each fruit sphere shrunk to its centre (None: no fruit).

    Drawn with these points, the spheres vanish (zero-area triangles) while
    cell ids, colours and picking stay those of the full mesh: what the view
    shows while volumetric fruit replace the spheres.  (VTK's hidden-cell
    ghost array is not honoured by the polydata mapper.)
    """
    kind = np.asarray(mesh.cell_data["kind"])
    if not (kind == KIND_FRUIT).any():
        return None
    from vtkmodules.util.numpy_support import vtk_to_numpy

    polys = mesh.GetPolys()
    conn = vtk_to_numpy(polys.GetConnectivityArray())
    offsets = vtk_to_numpy(polys.GetOffsetsArray())
    cell = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    fruit = kind[cell] == KIND_FRUIT
    organ = np.asarray(mesh.cell_data["organ"])[cell[fruit]]
    ids = conn[fruit]
    points = np.array(mesh.points, copy=True)
    count = np.bincount(organ)
    sums = np.stack([np.bincount(organ, points[ids, k]) for k in range(3)], axis=1)
    centre = sums / np.maximum(count, 1)[:, None]
    points[ids] = centre[organ]
    return points


_LAST_SELECTION: list = []  # [(selection, its ids as an array)]: the last one asked for


def selection_ids(selection: Collection[int]) -> np.ndarray:
    """``selection`` (a snapshot's tuple of leaf ids) as an int64 array.  The window asks for
    the same selection several times per edit (colours, the highlighted segments, its box): after
    a regrow of a quarter of Honda n = 17 it holds 650,000 leaves, each conversion about 60 ms,
    so the last one is kept (by identity: a tuple never changes).

    >>> sel = (3, 5, 9)
    >>> selection_ids(sel).tolist(), selection_ids(sel) is selection_ids(sel)
    ([3, 5, 9], True)
    """
    last = _LAST_SELECTION[0] if _LAST_SELECTION else None
    if last is not None and last[0] is selection and isinstance(selection, tuple):
        return last[1]
    ids = np.fromiter(selection, np.int64, len(selection))
    ids.flags.writeable = False
    _LAST_SELECTION[:] = [(selection, ids)]
    return ids


def leaf_mask(leaf_ids: np.ndarray, selection: Collection[int]) -> np.ndarray:
    """Boolean mask of ``leaf_ids`` that are in ``selection`` (a lookup table: O(n), no sort)."""
    leaf_ids = np.asarray(leaf_ids)
    sel = selection_ids(selection)
    if not len(sel) or not len(leaf_ids):
        return np.zeros(len(leaf_ids), bool)
    table = np.zeros(max(int(leaf_ids.max()), int(sel.max())) + 1, bool)
    table[sel[sel >= 0]] = True
    if int(leaf_ids.min()) >= 0:  # every cell has a leaf (the usual case): one gather
        return table[leaf_ids]
    return table[np.maximum(leaf_ids, 0)] & (leaf_ids >= 0)


#: The cut preview: what a regrow of the selection would change and is not selected (orange).
CUT_PREVIEW = (255, 153, 0)


def cell_colors(
    mesh: pv.DataSet,
    selection: Collection[int] = (),
    kinship_rgb: np.ndarray | None = None,
    base: np.ndarray | None = None,
    cut: Collection[int] = (),
) -> np.ndarray:
    """RGB (uint8) per cell: bark/leaf/fruit with the selection red, or the kinship colours;
    ``cut`` (the preview's leaves, :meth:`ramure.app.model.Explorer.preview`) orange under it.

    ``base`` is :func:`base_colors` computed once per plant (saves a pass per selection).
    """
    if kinship_rgb is not None:
        return kinship_rgb
    rgb = (base_colors(mesh) if base is None else base).copy()
    if len(cut):
        rgb[leaf_mask(mesh.cell_data["leaf_id"], cut)] = CUT_PREVIEW
    if len(selection):
        chosen = np.flatnonzero(leaf_mask(mesh.cell_data["leaf_id"], selection))  # few: recoloured by index
        fruit = np.asarray(mesh.cell_data["kind"])[chosen] == KIND_FRUIT
        rgb[chosen[~fruit]] = (255, 0, 0)
        rgb[chosen[fruit]] = FRUIT_SELECTED  # red on orange would read as ripe fruit
    return rgb


def kinship_cell_colors(explorer: Explorer, mesh: pv.DataSet) -> np.ndarray | None:
    """Per-cell RGB (uint8) by derivation kinship to the single selected leaf, else None.

    Segments take the model's :meth:`~ramure.app.model.Explorer.kinship_hues`; organ
    cells (leaves, fruit) take the colour of their own history leaf.
    """
    seg_rgb = explorer.kinship_hues()
    if seg_rgb is None:
        return None
    rgb = np.zeros((mesh.n_cells, 3))
    seg = np.asarray(mesh.cell_data["segment"])
    on_segment = seg >= 0
    rgb[on_segment] = seg_rgb[seg[on_segment]]
    if not on_segment.all():
        from ramure.lsys.regeneration.mincut import kinship

        tree = explorer.derivation.tree
        _, _, leaf_rgb = kinship(tree, explorer.selection[0], n=explorer.session.n)
        pos = tree.leaf_positions(np.asarray(mesh.cell_data["leaf_id"])[~on_segment])
        rgb[~on_segment] = np.where((pos >= 0)[:, None], leaf_rgb[np.maximum(pos, 0)], 0.5)
    return (np.clip(rgb, 0, 1) * 255).astype(np.uint8)


def selection_box_lines(skeleton: Skeleton, selection: Collection[int]) -> np.ndarray | None:
    """The selection's OBB as line segments (12, 2, 3), or None (empty or no branch selected)."""
    if not len(selection):
        return None
    segments = np.flatnonzero(leaf_mask(skeleton.leaf_id, selection))
    if not len(segments):
        return None
    from ramure.metrics import plant_obb
    from ramure.metrics.obb import EDGES

    corners = plant_obb(skeleton, segments=segments).corners()
    return corners[EDGES]


def cells_near_line(
    points: ArrayLike,
    offsets: ArrayLike,
    conn: ArrayLike,
    origin: ArrayLike,
    direction: ArrayLike,
    reach: float,
    tubes: tuple[int, int] = (0, 0),
) -> np.ndarray:
    """Ids (ascending) of the polygons that may come within ``reach`` of the line through
    ``origin`` along ``direction``: those whose box's circumscribed sphere does.

    ``offsets`` and ``conn`` are VTK's cell arrays over ``points``.  Every cell a ray pick
    with a tolerance up to ``reach`` can hit is among them (and a few more), so a picker run
    on them alone finds what it finds on the whole mesh.  ``tubes``: (count, sides) when the
    mesh starts with ``count`` tubes of ``sides`` quads over ``2 sides`` points each, segment
    by segment (:func:`ramure.app.desktop.view.plant_actors.tube_layout`): a tube is tested as a
    whole, from its points in place.  Read in chunks of :data:`NEAR_LINE_CHUNK` (a few MB of
    temporaries whatever the mesh's size).

    >>> pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 0], [6, 5, 0], [5, 6, 0]], float)
    >>> cells_near_line(pts, [0, 3, 6], [0, 1, 2, 3, 4, 5], [0.2, 0.2, -1], [0, 0, 1], 0.01).tolist()
    [0]
    """
    pts, offsets, conn = np.asarray(points), np.asarray(offsets), np.asarray(conn)
    d = np.asarray(direction, float)
    o, u, r = np.asarray(origin, float), d / np.linalg.norm(d), float(reach)
    count, sides = tubes
    found = []
    if count and sides:
        ends = pts[: 2 * sides * count].reshape(count, 2 * sides, 3)
        for first in range(0, count, NEAR_LINE_CHUNK):
            part = ends[first : first + NEAR_LINE_CHUNK]
            near = np.flatnonzero(_boxes_near_line(*_boxes(part), o, u, r)) + first
            found.append((near[:, None] * sides + np.arange(sides)).ravel())
    rest = np.arange(count * sides if sides else 0, len(offsets) - 1)
    size = offsets[rest + 1] - offsets[rest]
    for k in np.unique(size):  # cells of one size at a time: their corners as a (cells, k, 3) array
        cells = rest[size == k]
        for first in range(0, len(cells), NEAR_LINE_CHUNK):
            some = cells[first : first + NEAR_LINE_CHUNK]
            corners = pts[conn[offsets[some][:, None] + np.arange(k)]]
            found.append(some[_boxes_near_line(*_boxes(corners), o, u, r)])
    return np.sort(np.concatenate(found)) if found else np.zeros(0, np.int64)


#: Tubes or cells read at a time by :func:`cells_near_line`.
NEAR_LINE_CHUNK = 1 << 15


def _boxes(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lowest and highest corner of each row of ``corners`` ((n, k, 3)), one column of k at a
    time (numpy's reduction over a short middle axis is 10x slower)."""
    lo, hi = corners[:, 0].copy(), corners[:, 0].copy()
    for j in range(1, corners.shape[1]):
        np.minimum(lo, corners[:, j], out=lo)
        np.maximum(hi, corners[:, j], out=hi)
    return lo, hi


def _boxes_near_line(lo: np.ndarray, hi: np.ndarray, origin: np.ndarray, unit: np.ndarray, reach: float) -> np.ndarray:
    """True for the boxes ``lo``-``hi`` whose circumscribed sphere comes within ``reach`` of the
    line through ``origin`` along ``unit`` (a unit vector)."""
    lo, hi = lo.astype(float), hi.astype(float)
    rel = 0.5 * (lo + hi) - origin
    along = rel @ unit
    off_line = np.einsum("ij,ij->i", rel, rel) - along * along
    span = hi - lo
    radius = 0.5 * np.sqrt(np.einsum("ij,ij->i", span, span)) + reach
    return off_line <= radius * radius


def cell_subset(offsets: ArrayLike, conn: ArrayLike, cells: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """VTK's cell arrays (offsets, connectivity; the dtype of ``conn``) of the polygons ``cells``
    of the cell arrays ``offsets``, ``conn``, in that order, over the same points.

    >>> o, c = cell_subset([0, 3, 7], [0, 1, 2, 3, 4, 5, 6], [1])
    >>> o.tolist(), c.tolist()
    ([0, 4], [3, 4, 5, 6])
    """
    offsets, conn, cells = np.asarray(offsets), np.asarray(conn), np.asarray(cells, np.int64)
    begin, size = offsets[cells], offsets[cells + 1] - offsets[cells]
    sub_offsets = np.zeros(len(cells) + 1, conn.dtype)
    np.cumsum(size, out=sub_offsets[1:])
    where = np.repeat(begin - sub_offsets[:-1], size) + np.arange(int(sub_offsets[-1]))
    return sub_offsets, np.ascontiguousarray(conn[where])


# -- volumetric fruit ---------------------------------------------------------------
def fruit_surface(explorer: Explorer) -> pv.PolyData | None:
    """The plant's volumetric fruit as a surface (see :meth:`ramure.app.model.Explorer.fruit_surface`)."""
    return explorer.fruit_surface()


#: Plants with at most this many fruit are cut open subdivided once (every tissue shows).
CUT_FINE_FRUIT = 60


def tissue_colours(gm: GMap3, grid: pv.UnstructuredGrid) -> np.ndarray:
    """uint8 RGB per cell of ``grid`` (the grid of the plant's fruit ``gm``): each fruit's
    tissues in its own species' colours at its ripeness (a mixed tree keeps each fruit's)."""
    from ramure.gmap.organs.species import cell_rgb, check_stage, species_of

    leaf = np.asarray(grid.cell_data["leaf_id"], np.int64)
    tissue = np.asarray(grid.cell_data["tissue"])
    centres = np.asarray(grid.cell_centers().points)
    rgb = np.zeros((grid.n_cells, 3), np.uint8)
    for fruit in gm.meta.get("fruits", []):
        mine = leaf == int(fruit["leaf_id"])
        if mine.any():
            species = species_of(fruit["preset"])
            rgb[mine] = cell_rgb(tissue[mine], species, check_stage(species, None), centres[mine], None, int(fruit["seed"]))
    return rgb


def fruit_cut_surface(explorer: Explorer, normal: Sequence[float]) -> pv.PolyData | None:
    """The volumetric fruit cut open: each fruit loses the half in front of a plane through its
    own centre (``normal`` points at the viewer), so every fruit shows its inside.

    Whole cells are kept or dropped (no clipping): the exposed faces are the cells' own walls,
    so skin, flesh and locules read as the 3G-map's volumes.  Up to :data:`CUT_FINE_FRUIT`
    fruit are cut once volume-subdivided, with their tissues (skin, flesh, locules, seeds;
    about 50 ms a fruit, in the worker); more are cut coarse (columella and pericarp only).
    Returns a surface with
    ``leaf_id``, ``tissue`` and ``tissue_rgb`` (each fruit's species colours for its tissues
    at its ripeness, :func:`ramure.gmap.organs.species.cell_rgb`) per cell, or None without fruit.
    """
    from ramure.gmap.kernel.pyvista import to_unstructured_grid

    fruit_count = len(explorer.fruit_ids())
    if not fruit_count:
        return None
    gm = explorer.fruit_volumes(volume_levels=1 if fruit_count <= CUT_FINE_FRUIT else 0)
    grid = to_unstructured_grid(gm)
    grid.cell_data["tissue_rgb"] = tissue_colours(gm, grid)
    leaf = np.asarray(grid.cell_data["leaf_id"], np.int64)
    centres = np.asarray(grid.cell_centers().points)
    ids, inverse = np.unique(leaf, return_inverse=True)
    count = np.bincount(inverse)
    middle = np.stack([np.bincount(inverse, centres[:, k]) for k in range(3)], axis=1) / count[:, None]
    n = np.asarray(normal, float)
    n = n / (np.linalg.norm(n) or 1.0)
    keep = np.einsum("ij,j->i", centres - middle[inverse], n) <= 0
    kept = grid.extract_cells(np.flatnonzero(keep))  # type: ignore[arg-type]  # pyvista types index arrays as NDArray[int], not numpy's integer dtypes
    return kept.extract_surface(algorithm="dataset_surface")


# -- the cut graph -----------------------------------------------------------------
@dataclass
class GraphLayout:
    """Positions and roles of the cut graph's vertices and edges, ready to draw."""

    positions: dict  # vertex -> (x, y), y grows downwards
    source_side: set
    edges: list  # (u, v, capacity or None, is_cut)
    roots: set  # tree nodes regrown from
    selected: set  # selected leaves
    names: dict = field(default_factory=dict)  # tree node -> symbol name (tooltips)
    depths: dict = field(default_factory=dict)  # tree node -> derivation depth


def drawable_cut(cut: CutResult | None) -> bool:
    """Whether the cut-graph dock draws ``cut``: at most :data:`CUT_GRAPH_MAX_NODES` tree nodes."""
    return cut is not None and cut.graph_size <= CUT_GRAPH_MAX_NODES


def cut_too_large_words(cut: CutResult) -> str:
    """What the cut-graph dock says instead of drawing a cut too large to read.

    >>> from types import SimpleNamespace as NS
    >>> cut_too_large_words(NS(graph_size=65_254, roots=np.arange(44)))
    'The cut spans 65,254 nodes of the derivation tree (44 roots): too many to draw here (at most 3,000).'
    """
    roots = len(cut.roots)
    return (
        f"The cut spans {cut.graph_size:,} nodes of the derivation tree ({roots:,} root{'s' if roots != 1 else ''}): "
        f"too many to draw here (at most {CUT_GRAPH_MAX_NODES:,})."
    )


def cut_graph_layout(
    cut: CutResult, tree: DerivationTree, roots: Iterable[int] = (), symbols: Sequence[str] | None = None
) -> GraphLayout:
    """Lay out the graph of a :class:`ramure.lsys.regeneration.mincut.CutResult` as a tidy tree by derivation depth.

    Each tree node ``v`` gives two vertices ``(v, "in")`` above ``(v, "out")``;
    rows are derivation depths (the source at the top, the sink at the
    bottom).  Across, the graph's leaves take one column each in depth-first
    order and a parent sits centred over its children, so a subtree is one
    block under its parent and tree edges never cross.  ``symbols`` (the
    grammar's symbol names) names the nodes in :attr:`GraphLayout.names`.
    """
    graph = cut.graph
    nodes = sorted({v[0] for v in graph if isinstance(v, tuple)})
    depth = dict(zip(nodes, tree.depth_of(np.asarray(nodes, np.int64)).tolist()))  # these nodes only
    parent = tree.parent
    members = set(nodes)
    children: dict[int, list[int]] = {}
    tops = []
    for v in nodes:
        p = int(parent[v])
        if p in members:
            children.setdefault(p, []).append(v)
        else:
            tops.append(v)
    xs = {}
    column = 0
    for top in tops:  # iterative post-order: leaves take columns, parents centre over children
        stack = [(top, False)]
        while stack:
            v, done = stack.pop()
            kids = children.get(v)
            if not kids:
                xs[v] = float(column)
                column += 1
            elif done:
                xs[v] = (xs[kids[0]] + xs[kids[-1]]) / 2.0
            else:
                stack.append((v, True))
                stack.extend((k, False) for k in reversed(kids))
    rows = {int(depth[v]) for v in nodes}
    top = min(rows) if rows else 0
    bottom = max(rows) if rows else 0
    middle = (column - 1) / 2.0 if column else 0.0
    positions: dict[object, tuple[float, float]] = {}  # (node, "in"/"out"), "s", "t"
    for v in nodes:
        x, y = xs[v] - middle, 2.0 * (int(depth[v]) - top) + 1.0
        positions[(v, "in")] = (x, y)
        positions[(v, "out")] = (x, y + 0.8)
    positions["s"] = (0.0, 0.0)
    positions["t"] = (0.0, 2.0 * (bottom - top) + 3.0)
    source_side = set(cut.source_side)
    edges = [(u, v, d.get("capacity"), u in source_side and v not in source_side) for u, v, d in graph.edges(data=True)]
    selected = set(np.asarray(cut.selected if cut.selected is not None else [], np.int64).tolist())
    names = {}
    if symbols is not None:
        symbol = tree.symbol
        names = {v: str(symbols[int(symbol[v])]) for v in nodes}
    return GraphLayout(positions, source_side, edges, {int(r) for r in roots}, selected, names, {v: int(depth[v]) for v in nodes})
