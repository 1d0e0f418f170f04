"""The explorer's state, shared by the desktop window and the Jupyter widgets.

:class:`Explorer` holds the grammar text, the editing :class:`~ramure.lsys.regeneration.regen.Session`,
the selection and the last cut, and turns user actions into calls on the core
packages.  It has no GUI code: a front end calls its methods and redraws when
:attr:`Explorer.version` changes.  Bad input is refused with a
:class:`~ramure.lsys.errors.RamureError` and leaves the state as it was.

>>> ex = Explorer("grammars/honda_sympodial.lsys", n=6)
>>> ex.select(ex.session.leaves_with_symbol("F")[-3:])
>>> result = ex.regrow(constants={"a2": 30})
>>> ex.undo() is not None and ex.selection == []
True
"""

from __future__ import annotations

import math
import os
import pathlib
import threading
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

import ramure.io as atomic

from ramure.lsys import GrammarError, LSystem, load_kernels
from ramure.lsys.regeneration.select import leaves_where
from ramure.lsys.regeneration.mincut import FROM_AXIOM_MESSAGE, climb_levels, kinship, stranded_words
from ramure.lsys.history.tree import concat_ranges, sorted_unique
import ramure.grammars as grammar_files
from ramure.errors import RamureError, ValueRefused
from ramure.app.document import (
    OPEN_SUFFIXES,
    CodeNotAllowed,
    check_round_trip,
    document_text,
    open_document,
    session_runs_code,
)
from ramure.app.history import Timeline, history_words
from ramure.app.ids import not_a_leaf
from ramure.lsys.engine.combination import split as split_combination
from ramure.lsys.regeneration.regen import Session
from ramure.lsys.interpretation.geometry import patch_polydata, skeleton_to_polydata
from ramure.lsys.interpretation.turtle import changed_spans, reinterpret

if TYPE_CHECKING:
    import pyvista as pv
    from ramure.gmap.kernel.map3 import GMap3
    from ramure.lsys import Derivation
    from ramure.lsys.regeneration.mincut import CutResult
    from ramure.lsys.regeneration.regen import RegenResult
    from ramure.lsys.interpretation.turtle import Skeleton
    from ramure.metrics.apply import QualifierResult
    from ramure.metrics.qualifiers import QualifierRegions
    from ramure.metrics.sweep import VariantSweep

SELECT_MODES = ("replace", "add", "remove", "toggle")


class Explorer:
    """Edit–select–regenerate state for one plant: the document and its one undo history.

    ``source`` is a grammar file path, a shipped grammar's name (``"honda_sympodial"``, as
    :func:`ramure.load` takes) or grammar text; ``n`` and ``seed`` default to the grammar's
    ``n:`` and ``#seed``.  Files are opened by :func:`~ramure.app.document.open_document`:
    ``.lsys``, L-studio ``.l``, OpenAlea ``.mtg`` and L-Py ``.lpy`` models; an ``.lpy`` is a
    Python program and is run only with ``run_code=True`` (else
    :class:`~ramure.app.document.CodeNotAllowed`).

    The document is the grammar text with the session's ``n``, seed and constants written
    in (:meth:`document_text`) plus the local edits of parts of the plant (regrows, prunes,
    fruit), which only a session file holds.  :attr:`dirty` compares it with what was last
    saved or opened (the state the explorer started in counts as saved).  Undo and Redo walk
    the session's edits, then the :attr:`timeline` of the sessions a new text, ``n`` or seed
    replaced.  Opening a grammar or loading a session starts a fresh history: Undo never
    brings back a plant the user chose to leave by opening another file.
    """

    def __init__(self, source: str | os.PathLike, n: int | None = None, seed: int | None = None, run_code: bool = False) -> None:
        path = source_path(source)
        if path is not None:
            self.text, lsystem, self.path = open_document(path, run_code=run_code)
        else:
            self.text, lsystem, self.path = str(source), LSystem.from_text(str(source)), None
        self.error: GrammarError | None = None  # the last grammar error, shown by the front end
        self.rho = 0.5
        self.selection: list[int] = []
        self.fruit_region: dict | None = None  # {"leaf": id, "region": labels}: select_fruit_region
        self.last_result: RegenResult | None = None
        self.summary: str | None = None  # what the last edit changed (edit_summary)
        self.note: str | None = None  # why the last edit changed nothing on screen, if it did not
        self.version = 0
        self._cache: dict[str, Any] = {}
        self.session = Session(lsystem, n=n, seed=seed, filename=str(self.path) if self.path else None)
        self._drawn(self.derivation.skeleton())  # a turtle error (a polygon never closed) is raised here
        self.timeline = Timeline()  # the sessions a new text, n or seed replaced
        self.history_note = ""  # what the last Undo or Redo did ("Undid: a2 = 45"), "" after any other change
        self._left = (self.checkpoint(), list(self.session.edits))  # the state after the last change
        self.saved = self._fingerprint()  # what the file on disk holds (the start counts as saved)

    # -- derived views (cached per version) --------------------------------
    def _cached(self, key, make):
        if self._cache.get("version") != self.version:
            self._cache = {"version": self.version}
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    @property
    def lsystem(self) -> LSystem:
        return self.session.lsystem

    @property
    def derivation(self) -> Derivation:
        return self.session.derivation

    @property
    def skeleton(self) -> Skeleton:
        """The turtle's skeleton of the current plant; after an edit only the changed part is
        re-interpreted (:func:`ramure.lsys.interpretation.turtle.reinterpret`)."""
        return self._plant()["skeleton"]

    @property
    def mesh(self) -> pv.PolyData:
        """The plant's mesh; after an edit only the changed tubes are rebuilt
        (:func:`ramure.lsys.interpretation.geometry.patch_polydata`).  Tubes have :func:`mesh_sides` sides.

        Its points are float32 (what OpenGL draws; 9 MB less at 1.44 M modules), each the float64
        value rounded once; ``skeleton.to_polydata()`` gives float64 points when they are needed."""
        plant = self._plant()
        if plant["mesh"] is None:
            sides = mesh_sides(len(plant["skeleton"]))
            previous = plant.pop("previous_mesh", None)
            if previous is not None and previous[1] == sides:
                plant["mesh"] = patch_polydata(previous[0], plant["skeleton"], sides)
            else:
                plant["mesh"] = skeleton_to_polydata(plant["skeleton"], sides, points_dtype=np.float32)
            plant["sides"] = sides
        return plant["mesh"]

    def _plant(self):
        """Skeleton and mesh of this version, made from the last version's when the tree is the same.

        The plant before the last change is kept too: an undo (or a redo after it) puts back
        the very leaves array it had, and gets that plant's arrays back without recomputing.
        """
        plant = self.__dict__.get("_plant_state")
        if plant is not None and plant["version"] == self.version:
            return plant
        d = self.derivation
        before = self.__dict__.get("_plant_before")
        if (
            before is not None
            and before["tree"] is d.tree
            and before["lsystem"] is d.lsystem
            and before["leaves"] is d.tree.leaves
            and before.get("mesh") is not None
        ):
            before["version"] = self.version
            self._plant_before = plant if plant is not None and plant.get("mesh") is not None else None
            self._plant_state = before
            return before
        same_tree = plant is not None and plant["tree"] is d.tree and plant["lsystem"] is d.lsystem
        self._plant_before = plant if same_tree and plant is not None and plant.get("mesh") is not None else None
        skeleton = None
        if same_tree and plant is not None:  # (same_tree implies it; said again for mypy)
            old = plant["skeleton"]
            spans = None
            if "trace" in old.extra:  # the edit's own spans, else found by comparing the strings
                before = old.extra["trace"].leaves
                spans = self.session.edit_spans(before, d.tree.leaves) or changed_spans(before, d.tree.leaves, d.tree.size)
            if spans is not None:
                skeleton = reinterpret(d.lsystem, d.tree, old, d.tree.leaves, *spans)
        fresh = {
            "version": self.version,
            "tree": d.tree,
            "lsystem": d.lsystem,
            "leaves": d.tree.leaves,
            "skeleton": skeleton if skeleton is not None else d.skeleton(),
            "mesh": None,
        }
        if skeleton is not None and plant is not None and plant.get("mesh") is not None:
            fresh["previous_mesh"] = (plant["mesh"], plant["sides"])
        self._plant_state = fresh
        return fresh

    @property
    def constants(self) -> dict[str, float]:
        return dict(self.session.constants)

    def _changed(self, record: bool = True) -> None:
        """A new version.  ``record``: keep the history one line (a replaced session is
        remembered in the timeline; a new edit ends what Redo could bring back)."""
        self.history_note = ""  # an undo or redo sets it again after this
        if record:
            before, edits = self._left
            session = self.session
            if session is not before["session"]:
                self.timeline.leave(before, len(edits))
            elif len(session.edits) != len(edits) or any(a is not b for a, b in zip(session.edits, edits)):
                self.timeline.new_edit()
        self.version += 1
        self._left = (self.checkpoint(), list(self.session.edits))

    def checkpoint(self) -> dict:
        """The editing state a new text, n or seed replaces: grammar text, path and the session
        (with its own undo and redo).  :meth:`restore` brings it back (undo across sessions)."""
        return {"text": self.text, "path": self.path, "session": self.session}

    def restore(self, checkpoint: dict) -> None:
        """Make a :meth:`checkpoint` current again (selection cleared, a new version)."""
        self.text, self.path, self.session = checkpoint["text"], checkpoint["path"], checkpoint["session"]
        self.selection, self.last_result, self.error = [], None, None
        self._changed(record=False)

    # -- the document and its state on disk -----------------------------------
    def document_text(self) -> str:
        """The grammar text with the current ``n``, seed and constants written in: what Save
        grammar writes and the editor shows (see :func:`ramure.app.document.document_text`)."""
        s = self.session
        key = (self.text, self.path, s.lsystem, s.n, s.seed, tuple(s.constants.items()))
        memo = self.__dict__.get("_document")  # each snapshot asks twice (the text shown, dirty)
        if memo is None or memo[0] != key:
            memo = self._document = (key, document_text(self.text, s.lsystem, s.n, s.seed, s.constants, _name(self.path)))
        return memo[1]

    def local_edits(self) -> list[dict]:
        """The edits of parts of the plant (regrow, prune, fruit, details) that the grammar text
        cannot hold: only a session file keeps them."""
        return [e for e in self.session.edits if e["op"] != "constants"]

    def _fingerprint(self):
        return self.document_text(), tuple(self.local_edits())

    @property
    def dirty(self) -> bool:
        """True when the plant differs from what was last saved or opened (undoing back to the
        saved state makes it clean again)."""
        text, edits = self._fingerprint()
        return text != self.saved[0] or len(edits) != len(self.saved[1]) or any(a is not b for a, b in zip(edits, self.saved[1]))

    def mark_saved(self) -> None:
        """Take the current plant as what the file holds (after a save, or to drop the question)."""
        self.saved = self._fingerprint()

    @property
    def can_undo(self) -> bool:
        return self.session.can_undo or self.timeline.can_back

    @property
    def can_redo(self) -> bool:
        return self.session.can_redo or self.timeline.can_forward

    # -- grammar -----------------------------------------------------------
    def set_text(self, text: str) -> GrammarError | None:
        """Parse new grammar text.  On error keep the current plant and return the error.

        The user's ``n``, seed and constants stay unless the text's own line for them changed
        (its ``n:``, ``#seed`` or ``#define``): a comment typed in never resets them."""
        try:
            ls = LSystem.from_text(text, filename=str(self.path) if self.path else None)
            session = Session(ls, filename=self.session.filename, **self._kept_settings(ls))
            skeleton = session.derivation.skeleton()  # a turtle error (e.g. a polygon never closed) too
        except GrammarError as err:
            self.error = err
            return err
        self.text, self.error, self.session = text, None, session
        self.selection, self.last_result = [], None
        self._changed()
        self._drawn(skeleton)
        return None

    def _kept_settings(self, ls: LSystem) -> dict:
        """``n``, ``seed`` and ``constants`` for a new text ``ls``: the session's, except where the
        text's value differs from the old text's (the user edited that line)."""
        old, s = self.lsystem, self.session
        constants = {k: v for k, v in s.constants.items() if k in ls.constants and ls.constants[k] == old.constants.get(k)}
        return {
            "n": ls.n if ls.n != old.n else s.n,
            "seed": ls.seed if ls.grammar.seed != old.grammar.seed else s.seed,
            "constants": constants,
        }

    def open_grammar(self, path: str | os.PathLike, run_code: bool = False) -> None:
        """Open a grammar file: a fresh plant with the file's ``n``, seed and constants, a fresh
        history (Undo does not go back to the plant left) and a clean document.  On error
        (RamureError) nothing changes.

        Any file :func:`~ramure.app.document.open_document` opens: an ``.lpy`` only with
        ``run_code`` (its code runs), an ``.mtg`` becomes an unsaved grammar that draws it."""
        text, lsystem, document = open_document(path, run_code=run_code)  # regular files only
        session = Session(lsystem, filename=str(document) if document else None)
        skeleton = session.derivation.skeleton()
        self.text, self.path, self.session, self.error = text, document, session, None
        self._fresh(skeleton)

    def _fresh(self, skeleton=None) -> None:
        """A new document: nothing selected, no history, clean."""
        self.selection, self.last_result = [], None
        self.timeline.clear()
        self._changed(record=False)
        if skeleton is not None:
            self._drawn(skeleton)
        self.mark_saved()

    def _drawn(self, skeleton):
        """Keep the skeleton a new session was checked with as this version's plant."""
        d = self.derivation
        self._plant_state = {
            "version": self.version,
            "tree": d.tree,
            "lsystem": d.lsystem,
            "leaves": d.tree.leaves,
            "skeleton": skeleton,
            "mesh": None,
        }

    def set_constant(self, name: str, value: float) -> None:
        """Change one ``#define`` (an undoable edit that re-derives the plant).

        It becomes the last edit (:attr:`last_result`): the edit before it, a regrow or a prune,
        named nodes of the tree this one replaces (its cut, drawn by the desktop's cut graph)."""
        value = finite_number(value, name)
        if name not in self.lsystem.constants:
            raise ValueRefused(f"the grammar has no constant '{name}'")
        self._after_edit(self.session.set_constants({name: value}))

    def set_derivation(self, n: float | None = None, seed: float | None = None) -> None:
        """Change the derivation count or seed: a fresh session (clears undo history)."""
        n = self.session.n if n is None else n
        seed = self.session.seed if seed is None else seed
        if not float(n).is_integer() or not 0 <= int(n) <= 30:
            raise ValueRefused(f"the derivation count must be a whole number from 0 to 30, not {n}")
        if not float(seed).is_integer():
            raise ValueRefused(f"the seed must be a whole number, not {seed}")
        session = Session(self.lsystem, n=int(n), seed=int(seed), constants=self.constants, filename=self.session.filename)
        skeleton = session.derivation.skeleton()  # a turtle error leaves the current plant as it is
        self.session = session
        self.selection, self.last_result = [], None
        self._changed()
        self._drawn(skeleton)

    def set_rho(self, rho: float) -> None:
        """ρ, a fraction in (0, 1] (a front end's percent slider divides by 100 itself)."""
        rho = finite_number(rho, "rho")
        if not 0 < rho <= 1:
            raise ValueRefused(f"rho must be in (0, 1] (a fraction: 0.5 is half), not {rho:g}")
        self.rho = rho

    # -- selection ---------------------------------------------------------
    def select(self, leaf_ids: int | Iterable[int], mode: str = "replace") -> None:
        """Change the selection: ``replace``, ``add``, ``remove`` or ``toggle`` these leaves."""
        if mode not in SELECT_MODES:
            raise ValueRefused(f"selection mode must be one of {', '.join(SELECT_MODES)}")
        given = (
            list(leaf_ids)
            if isinstance(leaf_ids, Iterable) and not isinstance(leaf_ids, (list, tuple, np.ndarray, str))
            else leaf_ids
        )  # a number, or an array-like taken as it is
        ids = sorted_unique(np.atleast_1d(np.asarray(given, np.int64)))
        tree = self.derivation.tree
        known = (ids >= 0) & (ids < tree.size)
        is_leaf = np.zeros(ids.size, bool)
        is_leaf[known] = tree.in_string(ids[known])  # after an edit: from the tree's kept leaf sums
        if not is_leaf.all():
            raise ValueRefused(not_a_leaf(ids[~is_leaf][0]))
        current = np.asarray(self.selection, np.int64)
        new = {
            "replace": lambda: ids,
            "add": lambda: sorted_unique(np.concatenate([current, ids])),
            "remove": lambda: np.setdiff1d(current, ids, assume_unique=True),
            "toggle": lambda: np.setxor1d(current, ids, assume_unique=True),
        }[mode]()
        self.selection = new.tolist()  # sorted, unique (vectorised: 131k leaves in a few ms)

    def clear_selection(self) -> None:
        self.selection = []

    def leaf_of_cell(self, cell_id: int) -> int:
        """The history leaf that drew a mesh cell (what a click picks)."""
        leaf_ids = self.mesh.cell_data["leaf_id"]
        if not 0 <= int(cell_id) < len(leaf_ids):
            raise ValueRefused(f"cell {cell_id} is not part of the plant")
        return int(leaf_ids[int(cell_id)])

    def leaves_in_rectangle(self, screen_xy: ArrayLike, rect: Sequence[float]) -> list[int]:
        """Leaves whose segment midpoints project inside ``rect`` = (x0, y0, x1, y1).

        ``screen_xy`` is (s, 2): each segment midpoint projected by the view.
        """
        return leaves_in_rectangle(self.skeleton.leaf_id, screen_xy, rect)

    def segment_midpoints(self) -> np.ndarray:
        return self.skeleton.midpoints()

    def rectangle_points(self) -> tuple[np.ndarray, np.ndarray]:
        """What a rubber band selects by, in both front ends: the segments' midpoints then the
        leaves' and fruit's centres (k, 3), and the history leaf of each (k,)."""
        sk = self.skeleton
        points = np.concatenate([sk.midpoints(), np.asarray(sk.organs.position, float).reshape(-1, 3)])
        leaves = np.concatenate([np.asarray(sk.leaf_id, np.int64), np.asarray(sk.organs.leaf_id, np.int64)])
        return points, leaves

    def leaves_in_view(self, matrix: ArrayLike, size: tuple[int, int], rect: Sequence[float]) -> list[int]:
        """Leaves whose :meth:`rectangle_points` project inside display rectangle ``rect`` =
        (x0, y0, x1, y1) (pixels, origin bottom left, any corner order) through ``matrix`` (a
        camera's 4x4 world-to-clip projection) onto a viewport of ``size`` (width, height)."""
        points, leaves = self.rectangle_points()
        return leaves_in_rectangle(leaves, project_to_display(matrix, points, size), rect)

    def leaves_where(
        self, min_order: int | None = None, min_height: float | None = None, max_height: float | None = None
    ) -> list[int]:
        """Leaves by a branch-order / height filter (see :func:`ramure.lsys.regeneration.select.leaves_where`)."""
        return leaves_where(self.skeleton, min_order, min_height, max_height)

    def kinship_hues(self) -> np.ndarray | None:
        """Per-segment RGB by kinship to the single selected leaf (None otherwise)."""
        if len(self.selection) != 1:
            return None
        tree = self.derivation.tree
        _, _, rgb = kinship(tree, self.selection[0], n=self.session.n)
        pos = tree.leaf_positions(self.skeleton.leaf_id)
        return rgb[pos]

    def plan(self) -> CutResult | None:
        """The cut the current selection would use (nothing changes)."""
        if not self.selection:
            return None
        key = ("plan", self.rho, len(self.selection), hash(np.asarray(self.selection, np.int64).tobytes()))
        return self._cached(key, lambda: self.session.plan(self.selection, self.rho)[0])

    def preview(self) -> CutPreview | None:
        """What a Regrow (or a qualifier) of the current selection would change, before it
        changes anything: the cut's roots, the leaves of the string they hold, how many of the
        plant's modules that is, how far the cut climbs above the selected leaves, and the
        sentence both front ends show ("12 of 693 modules (1.7 %) will change ...").  None
        without a selection (a Regrow then regrows the whole plant).  Array code throughout:
        the leaves come from the roots' string spans, the climb from a walk up the parent links.
        """
        cut = self.plan()
        if cut is None:
            return None
        tree = self.derivation.tree
        first, last = tree.string_spans(cut.roots)
        has = last >= 0
        positions = concat_ranges(first[has], (last - first + 1)[has])
        leaves = np.asarray(tree.leaves)[positions]
        selected = np.asarray(self.selection, np.int64)
        levels = climb_levels(tree, selected, cut.roots)
        return CutPreview(
            roots=cut.roots,
            leaves=leaves,
            changed=int(len(leaves)),
            total=int(len(tree.leaves)),
            climb=_climb_range(levels),
            stranded=selected[(levels < 0) & (tree.parent[selected] >= 0)],
            from_axiom=bool(cut.from_axiom),
        )

    # -- edits -------------------------------------------------------------
    def regrow(
        self, seed: int | None = None, constants: Mapping[str, float] | None = None, params: dict | None = None
    ) -> RegenResult:
        """Regrow the selection's cut subtrees (the whole plant when nothing is selected)."""
        constants = {k: finite_number(v, k) for k, v in (constants or {}).items()}
        drawn = self.skeleton if constants and self.selection else None
        result = self.session.regrow(
            self.selection, rho=self.rho, seed=seed, constants=constants, params=params, refuse_empty=True
        )
        self._after_edit(result, keep=True)
        if drawn is not None and self._draws_the_same(drawn):
            self.note = unchanged_by_constants(self, result, constants)
        return result

    def prune(self) -> RegenResult:
        if not self.selection:
            raise ValueRefused("select the branches to prune first")
        return self._after_edit(self.session.prune(self.selection, rho=self.rho, refuse_empty=True))

    def variant_lsystem(self) -> LSystem:
        """The grammar with the session's current constants: what variant sweeps should vary."""
        return self.session.current_lsystem()

    def apply_qualifier(
        self,
        name: str,
        sweep: VariantSweep,
        points: np.ndarray | None = None,
        regions: QualifierRegions | None = None,
        tries: int = 5,
        directions: Mapping[str, Mapping[str, float]] | None = None,
    ) -> QualifierResult:
        """Regrow the selection (or the whole plant) toward qualifier ``name`` ("denser", "rond", ...).

        ``sweep`` is a fitted :class:`ramure.metrics.VariantSweep` of this grammar;
        with a study's ``regions`` and the sweep's PCA ``points`` the region
        centre chooses the variant; ``directions`` add words (a study's, from a
        vocabulary file: :func:`ramure.metrics.words.read_words`).  Candidates are tried until the selection's
        metrics move the qualifier's way (see :func:`ramure.metrics.apply.apply_qualifier`);
        the result is one undoable edit.
        """
        from ramure.metrics.apply import apply_qualifier

        out = apply_qualifier(
            self.session,
            name,
            sweep,
            self.selection,
            rho=self.rho,
            points=points,
            regions=regions,
            tries=tries,
            directions=directions or None,
        )
        if out.regen is not None:  # not improved: the plant and the selection stay as they were
            self._after_edit(out.regen, keep=True)
        return out

    def fruit_ids(self) -> list[int]:
        """History-leaf ids of the plant's ``Fruit`` organs."""
        organs = self.skeleton.organs
        return organs.leaf_id[organs.kind == "Fruit"].tolist()

    def regrow_fruit(self, seed: int | None = None, **settings: Any) -> RegenResult:
        """New seed / preset / size for the selected fruit (other fruit stay as they are)."""
        fruit = [leaf for leaf in self.selection if leaf in set(self.fruit_ids())]
        if not fruit:
            raise ValueRefused("select one or more fruit first")
        if "preset" in settings or len(settings) > int("size" in settings):
            from ramure.gmap.organs.fruit import resolve_params

            params = {k: v for k, v in settings.items() if k not in ("preset", "size")}
            resolve_params(settings.get("preset", "round_tomato"), **params)  # refuse bad values now
        return self._after_edit(self.session.regrow_fruit(fruit, seed=seed, **settings))

    def set_fruit_defects(self, specs: Iterable[str]) -> tuple[GMap3, dict]:
        """Record defect specs on the selected fruit: one undoable edit; the selection stays.

        The specs are applied first (:func:`ramure.app.fruit_defects.damaged_fruit`), so a
        refused defect changes nothing.  Returns ``(damaged map, facts)``.
        """
        from ramure.app.fruit_defects import check_specs, damaged_fruit, fruit_settings, selected_fruit

        leaf = selected_fruit(self)
        specs = check_specs(specs)
        shown = damaged_fruit(self, leaf, specs)
        self.last_result = self.session.regrow_fruit([leaf], seed=fruit_settings(self, leaf)["seed"], defects=specs)
        self._changed()
        return shown

    def select_fruit_region(
        self, how: str, *args: Any, mode: str = "replace", leaf: int | None = None, on: GMap3 | None = None
    ) -> dict:
        """Select a region of the selected fruit (not an edit: a selection, kept by edits).

        ``how``: ``"pattern"`` (args: a label pattern such as ``"(9, C*, *)"``), ``"cells"``
        (args: ``[ring, sector]`` pairs), ``"point"``
        (args: a picked skin point and a brush radius, plant units) or ``"rectangle"`` (args:
        a camera's 4x4 world-to-clip matrix, the viewport size and a display rectangle, as
        :meth:`leaves_in_view`).  ``mode``: replace, add or remove cells (a brush adds).
        ``on``: the map the point or the camera refers to (the Defects view's subdivided
        fruit), default the plant's fruit; the region is labels either way.
        Returns :attr:`fruit_region` (``{"leaf": id, "region": labels}``).
        """
        from ramure.app import fruit_regions as R

        picks: dict[str, Callable[..., tuple[int, Any]]] = {"pattern": R.by_pattern, "point": R.at_point, "cells": R.by_cells}
        pick = picks.get(how)
        if how == "rectangle":
            matrix, size, rect = args
            leaf, facing = R.facing_cells(self, matrix, leaf, on)
            keys = leaves_in_rectangle(facing["keys"], project_to_display(matrix, facing["centres"], size), rect)
            region = R.cells_of_keys(keys, facing["ph"])
        elif pick is not None:
            leaf, region = pick(self, *args, leaf=leaf, on=on)
        else:
            raise ValueRefused(f"select a fruit region by pattern, cells, point or rectangle, not {how!r}")
        old = self.fruit_region
        same = old is not None and old["leaf"] == leaf
        kept = old["region"] if old is not None and same else None
        self.fruit_region = {"leaf": leaf, "region": R.combine(kept, region, mode)}
        return self.fruit_region

    def clear_fruit_region(self) -> None:
        self.fruit_region = None

    def regrow_fruit_region(self, blend: int = 1, **params: Any) -> tuple[GMap3, dict]:
        """Regrow the selected region of the fruit with other shape ``params`` (a local
        malformation: ``largeur``, ``creux``, ``hamp`` ...): one undoable edit recording the
        region on the fruit; the rest of the fruit keeps its bytes (see
        :mod:`ramure.gmap.organs.regions`).  ``blend``: edges over which the change fades in
        from the region's rim (1, the default: every vertex of the region's own takes the new
        shape, a raised or sunk patch; 2 or more peak at the middle, which on a small region
        of a once-subdivided fruit looks crumpled).  ``precision`` (the fruit's times 2, 4 or 8)
        refines the region alone, pillowed at its rim (:mod:`ramure.gmap.organs.refine`); a
        coarser one is refused.  Returns what the Defects view shows ``(map, facts)``."""
        from ramure.app.fruit_defects import damaged_fruit, fruit_settings
        from ramure.gmap.organs.fruit import regrow_region
        from ramure.gmap.organs.regions import check_region

        if self.fruit_region is None:
            raise ValueRefused("select a region of a fruit first (a pattern, a click or a rubber band)")
        if not params:
            raise ValueRefused("give the region new parameters (e.g. largeur=70): nothing would change")
        leaf = self.fruit_region["leaf"]
        if leaf not in set(self.fruit_ids()):
            raise ValueRefused(f"fruit {leaf} is no longer on the plant: select a region again")
        s = fruit_settings(self, leaf)
        region = check_region({**self.fruit_region["region"], "params": params, "blend": blend})
        # refused here (nothing of its own to move, bad values) before recording; on the
        # fruit's cells as built (a finer precision of an earlier region comes after shapes)
        as_built = [{**r, "params": {k: v for k, v in r.get("params", {}).items() if k != "precision"}} for r in s["regions"]]
        before, _ = damaged_fruit(self, leaf, specs=[], regions=as_built)
        regrow_region(before, region, params)
        regions = [*s["regions"], region]
        shown = damaged_fruit(self, leaf, regions=regions)
        self.last_result = self.session.regrow_fruit([leaf], seed=s["seed"], regions=regions)
        self._changed()
        return shown

    def place_defect_in_region(self, spec: str, replace: int | None = None) -> tuple[GMap3, dict]:
        """Place defect ``spec`` (``"hail:depth_mm=3"``) in the selected region of the fruit
        (:func:`ramure.app.fruit_regions.defect_here`) and record the fruit's defects with it:
        one undoable edit.  ``replace``: the index of a recorded defect to move there instead
        of adding one.  Returns what the Defects view shows ``(map, facts)``."""
        from ramure.app.fruit_defects import damaged_fruit, fruit_settings
        from ramure.app.fruit_regions import defect_here

        if self.fruit_region is None:
            raise ValueRefused("select a region of a fruit first (a pattern, a click or a rubber band)")
        leaf = self.fruit_region["leaf"]
        if leaf not in self.selection:
            self.selection = [leaf, *[x for x in self.selection if x != leaf]]
        specs = list(fruit_settings(self, leaf)["defects"])
        gm, _ = damaged_fruit(self, leaf, specs=[])
        if replace is not None:
            if not 0 <= int(replace) < len(specs):
                raise ValueRefused(f"the fruit has {len(specs)} defect(s): no defect {replace} to move")
            specs[int(replace)] = defect_here(gm, self.fruit_region["region"], specs[int(replace)])
        else:
            specs.append(defect_here(gm, self.fruit_region["region"], spec))
        return self.set_fruit_defects(specs)

    def fruit_bounds(self, leaves: Iterable[int] | None = None) -> tuple[float, ...] | None:
        """Bounds ``(x0, x1, y0, y1, z0, z1)`` round fruit ``leaves`` (default: the selected
        fruit, or every fruit when none is selected), from the turtle's organs: a fruit hangs
        from its stem point along the heading and is ``size`` long, so its box is centred half a
        size down the heading, 0.6 size either way (a little margin).  None without fruit."""
        organs = self.skeleton.organs
        fruit = np.flatnonzero(np.asarray(organs.kind) == "Fruit")
        if not len(fruit):
            return None
        ids = np.asarray(organs.leaf_id)[fruit]
        wanted = [int(x) for x in (self.selection if leaves is None else leaves)]
        chosen = fruit[np.isin(ids, wanted)] if wanted else fruit
        if not len(chosen):
            chosen = fruit
        pos = np.asarray(organs.position, float)[chosen].reshape(-1, 3)
        heading = np.asarray(organs.frame, float)[chosen][:, 0, :]
        size = np.asarray(organs.size, float)[chosen].reshape(-1, 1)
        centre = pos + 0.5 * size * heading
        lo, hi = (centre - 0.6 * size).min(axis=0), (centre + 0.6 * size).max(axis=0)
        return tuple(float(v) for v in np.column_stack([lo, hi]).ravel())

    def fruit_volumes(self, preset: str = "round_tomato", seed: int = 0, **kwargs: Any) -> GMap3:
        """The plant's fruit as one volumetric 3G-map (gmap), with per-fruit edits applied."""

        def build():
            from ramure.gmap.organs.plant import fruits_from_skeleton

            return fruits_from_skeleton(
                self.skeleton, preset=preset, seed=seed, overrides=self.session.fruit_overrides(), **kwargs
            )

        return self._cached(("fruit", preset, seed, tuple(sorted(kwargs.items()))), build)

    def fruit_volume(self, leaf: int, preset: str = "round_tomato", seed: int = 0, **kwargs: Any) -> GMap3:
        """Fruit ``leaf`` alone as a volumetric 3G-map: the same fruit as in :meth:`fruit_volumes`
        (each fruit's draw depends on its leaf id, not on the others), built without the others."""
        from ramure.gmap.organs.plant import fruits_from_organs

        organs = self.skeleton.organs
        at = np.flatnonzero((organs.kind == "Fruit") & (organs.leaf_id == int(leaf)))
        if not len(at):
            raise ValueRefused(f"leaf {leaf} is not a fruit of this plant")
        overrides = {int(leaf): own} if (own := self.session.fruit_overrides().get(int(leaf))) else None

        def build():
            return fruits_from_organs(
                organs.position[at],
                organs.frame[at],
                organs.size[at],
                organs.leaf_id[at],
                preset=preset,
                seed=seed,
                overrides=overrides,
                **kwargs,
            )

        return self._cached(("one fruit", int(leaf), preset, seed, tuple(sorted(kwargs.items()))), build)

    def fruit_surface(self) -> pv.PolyData | None:
        """The volumetric fruit as a surface with a ``leaf_id`` per cell (None without fruit)."""
        from ramure.gmap.kernel.pyvista import boundary_polydata

        if not self.fruit_ids():
            return None
        gm = self.fruit_volumes()
        surface = boundary_polydata(gm)
        surface.cell_data["leaf_id"] = np.asarray(gm.volume_data["leaf_id"])[surface.cell_data["volume"]]
        if gm.meta.get("species"):  # per-tissue materials in the species' colours (app.export)
            surface.field_data["species"] = np.array([gm.meta["species"]])
            surface.field_data["ripeness"] = np.array([gm.meta["ripeness"]])
        return surface

    def _draws_the_same(self, drawn) -> bool:
        """Whether the plant now draws what ``drawn`` drew (False when it cannot be drawn: the
        turtle's error is the front end's to show, when it draws)."""
        try:
            return _same_drawing(drawn, self.skeleton)
        except RamureError:
            return False

    def _after_edit(self, result, keep: bool = False):
        """Record an edit; ``keep``: what grew back stays selected when something was selected
        (so Regrow again, or another qualifier, acts on the same part)."""
        had = self.selection
        drawn_before = bool(keep and had) and bool(self._draw(had).all())  # picks and rectangles draw
        self.last_result = result
        self.selection = []
        self.summary = edit_summary(self.derivation.tree, result)  # the tree the cut was made in
        self.note = None
        self._fold_whole_plant()
        self._changed()
        if keep and had:
            self.selection = self._regrown_selection(drawn_before, result)
        return result

    def _fold_whole_plant(self) -> None:
        """A regrow of the whole plant (nothing selected: a gallery pick, a qualifier, Regrow)
        with constants every rule reads is the plant the grammar derives with that seed and those
        constants: make it so (a new session of that seed and constants), so the constants panel,
        the editor and Save show it.  A combination for one rule stays a local edit."""
        s = self.session
        edit = s.edits[-1] if s.edits else None
        if edit is None or edit["op"] != "regrow" or edit["selection"]:
            return
        extra, per_rule = split_combination(edit["params"])
        if per_rule:
            return
        constants = {**s.constants, **edit["constants"], **extra}
        folded = Session(s.lsystem, n=s.n, seed=edit["seed"], constants=constants, filename=s.filename)
        s.undo()  # the session left keeps the plant before (Undo goes back to it)
        self.session = folded

    def _draw(self, leaves) -> np.ndarray:
        """Whether each of ``leaves`` draws something (a segment or an organ) in the plant shown:
        one lookup table over the leaf ids, no sort of the plant's 100k+ leaves."""
        sk = self.skeleton
        drawn = np.concatenate([sk.leaf_id, sk.organs.leaf_id]).astype(np.int64)
        leaves = np.asarray(leaves, np.int64)
        if not len(leaves) or not len(drawn):
            return np.zeros(len(leaves), bool)
        return np.isin(leaves, drawn, kind="table")

    def _regrown_selection(self, only_drawn: bool, result) -> list[int]:
        """The regrown part as a selection of the same kind as the one regrown: the leaves that
        draw, when only such leaves were selected (picks, rectangles: their cut then gives the
        same roots again, where every new module selected would climb higher), else every new
        leaf (a selection made in the derivation tree)."""
        new = np.asarray(regrown_leaves(self.derivation.tree, result), np.int64)
        if only_drawn:
            try:
                new = new[self._draw(new)]
            except RamureError:  # the new plant cannot be drawn: the front end says why when it draws
                pass
        return new.tolist()

    def undo(self) -> dict | None:
        """Undo the last edit, or go back to the text, n or seed before the last change of them.
        Returns the edit undone (``{"op": "document"}`` for a text, n or seed), None if none;
        :attr:`history_note` says what was undone ("Undid: a2 = 45")."""
        before = self._document_state()
        if self.session.can_undo:
            edit = self.session.undo()
        else:
            edit = {"op": "document"} if self.timeline.back(self, len(self.session.edits)) else None
        return self._history(edit, "Undid", before, before)

    def redo(self) -> dict | None:
        """Redo what Undo took back, in the order it was done (:attr:`history_note` says what)."""
        before = self._document_state()
        stop = self.timeline.stop()
        if self.session.can_redo and (stop is None or len(self.session.edits) < stop):
            edit = self.session.redo()
        else:
            edit = {"op": "document"} if self.timeline.forward(self, len(self.session.edits)) else None
        return self._history(edit, "Redid", before, None)

    def _document_state(self) -> dict:
        s = self.session
        return {"text": self.text, "n": s.n, "seed": s.seed, "constants": dict(s.constants)}

    def _history(self, edit, verb, before, changed):
        """After an undo or redo: nothing selected, the model's text shown (a grammar error typed
        since is gone with the text that had it) and :attr:`history_note` set.  ``changed``:
        the document state the step took away (Undo) or None (Redo: the state it brought)."""
        if edit is None:
            self.history_note = history_words(verb, None)
            return None
        self.selection, self.last_result, self.error = [], None, None
        self.summary = self.note = None
        self._changed(record=False)
        after = self._document_state()
        old, new = (after, before) if changed is not None else (before, after)
        self.history_note = history_words(verb, edit, old, new)
        return edit

    def status(self) -> str:
        """One line for a status bar."""
        r = self.last_result
        base = f"{len(self.derivation)} modules, {len(self.skeleton)} segments"
        if self.selection:
            base += f", {len(self.selection)} selected"
        if r is None:
            return base
        if r.op == "fruit":
            return f"{base} — {len(r.roots)} fruit regrown"
        if r.op == "constants":
            return f"{base} — constants changed, plant re-derived"
        line = f"{base} — {self.summary or edit_summary(self.derivation.tree, r)}"
        return f"{line} — {self.note}" if self.note else line

    # -- files -------------------------------------------------------------
    def save_grammar(self, path: str | os.PathLike, text: str | None = None) -> pathlib.Path:
        """Save the grammar with the current ``n``, seed and constants written in
        (:meth:`document_text`), atomically (temporary file, fsync, rename): a crash or a full
        disk leaves the previous file whole and raises RamureError.  ``text``: write this text
        instead (the editor's, when it holds an error); the document stays unsaved unless it is
        the document's.

        Refused (nothing written) while the plant has local edits (regrown or pruned parts,
        fruit): a grammar cannot hold them; :meth:`save_session` does.
        """
        local = self.local_edits()
        if local:
            raise ValueRefused(local_edits_message(len(local)))
        document = self.document_text()
        if text is None:
            check_round_trip(document, self.session, str(path))
        atomic.write_text(path, document if text is None else text)
        self.path = pathlib.Path(path)
        if text is None or text == document:
            self.mark_saved()
        self._left = (self.checkpoint(), self._left[1])
        return self.path

    def save_session(self, path: str | os.PathLike) -> pathlib.Path:
        """Save the session (grammar, n, seed, constants and every edit) as JSON; the plant is
        then what is on disk."""
        out = self.session.save(path)
        self.mark_saved()
        return out

    def load_session(
        self, path: str | os.PathLike, progress: Callable[[int, int], None] | None = None, run_code: bool = False
    ) -> None:
        """Load a session file (a fresh history, a clean document); on error the current plant is
        untouched.  ``progress(done, total)`` follows the replay of its edits (at most
        :data:`ramure.lsys.regeneration.regen.MAX_SESSION_EDITS`).

        The loaded plant is drawn before it replaces the current one (as the constructor and
        :meth:`set_text` do): a session whose plant cannot be drawn (``F(1e300)``) is refused.
        A session of an L-Py model replays the model's code: only with ``run_code``."""
        if not run_code and session_runs_code(path):
            raise CodeNotAllowed(path)
        session = Session.load(path, progress=progress)
        skeleton = session.derivation.skeleton()  # a turtle error leaves the current plant as it is
        self.session, self.text = session, session.lsystem.text
        self.error = None
        self._fresh(skeleton)

    def export(self, path: str | os.PathLike) -> pathlib.Path:
        """Export the plant mesh by suffix (:mod:`ramure.app.export`): .glb/.gltf (binary or JSON
        glTF with materials), .obj (+ .mtl), .vtp/.vtk (cell data), .ply, .stl."""
        from ramure.app.export import export_mesh

        return export_mesh(self.mesh, path)


def source_path(source: str | os.PathLike) -> pathlib.Path | None:
    """The file an :class:`Explorer` ``source`` names, or None when it is grammar text: a path
    object, a one-line string ending in one of :data:`~ramure.app.document.OPEN_SUFFIXES`, or a
    shipped grammar's name."""
    if isinstance(source, pathlib.Path):
        return grammar_files.resolve(source)
    if isinstance(source, str) and "\n" not in source:
        if source.lower().endswith(OPEN_SUFFIXES) or source in grammar_files.names():
            return grammar_files.resolve(source)
    return None


def local_edits_message(count: int) -> str:
    """What Save grammar says when the plant has ``count`` local edits."""
    return (
        f"the plant has {count} regrown, pruned or fruit edit{'s' if count != 1 else ''} of a selection: "
        "a grammar file cannot hold them (it only grows the whole plant again). "
        "Use File ▸ Save session (.json) to keep them, or undo them to save the grammar"
    )


@dataclass(frozen=True)
class CutPreview:
    """What a regrow of the selection would change (:meth:`Explorer.preview`).

    ``roots``: the cut's roots; ``leaves``: the modules of the string they hold (what will
    change, in string order); ``changed`` of ``total`` modules; ``climb``: the fewest and most
    levels the cut climbs above a selected leaf (None when nothing regrows); ``stranded``:
    selected leaves nothing regrows (see :func:`ramure.lsys.regeneration.mincut.minimum_ascension`);
    ``from_axiom``: a root is an axiom module.
    """

    roots: np.ndarray
    leaves: np.ndarray
    changed: int
    total: int
    climb: tuple[int, int] | None
    stranded: np.ndarray
    from_axiom: bool

    @property
    def share(self) -> float:
        """``changed / total`` (0 for an empty plant)."""
        return self.changed / self.total if self.total else 0.0

    @property
    def message(self) -> str:
        """The sentence both front ends show next to the highlighted part."""
        if not self.changed:
            return f"nothing will change: {stranded_words(len(self.stranded))}"
        line = f"{self.changed:,} of {self.total:,} modules ({percent(self.share)}) will change"
        line += f", {climb_words(self.climb)}"
        if self.from_axiom:
            line += f" — {FROM_AXIOM_MESSAGE}"
        if len(self.stranded):
            count = len(self.stranded)
            line += f"; {_leaves(count)} stay{'s' if count == 1 else ''}: {stranded_words(count)}"
        return line


def percent(share: float) -> str:
    """A share as the user reads it: ``"1.7 %"``, ``"49 %"``, ``"0.02 %"``, never ``"0 %"`` for a change.

    >>> percent(0.017), percent(0.4935), percent(0.0002), percent(0.0), percent(1.0), percent(1e-7)
    ('1.7 %', '49 %', '0.02 %', '0 %', '100 %', '< 0.01 %')
    """
    p = 100.0 * share
    if 0 < p < 0.01:
        return "< 0.01 %"
    return f"{p:.0f} %" if p == 0 or p >= 9.95 else f"{float(f'{p:.2g}'):g} %"


def climb_words(climb: tuple[int, int] | None) -> str:
    """``"the cut climbs 1 level above the selected leaves"`` (or ``"1-3 levels"``).

    >>> climb_words((1, 1)), climb_words((0, 2))
    ('the cut climbs 1 level above the selected leaves', 'the cut climbs 0-2 levels above the selected leaves')
    """
    if climb is None:
        return "nothing regrows"
    lo, hi = climb
    span = f"{lo}" if lo == hi else f"{lo}-{hi}"
    return f"the cut climbs {span} level{'' if span == '1' else 's'} above the selected leaves"


def _leaves(count: int) -> str:
    return f"{count:,} selected lea{'f' if count == 1 else 'ves'}"


def _climb_range(levels: np.ndarray) -> tuple[int, int] | None:
    climbed = levels[levels >= 0]
    return (int(climbed.min()), int(climbed.max())) if climbed.size else None


def regrown_leaves(tree: Any, result: RegenResult | None) -> list[int]:
    """The leaves a regrow put in the string (what stays selected after it), sorted."""
    change = getattr(result, "change", None)
    if change is None or not len(change.added):
        return []
    added = np.asarray(change.added, np.int64)
    # alive and not rewritten: a look at the added nodes only, no table over the whole tree
    return np.sort(added[(tree.child_count[added] == 0) & tree.alive[added]]).tolist()


def edit_summary(tree: Any, result: RegenResult) -> str:
    """What a regrow or prune changed, in the user's words: the share of the plant and how far
    the cut climbed above the selected leaves, e.g. "regrew 12 of 693 modules (1.7 %) as 12;
    the cut climbed 1 level above the selected leaves"."""
    if result.op not in ("regrow", "prune"):
        return f"last edit: {result.op}"
    total = len(tree.leaves) - result.added + result.removed  # the plant before the edit
    done = "regrew" if result.op == "regrow" else "pruned"
    cut = getattr(result, "cut", None)
    if cut is None:
        return f"{done} the whole plant ({result.removed:,} modules replaced by {result.added:,})"
    line = f"{done} {result.removed:,} of {total:,} modules ({percent(result.removed / total if total else 0.0)})"
    if result.op == "regrow":
        line += f" as {result.added:,}"
    selected = cut.selected if cut.selected is not None else np.zeros(0, np.int64)
    levels = climb_levels(tree, selected, result.roots)
    line += "; " + climb_words(_climb_range(levels)).replace("climbs", "climbed")
    if result.from_axiom:
        line += f" — {FROM_AXIOM_MESSAGE}"
    stranded = int(((levels < 0) & (tree.parent[selected] >= 0)).sum())
    if stranded:
        line += f"; {_leaves(stranded)} stayed: {stranded_words(stranded)}"
    return line


def _same_drawing(before: Skeleton, after: Skeleton) -> bool:
    """Whether two skeletons draw the same segments at the same places."""
    return len(before) == len(after) and bool(np.array_equal(before.start, after.start) and np.array_equal(before.end, after.end))


def unchanged_by_constants(explorer: Explorer, result: RegenResult, constants: Mapping[str, float]) -> str:
    """Why a regrow with new constants drew the same plant, precisely (never "press Regrow with
    constants": the user just did).  Nothing regrew; or the part was made in the last step, so
    the new values reach only modules no later step rewrites; or the rules that regrew it do
    not read those constants."""
    names = ", ".join(sorted(constants))
    tree, n = explorer.derivation.tree, explorer.session.n
    if not len(result.roots):
        count = len(result.cut.selected) if result.cut is not None and result.cut.selected is not None else 2
        return f"nothing regrew, so the new {names} changed nothing: {stranded_words(count)}"
    steps_left = int(n - tree.step[result.roots].min())
    if steps_left <= 1:
        return (
            f"this part was made in the last derivation step: the new values of {names} only reach modules that no "
            "later step rewrites, so nothing is left to regrow with new constants. Select a larger part "
            "(or lower ρ) so the cut starts a step earlier, or change the constant for the whole plant"
        )
    from ramure.metrics.variants import rule_constant_names

    used = rule_constant_names(explorer.lsystem)
    added = np.asarray(result.change.added if result.change is not None else [], np.int64)
    rules = [int(r) for r in np.unique(tree.rule[added]) if r >= 0]
    if not any(set(constants) & used[r] for r in rules if r < len(used)):
        grammar = explorer.lsystem.grammar.rules
        which = ", ".join(f"{grammar[r].pred} (line {grammar[r].line})" for r in rules)
        return (
            f"the {steps_left} steps that regrew this part apply the rules for {which}, which read none of "
            f"{names}: nothing is left to regrow with these constants. Select a part grown by a rule that reads them"
        )
    return (
        f"the new {names} did not change how this part is drawn ({steps_left} steps regrown): "
        "they reach only modules that draw nothing"
    )


#: Tube quads the on-screen mesh aims at: above it, tubes get fewer sides (level of detail).
MESH_QUAD_BUDGET = 400_000


def mesh_sides(segments: int) -> int:
    """Sides per tube for a plant of ``segments``: 8 up to 50,000 segments, fewer above, at least 3.

    Software OpenGL draws about a million quads a second: a 131,000-segment
    plant with 3-sided tubes shows in well under a second, with 8 in several.
    """
    return int(np.clip(MESH_QUAD_BUDGET // max(int(segments), 1), 3, 8))


#: The warm-up plant: the first derivation of the user's grammar with at least this many
#: modules (where the turtle and the tree passes run compiled once numba is loaded, as for a
#: large plant).
WARM_UP_NODES = 2_000
#: ... and at most this many: a grammar that jumps past it in one step is not warmed up (the
#: warm-up would cost about what the edit does).
WARM_UP_MAX_NODES = 100_000


def warm_up_edits(text: str, n: int | None = None, seed: int = 0) -> bool:
    """Make the first edit of a plant as fast as the later ones: regrow, undo and redo once on a
    small derivation of the same grammar (``text``), in a throwaway :class:`Explorer`.

    A process's first regrow imports networkx (the minimum cut, about 0.1 s) and loads the
    compiled kernels only edits use (leaf sums, the re-interpreting turtle walk) from numba's
    cache; on Honda n = 17 that made the desktop's first regrow 0.36-0.49 s to the frame against
    about 0.1 s for the next ones (0.13-0.18 s after the warm-up).  A front end calls this in a
    background thread when the user first selects something (a regrow usually follows), so the
    cost falls in the time the user takes to reach the button.  The small plant (the first of
    steps 1 .. ``n`` with :data:`WARM_UP_NODES` modules or more, else step ``n``) has the
    same symbols and parameters, so the kernels specialise for the same array types.  Nothing of
    the user's plant is read or changed.  Returns False, and does nothing more, if the text does
    not give a plant (a warm-up never reports errors: the real edit will), or the small plant
    would have more than :data:`WARM_UP_MAX_NODES` nodes.
    """
    try:
        last = LSystem.from_text(text).n if n is None else int(n)
        load_kernels()  # a small plant is drawn without numba: load it, so the passes below run compiled
        for step in range(1, max(last, 1) + 1):
            ex = Explorer(text, n=step, seed=seed)
            if len(ex.derivation) >= WARM_UP_NODES:
                break
        if len(ex.derivation.tree) > WARM_UP_MAX_NODES:
            return False
        leaves = ex.skeleton.leaf_id
        if not len(leaves):
            return False
        meshes = [ex.mesh]
        tree = ex.derivation.tree  # a leaf and its siblings: a selection that regrows something
        ex.select(
            tree.leaves_under(int(tree.parent[int(leaves[len(leaves) // 2])])) if tree.depth_of([leaves[0]])[0] else leaves[:4]
        )
        for edit in (lambda: ex.regrow(seed=seed + 1), ex.undo, ex.redo):
            edit()
            meshes.append(ex.mesh)  # the re-interpreting turtle and the mesh patch
    except RamureError:
        return False
    return True


_warm_up: list[threading.Thread] = []  # the process's edit warm-up, once started


def warm_up_in_background(text: str, n: int | None) -> threading.Thread:
    """Start :func:`warm_up_edits` for ``text`` in a background thread, once per process (what it
    warms up, networkx and numba's kernels, is the process's, not a plant's); returns that
    thread.  It reads nothing of the caller's plant, so it needs no lock and never makes a
    click wait.  The desktop and the notebook explorer call it at the first selection."""
    if not _warm_up:
        thread = threading.Thread(target=warm_up_edits, args=(text, n), name="ramure-warm-up", daemon=True)
        _warm_up.append(thread)
        thread.start()
    return _warm_up[0]


def leaves_in_rectangle(leaf_ids: ArrayLike, screen_xy: ArrayLike, rect: Sequence[float]) -> list[int]:
    """Unique leaf ids whose screen points fall inside the rectangle (any corner order)."""
    x0, y0, x1, y1 = rect
    xy = np.asarray(screen_xy, float)
    inside = (xy[:, 0] >= min(x0, x1)) & (xy[:, 0] <= max(x0, x1)) & (xy[:, 1] >= min(y0, y1)) & (xy[:, 1] <= max(y0, y1))
    return sorted_unique(np.asarray(leaf_ids)[inside]).tolist()


def project_to_display(matrix: ArrayLike, points: ArrayLike, size: tuple[int, int]) -> np.ndarray:
    """Display coordinates (k, 2) of world ``points`` through a 4x4 composite projection.

    ``matrix`` maps world to clip coordinates (VTK's composite projection
    transform); ``size`` is the viewport (width, height) in pixels.  Display y
    points up (VTK's convention).  Points behind the camera come out as NaN.
    """
    pts = np.asarray(points, float).reshape(-1, 3)
    m = np.asarray(matrix, float)
    x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]

    def row(i):  # one clip coordinate, elementwise (a BLAS matmul stalls its threads on a busy machine)
        return x * m[i, 0] + y * m[i, 1] + z * m[i, 2] + m[i, 3]

    w = row(3)  # z is not needed
    w[w <= 0] = np.nan  # behind the camera
    width, height = size
    out = np.empty((len(pts), 2))
    with np.errstate(divide="ignore", invalid="ignore"):
        out[:, 0] = (row(0) / w + 1.0) * (0.5 * width)
        out[:, 1] = (row(1) / w + 1.0) * (0.5 * height)
    return out


def write_obj(mesh: pv.PolyData, path: str | os.PathLike) -> pathlib.Path:
    """Wavefront OBJ of a plant mesh with normals and a ``.mtl`` beside it (see :mod:`ramure.app.export`)."""
    from ramure.app.export import plant_parts
    from ramure.app.export import write_obj as write

    return write(plant_parts(mesh), path)


def _name(path):
    return str(path) if path else None


def finite_number(value: float | str, name: str) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise ValueRefused(f"{name}: '{value}' is not a number") from None
    if not math.isfinite(value):
        raise ValueRefused(f"{name}: the value must be a finite number")
    return value


__all__ = [
    "CutPreview",
    "Explorer",
    "RamureError",
    "finite_number",
    "leaves_in_rectangle",
    "local_edits_message",
    "project_to_display",
    "warm_up_edits",
    "warm_up_in_background",
    "write_obj",
]
